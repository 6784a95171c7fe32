//! A conditional 2D warp: a piecewise-bilinear density on [0, 1]² per *slice*, its CDFs, and
//! sampling and inversion with every quantity interpolated linearly over the conditioning
//! parameters (up to four slices with weights, [`Corners`]).
//!
//! This is the `Marginal2D` of Dupuy & Jakob's RGL-EPFL format (rgl-epfl/brdf-loader,
//! `powitacq_rgb.inl`): the density is given at (nx × ny) nodes of a regular grid and is
//! bilinear between them; each slice is normalized to integrate to 1; the conditional CDF of a
//! row and the marginal CDF over rows are exact integrals of the bilinear patches, so sampling
//! inverts them with one quadratic per axis. Because the CDFs are linear in the data, a slice
//! interpolated over the conditioning parameters is again a normalized distribution whose CDFs
//! are the interpolated CDFs: sampling, inversion and density stay exactly consistent between
//! slices.
//!
//! The RGL reader ([`crate::measured::rgl`]) uses it for the files' VNDF and luminance warps,
//! the RGL writer to build them, and the table sampler ([`super::sampling`]) for its conditional
//! distributions of f_r cos θi.

/// A bilinearly interpolated grid of `slices` planes of `ny` rows × `nx` columns on [0, 1]².
#[derive(Debug, Clone)]
pub(crate) struct Planes {
    pub(crate) nx: usize,
    pub(crate) ny: usize,
    pub(crate) data: Vec<f32>,
}

impl Planes {
    #[inline]
    pub(crate) fn plane_len(&self) -> usize {
        self.nx * self.ny
    }

    /// Cell index and fractional position along an axis of `n` samples for unit coordinate `u`.
    #[inline]
    pub(crate) fn locate(u: f64, n: usize) -> (usize, f64) {
        let p = u * (n - 1) as f64;
        let i = if p > 0.0 { (p as usize).min(n - 2) } else { 0 };
        (i, p - i as f64)
    }
}

/// Interpolation corners over the conditioning parameters (φi, θi): up to four slices.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Corners {
    pub(crate) slice: [usize; 4],
    pub(crate) w: [f64; 4],
}

impl Corners {
    /// Exactly slice `slice` (no interpolation over the conditioning parameters).
    pub(crate) fn single(slice: usize) -> Self {
        Corners {
            slice: [slice; 4],
            w: [1.0, 0.0, 0.0, 0.0],
        }
    }

    /// Σ w_k · data[slice_k · stride + offset].
    #[inline]
    pub(crate) fn lookup(&self, data: &[f32], stride: usize, offset: usize) -> f64 {
        let mut s = 0.0;
        for k in 0..4 {
            if self.w[k] != 0.0 {
                s += self.w[k] * data[self.slice[k] * stride + offset] as f64;
            }
        }
        s
    }
}

/// The VNDF warp: a normalized piecewise-bilinear density per slice with its conditional (per
/// row) and marginal (over rows) CDFs.
#[derive(Debug, Clone)]
pub(crate) struct Warp {
    pub(crate) pdf: Planes,
    conditional: Vec<f32>,
    marginal: Vec<f32>,
}

