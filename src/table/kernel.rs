//! The fast lookup of adaptive (warped) `halfdiff` tables: what a renderer calls per shading
//! point on a measured material.
//!
//! The general lookup ([`super::lookup`]) computes the four Rusinkiewicz angles with acos and
//! atan2 and maps each through its axis. On a table whose θh, θd and φd axes are all
//! [`Warp`](super::Warp)s ([`super::adaptive`]), every axis only needs its warp *variable*, and
//! those come from the direction vectors without any transcendental function. With
//! h = ωi + ωo (not normalized) and unit ωi, ωo:
//!
//! - cos θd = ωi·ĥ = (1 + ωi·ωo)/|h| = |h|/2, so v_d = (1 − |h|/2)^½;
//! - sin²θh = (h_x² + h_y²)/|h|², so v_h = (sin θh)^½ needs no |h| first;
//! - the Rusinkiewicz difference vector d = R_y(−θh) R_z(−φh) ωi has, up to the common positive
//!   factor sin θh |h|², d_x ∝ h_z (h_x ωi_x + h_y ωi_y) − (h_x² + h_y²) ωi_z and
//!   d_y ∝ |h| (h_x ωi_y − h_y ωi_x), and the pseudo-angle of φd is a ratio of these.
//!
//! Then per axis one knot interpolation gives the fractional node index, and eight corners
//! (λ innermost: two runs of 2 × channels adjacent values per (θh, θd) pair) are blended in
//! f32. [`Kernel::eval`] is tested against the reference path (angles through
//! [`super::symmetry::canonical_coords`] and [`super::StoredAxis::linear`]) in this module's
//! tests.

use glam::DVec3;

use crate::geometry;
use crate::simd::F4;
use crate::table::grid::{Grid, Mapping, Nodes, Param};
use crate::table::warp::{Warp, WarpVar};

/// One warped axis as the kernel reads it: fractional node index s at the knots.
#[derive(Debug, Clone)]
struct Axis {
    /// s = u·(n − 1) at v = k/K, k = 0..=K.
    s: Box<[f32]>,
    /// K as f32.
    k: f32,
    /// Number of nodes (≥ 2).
    n: usize,
    /// The last knot interval (K − 1).
    kmax: i32,
    /// The last lower node (n − 2).
    imax: i32,
}

impl Axis {
    /// `centers`: node i at u = (i + ½)/n, s = u·n − ½; otherwise at u = i/(n − 1).
    fn new(w: &Warp, n: usize, centers: bool) -> Axis {
        let (scale, shift) = if centers {
            (n as f32, -0.5)
        } else {
            ((n - 1) as f32, 0.0)
        };
        Axis {
            s: w.knots().iter().map(|&u| u * scale + shift).collect(),
            k: (w.knots().len() - 1) as f32,
            n,
            kmax: (w.knots().len() - 2) as i32,
            imax: (n - 2) as i32,
        }
    }

    /// The lower node and the weight of the upper one at variable `v` (clamped to [0, 1]).
    ///
    /// Indices go through i32: a saturating f32 → usize conversion costs about three times as
    /// many instructions, and every value here is in [0, 2^16].
    #[inline(always)]
    fn node(&self, v: f32) -> (usize, f32) {
        // max/min, not clamp: NaN becomes 0 instead of propagating.
        let t = (v * self.k).max(0.0).min(self.k);
        let j = (t as i32).min(self.kmax);
        let (a, b) = (self.s[j as usize], self.s[j as usize + 1]);
        let s = a + (t - j as f32) * (b - a);
        let i = (s as i32).clamp(0, self.imax);
        (i as usize, (s - i as f32).clamp(0.0, 1.0))
    }
}

/// The fast linear lookup of a table on an adaptive grid (see the module docs).
#[derive(Debug, Clone)]
pub struct Kernel {
    axes: [Axis; 3],
    /// φd folded onto [0, π/2] (reciprocity) instead of [0, π].
    quarter: bool,
    channels: usize,
    /// Values per θd row of a chunk (stored φd nodes × channels).
    row: usize,
    /// Values per chunk (θh node).
    chunk: usize,
    /// Lane constants of [`Kernel::eval_rgb`]: K per axis, K − ½ (the last knot interval's
    /// truncation bound), n − 1 and n − 1.5 per axis; lane 3 is unused (0).
    lanes: [F4; 4],
}

impl Kernel {
    /// The kernel of `grid` when it applies: `halfdiff`, isotropic and bilateral, θh, θd and φd
    /// warped with their default variables on edge nodes. `None` otherwise (use the general
    /// lookup).
    pub fn new(grid: &Grid) -> Option<Kernel> {
        let s = grid.symmetry();
        if grid.param() != Param::HalfDiff || !s.isotropic || !s.bilateral {
            return None;
        }
        let ax = grid.stored_axes();
        let want = [
            (0, WarpVar::SqrtSine),
            (2, WarpVar::HalfPower),
            (3, WarpVar::PseudoAngle),
        ];
        let mut axes = Vec::with_capacity(3);
        for (k, var) in want {
            let nodes_ok = match ax[k].nodes {
                Nodes::Edges => true,
                Nodes::Centers => k != 3,
                Nodes::CellStart => false,
            };
            match &ax[k].mapping {
                Mapping::Warp(w) if w.var() == var && nodes_ok => {
                    if ax[k].size < 2 {
                        return None;
                    }
                    let centers = ax[k].nodes == Nodes::Centers;
                    axes.push(Axis::new(w, ax[k].size, centers));
                }
                _ => return None,
            }
        }
        let axes: [Axis; 3] = axes.try_into().ok()?;
        let channels = grid.channels().len();
        let per = |f: &dyn Fn(&Axis) -> f32| F4::new(f(&axes[0]), f(&axes[1]), f(&axes[2]), 0.0);
        let lanes = [
            per(&|a| a.k),
            per(&|a| a.k - 0.5),
            per(&|a| (a.n - 1) as f32),
            per(&|a| a.n as f32 - 1.5),
        ];
        Some(Kernel {
            lanes,
            row: axes[2].n * channels,
            chunk: axes[1].n * axes[2].n * channels,
            axes,
            quarter: s.reciprocal,
            channels,
        })
    }