impl Warp {
    /// Builds the CDFs of every slice (sums in f64, stored as f32 as the reference does), and
    /// normalizes each slice to integrate to 1 over the unit square. A slice that does not integrate to a positive finite value
    /// is returned as `Err((slice, integral))`. (The RGL writer builds its warps with this, so
    /// that it places samples exactly where the reader looks for them.)
    pub(crate) fn build(planes: Planes) -> std::result::Result<Self, (usize, f32)> {
        let (nx, ny) = (planes.nx, planes.ny);
        let n = planes.plane_len();
        let slices = planes.data.len() / n;
        let mut data = planes.data;
        let mut conditional = vec![0.0f32; data.len()];
        let mut marginal = vec![0.0f32; slices * ny];
        for s in 0..slices {
            let d = &mut data[s * n..(s + 1) * n];
            let c = &mut conditional[s * n..(s + 1) * n];
            let m = &mut marginal[s * ny..(s + 1) * ny];
            for y in 0..ny {
                let row = y * nx;
                let mut sum = 0.0f64;
                c[row] = 0.0;
                for x in 0..nx - 1 {
                    sum += 0.5 * (d[row + x] as f64 + d[row + x + 1] as f64);
                    c[row + x + 1] = sum as f32;
                }
            }
            let mut sum = 0.0f64;
            m[0] = 0.0;
            for y in 0..ny - 1 {
                sum += 0.5 * (c[(y + 1) * nx - 1] as f64 + c[(y + 2) * nx - 1] as f64);
                m[y + 1] = sum as f32;
            }
            let total = m[ny - 1];
            if !(total > 0.0 && total.is_finite()) {
                return Err((s, total));
            }
            let norm = 1.0 / total;
            c.iter_mut().for_each(|v| *v *= norm);
            m.iter_mut().for_each(|v| *v *= norm);
            d.iter_mut().for_each(|v| *v *= norm);
        }
        Ok(Warp {
            pdf: Planes { nx, ny, data },
            conditional,
            marginal,
        })
    }

    /// The point of the unit square that the warp maps onto `u` (the inverse of sampling).
    #[inline]
    pub(crate) fn invert(&self, u: [f64; 2], k: &Corners) -> [f64; 2] {
        self.invert_pdf(u, k).0
    }

    /// Density scale: the data are normalized to integrate to 1 over the patches.
    #[inline]
    pub(crate) fn inv_patch_area(&self) -> f64 {
        ((self.pdf.nx - 1) * (self.pdf.ny - 1)) as f64
    }

    /// The density of the warp's output at `u` (bilinear, per unit area).
    #[inline]
    pub(crate) fn eval(&self, u: [f64; 2], k: &Corners) -> f64 {
        bilinear(&self.pdf, k, self.pdf.plane_len(), 0, u) * self.inv_patch_area()
    }

    /// Maps a uniform point of the unit square through the warp: the marginal CDF picks the row,
    /// the conditional CDF the column, each inverted exactly for the bilinear patch (a quadratic).
    /// Returns the warped point and its density.
    pub(crate) fn sample(&self, mut u: [f64; 2], k: &Corners) -> ([f64; 2], f64) {
        const ONE_MINUS_EPS: f64 = 0.999_999_940_395_355_2;
        let (nx, ny) = (self.pdf.nx, self.pdf.ny);
        let stride = nx * ny;
        for v in &mut u {
            *v = v.clamp(1.0 - ONE_MINUS_EPS, ONE_MINUS_EPS);
        }
        let cd = &self.conditional;
        let marginal = |i: usize| k.lookup(&self.marginal, ny, i);
        let row = find_interval(ny, |i| marginal(i) < u[1]);
        u[1] -= marginal(row);
        let off = row * nx;
        let r0 = k.lookup(cd, stride, off + nx - 1);
        let r1 = k.lookup(cd, stride, off + 2 * nx - 1);
        u[1] = solve_linear_cdf(r0, r1, u[1]);
        u[0] *= (1.0 - u[1]) * r0 + u[1] * r1;
        let cond = |i: usize| {
            (1.0 - u[1]) * k.lookup(cd, stride, off + i) + u[1] * k.lookup(cd, stride, off + nx + i)
        };
        let col = find_interval(nx, |i| cond(i) < u[0]);
        u[0] -= cond(col);
        let o = off + col;
        let d = &self.pdf.data;
        let v00 = k.lookup(d, stride, o);
        let v10 = k.lookup(d, stride, o + 1);
        let v01 = k.lookup(d, stride, o + nx);
        let v11 = k.lookup(d, stride, o + nx + 1);
        let c0 = (1.0 - u[1]) * v00 + u[1] * v01;
        let c1 = (1.0 - u[1]) * v10 + u[1] * v11;
        u[0] = solve_linear_cdf(c0, c1, u[0]);
        let pdf = ((1.0 - u[0]) * c0 + u[0] * c1) * self.inv_patch_area();
        (
            [
                (col as f64 + u[0]) / (nx - 1) as f64,
                (row as f64 + u[1]) / (ny - 1) as f64,
            ],
            pdf,
        )
    }