    /// The warp variables (v_h, v_d, v_φ) of a pair, or `None` below the horizon (the fast
    /// path; [`reference_vars`] is the same in the paper's terms).
    #[inline(always)]
    pub fn vars(&self, wi: DVec3, wo: DVec3) -> Option<[f32; 3]> {
        let (wi, wo) = (geometry::unit(wi)?, geometry::unit(wo)?);
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return None;
        }
        let (ix, iy, iz) = (wi.x as f32, wi.y as f32, wi.z as f32);
        let (ox, oy, oz) = (wo.x as f32, wo.y as f32, wo.z as f32);
        let (hx, hy, hz) = (ix + ox, iy + oy, iz + oz);
        let r2 = hx * hx + hy * hy;
        let hl = (r2 + hz * hz).sqrt();
        // sin²θh = r²/|h|², and 1 − cos θd = 1 − |h|/2 = |ωi − ωo|²/(2(2 + |h|)): no
        // cancellation near θh = 0 or θd = 0.
        let (ex, ey, ez) = (ix - ox, iy - oy, iz - oz);
        let vd = ((ex * ex + ey * ey + ez * ez) / (2.0 * (2.0 + hl))).sqrt();
        let vh = (r2 / (r2 + hz * hz)).sqrt().sqrt();
        let dx = hz * (hx * ix + hy * iy) - r2 * iz;
        let dy = (hl * (hx * iy - hy * ix)).abs();
        let den = dx.abs() + dy;
        let vp = if !(den > 0.0) {
            0.0
        } else if self.quarter {
            dy / den
        } else {
            0.5 - 0.5 * (dx / den)
        };
        Some([vh, vd, vp])
    }

    /// [`Kernel::vars`] on four lanes: the three quotients in one division, the square roots
    /// in one (two for v_h); the same IEEE operations, so the same values (tested).
    #[inline(always)]
    fn vars_lanes(&self, wi: DVec3, wo: DVec3) -> Option<F4> {
        // One branch for the usual unit pair; anything else goes through `geometry::unit`.
        let unit =
            geometry::is_unit_l2(wi.length_squared()) & geometry::is_unit_l2(wo.length_squared());
        let (wi, wo) = if unit { (wi, wo) } else { unit_pair(wi, wo)? };
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return None;
        }
        let (ix, iy, iz) = (wi.x as f32, wi.y as f32, wi.z as f32);
        let (ox, oy, oz) = (wo.x as f32, wo.y as f32, wo.z as f32);
        let (hx, hy, hz) = (ix + ox, iy + oy, iz + oz);
        let r2 = hx * hx + hy * hy;
        let hh = r2 + hz * hz;
        // v_h's chain (a quotient, two roots) starts without waiting for |h|.
        let vh = (r2 / hh).sqrt().sqrt();
        let hl = hh.sqrt();
        let (ex, ey, ez) = (ix - ox, iy - oy, iz - oz);
        let e2 = ex * ex + ey * ey + ez * ez;
        let dx = hz * (hx * ix + hy * iy) - r2 * iz;
        let dy = (hl * (hx * iy - hy * ix)).abs();
        let den = dx.abs() + dy;
        // Lane 1: 1 − cos θd; lane 2: q = dy/den (quarter) or dx/den, the degenerate den = 0
        // giving v_φ = 0.
        let (pn, pd) = match (den > 0.0, self.quarter) {
            (true, true) => (dy, den),
            (true, false) => (dx, den),
            (false, true) => (0.0, 1.0),
            (false, false) => (1.0, 1.0),
        };
        let q = F4::new(1.0, e2, pn, 0.0) / F4::new(1.0, 2.0 * (2.0 + hl), pd, 1.0);
        let [_, q1, q2, _] = q.to_array();
        let p = if self.quarter { q2 } else { 0.5 - 0.5 * q2 };
        let v = F4::new(vh, q1.sqrt(), p, 0.0);
        Some(v)
    }

    /// Evaluates into `out[..channels]` from the table's stored `values` (all chunks, in
    /// order; corners beyond its end — an empty slice when the table could not be loaded —
    /// count as 0).
    #[inline]
    pub fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32], values: &[f32]) {
        if self.channels == 3 {
            match self.vars_lanes(wi, wo) {
                Some(v) => self.eval_rgb(v, out, values),
                None => out[..3].fill(0.0),
            }
            return;
        }
        let Some(v) = self.vars(wi, wo) else {
            out[..self.channels].fill(0.0);
            return;
        };
        match self.channels {
            3 => self.blend::<3>(v, out, values),
            1 => self.blend::<1>(v, out, values),
            _ => self.blend::<0>(v, out, values),
        }
    }

    /// [`Kernel::blend`] for three channels on four-lane registers ([`F4`]): the three axes'
    /// knot and node arithmetic in one register, then each of the four (θh, θd) corner rows
    /// as two four-lane loads (RGB of the two φd corners; the fourth lane is ignored). Computes
    /// the same operations as `blend::<3>`, which stays as its reference (tested equal).
    #[inline(always)]
    fn eval_rgb(&self, v: F4, out: &mut [f32], values: &[f32]) {
        let [k, kcap, nmax, ncap] = self.lanes;
        let zero = F4::splat(0.0);
        // Knot interval j and its fraction per axis (lane 3: 0).
        // v ∈ [0, 1] by construction (each is a ratio bounded by 1), so t ∈ [0, K] up to
        // rounding; the truncation bound K − ½ keeps j ≤ K − 1 (and maps NaN there too).
        let t = v * k;
        let (j, jf) = t.min(kcap).trunc();
        let f = t - jf;
        let knot = |a: usize, d: usize| {
            let s = &self.axes[a].s;
            s.get(j[a] as usize + d).copied().unwrap_or(0.0)
        };
        let lo = F4::new(knot(0, 0), knot(1, 0), knot(2, 0), 0.0);
        let hi = F4::new(knot(0, 1), knot(1, 1), knot(2, 1), 0.0);
        // Fractional node index s, clamped to [0, n − 1] (beyond the first and last cell
        // centres the end values hold), its lower node (≤ n − 2) and the upper one's weight.
        let s = (lo + f * (hi - lo)).max(zero).min(nmax);
        let (i, if_) = s.min(ncap).trunc();
        let w = s - if_;
        let om = F4::splat(1.0) - w;
        // Row weights (1−th)(1−td), (1−th)td, th(1−td), th·td, times each φd corner's weight.
        let rw = F4::pair_lanes::<0>(om, w) * F4::interleave_lo(om.lane::<1>(), w.lane::<1>());
        let (p0, p1) = (rw * om.lane::<2>(), rw * w.lane::<2>());
        let o = i[0] as usize * self.chunk + i[1] as usize * self.row + i[2] as usize * 3;
        let rows = [o, o + self.row, o + self.chunk, o + self.chunk + self.row];
        let mut acc = zero;
        let mut add = |r: usize, w0: F4, w1: F4| {
            // The row's six values r..r+6: lanes 0..3 at r (φd corner 0) and at r + 3 (corner
            // 1), the latter loaded from r + 2 and shifted down so that no read passes r + 6.
            if let Some(x) = values.get(r..r + 6)
                && let (Some(a), Some(b)) = (F4::load(x), F4::load(&x[2..]))
            {
                acc = acc + (w0 * a + w1 * b.shift_down());
            }
        };
        add(rows[0], p0.lane::<0>(), p1.lane::<0>());
        add(rows[1], p0.lane::<1>(), p1.lane::<1>());
        add(rows[2], p0.lane::<2>(), p1.lane::<2>());
        add(rows[3], p0.lane::<3>(), p1.lane::<3>());
        let [r, g, b, _] = acc.to_array();
        out[..3].copy_from_slice(&[r, g, b]);
    }

    /// Trilinear blend of the eight corners; `N` > 0: exactly N channels in registers.
    #[inline(always)]
    fn blend<const N: usize>(&self, v: [f32; 3], out: &mut [f32], values: &[f32]) {
        let c = if N > 0 { N } else { self.channels };
        let (ih, th) = self.axes[0].node(v[0]);
        let (id, td) = self.axes[1].node(v[1]);
        let (ip, tp) = self.axes[2].node(v[2]);
        let o = ih * self.chunk + id * self.row + ip * c;
        // The four (θh, θd) corner rows, each holding the two φd corners side by side.
        let rows = [o, o + self.row, o + self.chunk, o + self.chunk + self.row];
        let w = [
            (1.0 - th) * (1.0 - td),
            (1.0 - th) * td,
            th * (1.0 - td),
            th * td,
        ];
        let (wp0, wp1) = (1.0 - tp, tp);
        let out = &mut out[..c];
        if N > 0 {
            let mut acc = [0f32; N];
            for (r, w) in rows.iter().zip(w) {
                if let Some(x) = values.get(*r..*r + 2 * N) {
                    let (w0, w1) = (w * wp0, w * wp1);
                    for k in 0..N {
                        acc[k] += w0 * x[k] + w1 * x[N + k];
                    }
                }
            }
            out.copy_from_slice(&acc);
        } else {
            out.fill(0.0);
            for (r, w) in rows.iter().zip(w) {
                if let Some(x) = values.get(*r..*r + 2 * c) {
                    let (w0, w1) = (w * wp0, w * wp1);
                    for k in 0..c {
                        out[k] += w0 * x[k] + w1 * x[c + k];
                    }
                }
            }
        }
    }
}

/// Both directions made unit (out of the hot path).
#[cold]
#[inline(never)]
fn unit_pair(wi: DVec3, wo: DVec3) -> Option<(DVec3, DVec3)> {
    Some((geometry::unit(wi)?, geometry::unit(wo)?))
}

/// The warp variables of a pair from its Rusinkiewicz angles (the reference for
/// [`Kernel::vars`]): `None` below the horizon.
pub fn reference_vars(wi: DVec3, wo: DVec3, quarter: bool) -> Option<[f64; 3]> {
    let (wi, wo) = geometry::upper_pair(wi, wo)?;
    let hd = geometry::to_half_diff(wi, wo)?;
    // Bilateral symmetry folds φd onto [0, π]; reciprocity (φd → φd + π) onto [0, π/2].
    let mut p = hd.phi_d.abs();
    let hi = if quarter {
        if p > std::f64::consts::FRAC_PI_2 {
            p = std::f64::consts::PI - p;
        }
        std::f64::consts::FRAC_PI_2
    } else {
        std::f64::consts::PI
    };
    Some([
        WarpVar::SqrtSine.of_angle(hd.theta_h, std::f64::consts::FRAC_PI_2),
        WarpVar::HalfPower.of_angle(hd.theta_d, std::f64::consts::FRAC_PI_2),
        WarpVar::PseudoAngle.of_angle(p, hi),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Brdf;
    use crate::rng::Pcg32;
    use crate::spec::ModelSpec;
    use crate::spectrum::Channels;
    use crate::table::adaptive::{AdaptiveOptions, adaptive_grid};
    use crate::table::symmetry::Symmetry;
    use crate::table::{BakeOptions, TabulatedBrdf, bake, lookup::Interp, lookup::Lookup};

    fn random_pair(r: &mut Pcg32) -> (DVec3, DVec3) {
        let d = |r: &mut Pcg32| {
            let (u, v) = (r.next_f64(), r.next_f64());
            let z = u.max(1e-9);
            let s = (1.0 - z * z).sqrt();
            let p = std::f64::consts::TAU * v;
            DVec3::new(s * p.cos(), s * p.sin(), z)
        };
        (d(r), d(r))
    }

    fn test_kernel(quarter: bool) -> Kernel {
        let axes =
            std::array::from_fn(|_| Axis::new(&Warp::identity(WarpVar::HalfPower), 2, false));
        let per = |x: f32| F4::new(x, x, x, 0.0);
        Kernel {
            axes,
            quarter,
            channels: 1,
            row: 2,
            chunk: 4,
            lanes: [per(1.0), per(0.5), per(1.0), per(0.5)],
        }
    }

    #[test]
    fn fast_variables_match_the_angles() {
        for quarter in [false, true] {
            let mut r = Pcg32::new(71);
            let k = test_kernel(quarter);
            for _ in 0..100_000 {
                let (wi, wo) = random_pair(&mut r);
                let f = k.vars(wi, wo).unwrap();
                let g = reference_vars(wi, wo, quarter).unwrap();
                // The lane version does the same IEEE operations.
                let l = k.vars_lanes(wi, wo).unwrap().to_array();
                assert_eq!(&l[..3], &f[..], "{wi} {wo}");
                // f32 arithmetic without cancellation: a few ulps of v ≤ 1. φd itself is
                // only as good as h = ωi + ωo in f32 relative to sin θh (it is undefined at
                // θh = 0, where an isotropic BRDF does not depend on it).
                let sin_h = (g[0] * g[0]).max(1e-12);
                assert!((f[0] as f64 - g[0]).abs() < 1e-5, "{wi} {wo}: {f:?} {g:?}");
                assert!((f[1] as f64 - g[1]).abs() < 1e-5, "{wi} {wo}: {f:?} {g:?}");
                assert!(
                    (f[2] as f64 - g[2]).abs() < 1e-5 + 1e-6 / sin_h,
                    "{wi} {wo}: {f:?} {g:?}"
                );
            }
        }
    }

    #[test]
    fn kernel_agrees_with_the_general_lookup() {
        let src = ModelSpec::parse(r#"{"model": "ggx", "alpha": 0.05}"#)
            .unwrap()
            .build(&Channels::Rgb)
            .unwrap();
        for reciprocal in [false, true] {
            let sym = Symmetry {
                isotropic: true,
                reciprocal,
                bilateral: true,
            };
            let opts = AdaptiveOptions {
                nodes: [24, 16, 9],
                fine: [64, 32, 16],
                ..Default::default()
            };
            let grid = adaptive_grid(src.as_ref(), sym, &opts).unwrap();
            let (t, _) = bake(src.as_ref(), &grid, &BakeOptions::default()).unwrap();
            let k = Kernel::new(t.grid()).expect("an adaptive grid has a kernel");
            let general = Lookup::new(t.grid());
            let tb = TabulatedBrdf::from_table(t.clone());
            let mut r = Pcg32::new(32);
            let (mut a, mut b, mut c, mut d) = ([0f32; 3], [0f32; 3], [0f32; 3], [0f32; 3]);
            let peak = t.values().iter().fold(0f32, |m, &x| m.max(x));
            let mut worst = 0f32;
            for _ in 0..50_000 {
                let (wi, wo) = random_pair(&mut r);
                k.eval(wi, wo, &mut a, t.values());
                general.eval(Interp::Linear, wi, wo, &mut b, |i| t.chunk(i));
                tb.eval(wi, wo, &mut c);
                // The four-lane RGB path against its scalar reference, `blend::<3>`.
                if let Some(v) = k.vars(wi, wo) {
                    k.blend::<3>(v, &mut d, t.values());
                    for ch in 0..3 {
                        assert!((a[ch] - d[ch]).abs() <= 1e-6 * d[ch].abs(), "{a:?} {d:?}");
                    }
                }
                for ch in 0..3 {
                    // Both interpolate the same nodes; they differ by the f32 variables (a
                    // few 1e-7) times the slope in node units, below 1e-3 of the value plus
                    // 1e-4 of the table's peak.
                    let e = (a[ch] - b[ch]).abs() / (b[ch].abs() * 1e-3 + peak * 1e-4);
                    worst = worst.max(e);
                    assert_eq!(a[ch], c[ch], "TabulatedBrdf uses the kernel");
                }
            }
            assert!(worst <= 1.0, "worst scaled difference {worst}");
        }
    }
}