    /// [`Warp::invert`] and the density there.
    #[inline]
    pub(crate) fn invert_pdf(&self, u: [f64; 2], k: &Corners) -> ([f64; 2], f64) {
        let (nx, ny) = (self.pdf.nx, self.pdf.ny);
        let stride = nx * ny;
        let (ix, fx) = Planes::locate(u[0], nx);
        let (iy, fy) = Planes::locate(u[1], ny);
        let off = ix + iy * nx;
        let d = &self.pdf.data;
        let v00 = k.lookup(d, stride, off);
        let v10 = k.lookup(d, stride, off + 1);
        let v01 = k.lookup(d, stride, off + nx);
        let v11 = k.lookup(d, stride, off + nx + 1);
        let c0 = (1.0 - fy) * v00 + fy * v01;
        let c1 = (1.0 - fy) * v10 + fy * v11;
        // Column: integral of the bilinear patch up to fx, plus the CDF at the cell start.
        let mut sx = fx * (c0 + 0.5 * fx * (c1 - c0));
        let cd = &self.conditional;
        let v0 = k.lookup(cd, stride, off);
        let v1 = k.lookup(cd, stride, off + nx);
        sx += (1.0 - fy) * v0 + fy * v1;
        let row = iy * nx;
        let r0 = k.lookup(cd, stride, row + nx - 1);
        let r1 = k.lookup(cd, stride, row + 2 * nx - 1);
        let row_total = (1.0 - fy) * r0 + fy * r1;
        sx = if row_total > 0.0 { sx / row_total } else { 0.0 };
        // Row: integral of the row totals up to fy, plus the marginal CDF at the row start.
        let mut sy = fy * (r0 + 0.5 * fy * (r1 - r0));
        sy += k.lookup(&self.marginal, ny, iy);
        let pdf = ((1.0 - fx) * c0 + fx * c1) * self.inv_patch_area();
        ([sx, sy], pdf)
    }
}

/// Largest i in [0, n−2] with `pred(i)` true (0 if none), for a predicate that is true on a
/// prefix (binary search, as the reference's `find_interval`).
#[inline]
pub(crate) fn find_interval(n: usize, pred: impl Fn(usize) -> bool) -> usize {
    let (mut lo, mut hi) = (1usize, n.saturating_sub(1)); // search (0, n−1)
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if pred(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo.saturating_sub(1).min(n.saturating_sub(2))
}

/// t ∈ [0, 1] with ∫₀ᵗ (a (1 − s) + b s) ds = y, i.e. a t + (b − a) t²/2 = y.
#[inline]
pub(crate) fn solve_linear_cdf(a: f64, b: f64, y: f64) -> f64 {
    let t = if (a - b).abs() < 1e-4 * (a + b) {
        2.0 * y / (a + b)
    } else {
        (a - (a * a - 2.0 * y * (a - b)).max(0.0).sqrt()) / (a - b)
    };
    if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Bilinear interpolation of plane `plane` (within slice stride `stride`) at unit point `u`.
#[inline]
pub(crate) fn bilinear(
    p: &Planes,
    k: &Corners,
    stride: usize,
    plane_off: usize,
    u: [f64; 2],
) -> f64 {
    let (ix, fx) = Planes::locate(u[0], p.nx);
    let (iy, fy) = Planes::locate(u[1], p.ny);
    let o = plane_off + ix + iy * p.nx;
    let v00 = k.lookup(&p.data, stride, o);
    let v10 = k.lookup(&p.data, stride, o + 1);
    let v01 = k.lookup(&p.data, stride, o + p.nx);
    let v11 = k.lookup(&p.data, stride, o + p.nx + 1);
    (1.0 - fy) * ((1.0 - fx) * v00 + fx * v10) + fy * ((1.0 - fx) * v01 + fx * v11)
}

pub(crate) const NO_PARAMS: Corners = Corners {
    slice: [0; 4],
    w: [1.0, 0.0, 0.0, 0.0],
};
