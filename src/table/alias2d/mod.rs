//! Constant-time sampling of the table sampler's conditional densities: the same
//! piecewise-bilinear densities as [`super::warp2d::Warp`], drawn with alias tables and a
//! stochastic choice of slice instead of binary searches over interpolated CDFs.
//!
//! Why: [`super::sampling::TableSampler`] draws a direction for every BSDF sample a renderer
//! takes. Through `Warp::sample` a draw ran two binary searches over CDFs interpolated between
//! two (four) conditioning slices — about two dozen dependent loads from a megabyte structure —
//! and cost half of a sample of a measured table, several times its lookup. Here a draw is a
//! fixed number of loads.
//!
//! # The draw
//!
//! A density interpolated over the conditioning parameters with weights w_k between slices p_k
//! that are each normalized is the mixture Σ w_k p_k. So a draw first picks slice k with
//! probability w_k and then draws from p_k alone; its density is still the mixture, which is
//! what [`AliasWarp::eval`] gives (the same function as `Warp::eval` on the same nodes).
//!
//! Within a slice, on the strip between node rows j and j + 1 (t ∈ [0, 1] across it) the
//! bilinear density is p(x, t) = (1 − t) r_j(x) + t r_{j+1}(x), with r_j the row's
//! piecewise-linear interpolant and T_j its integral. That is a mixture of two products:
//! T_j/2 · [2(1 − t)] · [r_j(x)/T_j] and T_{j+1}/2 · \[2t\] · [r_{j+1}(x)/T_{j+1}]. So:
//! 1. one alias table per slice over the 2(ny − 1) *half-strips* (masses T_j/2, T_{j+1}/2)
//!    gives the strip j and the row r (j or j + 1);
//! 2. t from 2(1 − t) (t = 1 − √(1 − v)) or from 2t (t = √v);
//! 3. x from row r alone: one alias table per row over its nx − 1 cells (masses
//!    (r\[c\] + r\[c + 1\])/2) gives the cell c; the row's linear piece there,
//!    (1 − f) r\[c\] + f r\[c + 1\], is again a mixture of 2(1 − f) and 2f with masses r\[c\]/2 and
//!    r\[c + 1\]/2: a coin between them, then f = 1 − √(1 − v) or √v.
//!
//! Steps 2 and 3 do not depend on each other, so the chain of a draw is the slice choice, three
//! loads and a square root; no quadratic, no search. (Alias tables over half-cells would save
//! the coin's load and division but hold twice the entries: 1.5 × the bytes of the CDFs they
//! replace, where cells hold the same.) The first uniform number draws the cell, the coin and
//! f, the second the slice, the half-strip and t (each step rescales its remainder to
//! [0, 1)). The alias tables store their probabilities in fixed point ([`Packing`]), so the
//! drawn distribution matches the density to the rounding of the masses.

use super::warp2d::{Corners, Planes, Warp};

/// Alias tables (Walker; Vose's construction) packed in one u32 per slot: draw slot i
/// uniformly, keep it with probability `keep`, else take `other`. The top `bits` of an entry
/// hold `other`, the rest `keep` in fixed point (2^−(32 − bits) steps: 2^−25 of a slot's mass
/// with the default sampler's 126 half-strips per slice, finer than the f32 CDFs of [`Warp`]). A slot that
/// keeps everything names itself as `other` with `keep` 0 (the same draw, and 1 needs no
/// representation).
#[derive(Debug, Clone, Copy)]
struct Packing {
    /// Bits of `other`.
    bits: u32,
}

impl Packing {
    /// The packing for tables of at most `n` slots.
    fn for_slots(n: usize) -> Packing {
        let bits = (usize::BITS - n.saturating_sub(1).leading_zeros()).clamp(1, 24);
        Packing { bits }
    }

    #[inline(always)]
    fn keep_bits(self) -> u32 {
        32 - self.bits
    }

    fn pack(self, keep: f64, other: usize) -> u32 {
        let scale = (1u64 << self.keep_bits()) as f64;
        let k = ((keep * scale).round() as u64).min((1u64 << self.keep_bits()) - 1) as u32;
        ((other as u32) << self.keep_bits()) | k
    }

    /// (keep, other) of an entry.
    #[inline(always)]
    fn unpack(self, e: u32) -> (f64, usize) {
        let kb = self.keep_bits();
        let keep = (e & ((1u32 << kb) - 1)) as f64 * f64::from_bits(((1023 - kb) as u64) << 52);
        (keep, (e >> kb) as usize)
    }

    /// Fills `out` with the alias table of `masses` (non-negative; all zero gives the uniform
    /// distribution).
    fn build(self, masses: &[f64], out: &mut [u32]) {
        let n = masses.len();
        let total: f64 = masses.iter().sum();
        let mut q: Vec<f64> = if total > 0.0 && total.is_finite() {
            masses.iter().map(|&m| m * n as f64 / total).collect()
        } else {
            vec![1.0; n]
        };
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| q[i] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            out[s] = self.pack(q[s], l);
            // The large slot gives away what fills the small one's.
            q[l] -= 1.0 - q[s];
            if q[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What is left is 1 up to rounding: kept whole.
        for i in small.into_iter().chain(large) {
            out[i] = self.pack(0.0, i);
        }
    }

    /// Draws a slot of `table` with `u` ∈ [0, 1); returns it and the remainder of `u`, again
    /// uniform on [0, 1).
    #[inline(always)]
    fn pick(self, table: &[u32], u: f64) -> (usize, f64) {
        let n = table.len();
        let x = u * n as f64;
        let i = (x as usize).min(n - 1);
        let f = x - i as f64;
        let (keep, other) = self.unpack(table[i]);
        // Arithmetic rather than branches (which the compiler may emit for selects): the
        // outcome is a coin flip, which a branch would mispredict half the time.
        let kept = (f < keep) as u8 as f64;
        let slot = if kept > 0.0 { i } else { other };
        let num = f - keep * (1.0 - kept);
        let den = keep * kept + (1.0 - keep) * (1.0 - kept);
        (slot, (num / den).min(1.0))
    }
}

/// Chooses one of the corners with probability its weight, from `u` ∈ [0, 1); returns the
/// slice and the remainder of `u` (uniform on [0, 1)). Selects, not branches (the choice is
/// random).
#[inline(always)]
fn pick_slice(k: &Corners, u: f64) -> (usize, f64) {
    let (mut m, mut lo, mut acc) = (0, 0.0, k.w[0]);
    for n in 1..4 {
        // Past corner n − 1's share, onto corner n (if it weighs anything).
        let next = (u >= acc) & (k.w[n] > 0.0);
        m = if next { n } else { m };
        lo += (acc - lo) * (next as u8 as f64);
        acc += k.w[n];
    }
    (k.slice[m], ((u - lo) / k.w[m]).clamp(0.0, 1.0))
}

/// Piecewise-bilinear densities per slice with alias tables over strips and cells (see the
/// module docs).
#[derive(Debug, Clone)]
pub(crate) struct AliasWarp {
    /// The normalized node densities (the same as [`Warp`]'s: each slice integrates to 1 over
    /// its patches, every patch of unit area).
    pub(crate) pdf: Planes,
    /// Per slice, the alias table over the 2(`ny` − 1) half-strips.
    strips: Vec<u32>,
    /// Per slice and row, the alias table over the row's `nx` − 1 cells.
    cells: Vec<u32>,
    /// How `strips` and `cells` are packed.
    packing: Packing,
}

impl AliasWarp {
    /// Normalizes each slice of `planes` as [`Warp::build`] does and builds its alias tables; a
    /// slice that does not integrate to a positive finite value is `Err((slice, integral))`.
    pub(crate) fn build(planes: Planes) -> std::result::Result<Self, (usize, f32)> {
        let pdf = Warp::build(planes)?.pdf;
        let (nx, ny) = (pdf.nx, pdf.ny);
        let slices = pdf.data.len() / pdf.plane_len();
        let hy = 2 * (ny - 1);
        let packing = Packing::for_slots((nx - 1).max(hy));
        let mut strips = vec![0u32; slices * hy];
        let mut cells = vec![0u32; slices * ny * (nx - 1)];
        let mut masses = vec![0.0f64; nx.max(hy)];
        let mut rows = vec![0.0f64; ny];
        for s in 0..slices {
            let plane = &pdf.data[s * nx * ny..(s + 1) * nx * ny];
            for (j, row) in plane.chunks_exact(nx).enumerate() {
                let m = &mut masses[..nx - 1];
                for (c, m) in m.iter_mut().enumerate() {
                    *m = 0.5 * (row[c] as f64 + row[c + 1] as f64);
                }
                rows[j] = m.iter().sum();
                packing.build(m, &mut cells[(s * ny + j) * (nx - 1)..][..nx - 1]);
            }
            // Half-strips: strip j's (1 − t) r_j and t r_{j+1}, masses T_j/2, T_{j+1}/2.
            let m = &mut masses[..hy];
            for (h, m) in m.iter_mut().enumerate() {
                *m = 0.5 * rows[h / 2 + h % 2];
            }
            packing.build(m, &mut strips[s * hy..][..hy]);
        }
        Ok(AliasWarp {
            pdf,
            strips,
            cells,
            packing,
        })
    }

    /// What a host needs to run this draw itself: the bits of `other` in an entry, the
    /// normalized node densities, the half-strip tables (per slice) and the cell tables (per
    /// slice and row).
    pub(crate) fn parts(&self) -> (u32, &[f32], &[u32], &[u32]) {
        (self.packing.bits, &self.pdf.data, &self.strips, &self.cells)
    }

    /// Bytes held (densities and alias tables).
    pub(crate) fn memory_bytes(&self) -> usize {
        4 * (self.pdf.data.len() + self.strips.len() + self.cells.len())
    }

    /// Density scale: the data are normalized to integrate to 1 over the patches.
    #[inline]
    fn inv_patch_area(&self) -> f64 {
        ((self.pdf.nx - 1) * (self.pdf.ny - 1)) as f64
    }

    /// The density at `u` of the slices mixed by `k` (bilinear, per unit area).
    #[inline]
    pub(crate) fn eval(&self, u: [f64; 2], k: &Corners) -> f64 {
        let (c, f) = Planes::locate(u[0], self.pdf.nx);
        let (j, t) = Planes::locate(u[1], self.pdf.ny);
        self.mix(k, c, f, j, t)
    }

    /// Σ w_k × slice k's bilinear density in cell (`c`, `j`) at fractions (`f`, `t`), per
    /// unit area.
    #[inline(always)]
    fn mix(&self, k: &Corners, c: usize, f: f64, j: usize, t: f64) -> f64 {
        let nx = self.pdf.nx;
        let plane = self.pdf.plane_len();
        let o = j * nx + c;
        let d = &self.pdf.data;
        let mut p = 0.0;
        for m in 0..4 {
            let w = k.w[m];
            if w != 0.0 {
                let q = &d[k.slice[m] * plane + o..][..nx + 2];
                p += w
                    * ((1.0 - t) * ((1.0 - f) * q[0] as f64 + f * q[1] as f64)
                        + t * ((1.0 - f) * q[nx] as f64 + f * q[nx + 1] as f64));
            }
        }
        p * self.inv_patch_area()
    }

    /// Maps `u` ∈ [0, 1)² to a point of the unit square drawn from the slices mixed by `k`;
    /// returns the point and its density ([`AliasWarp::eval`] there).
    pub(crate) fn sample(&self, u: [f64; 2], k: &Corners) -> ([f64; 2], f64) {
        let (nx, ny) = (self.pdf.nx, self.pdf.ny);
        let hy = 2 * (ny - 1);
        let plane = nx * ny;
        let (s, v) = pick_slice(k, u[1].clamp(0.0, 1.0));
        // Steps 1–2: the half-strip, so the strip j, the row r and t across the strip.
        let (h, v) = self.packing.pick(&self.strips[s * hy..][..hy], v);
        let (j, upper) = (h / 2, h % 2);
        let t = rise_or_fall(upper, v);
        // Step 3: the cell c of row r, the coin between its two halves and f across it.
        let r = j + upper;
        let (c, x) = self.packing.pick(
            &self.cells[(s * ny + r) * (nx - 1)..][..nx - 1],
            u[0].clamp(0.0, 1.0),
        );
        let ends = &self.pdf.data[s * plane + r * nx + c..][..2];
        let (a, b) = (ends[0] as f64, ends[1] as f64);
        let x = x * (a + b);
        let right = ((x >= a) & (b > 0.0)) as u8 as f64;
        let (num, den) = (x - a * right, a + (b - a) * right);
        // In [0, 1] up to rounding; NaN (0/0, an empty row) becomes 0.
        let v = num / den;
        let f = rise_or_fall(right as usize, if v >= 0.0 { v.min(1.0) } else { 0.0 });
        (
            [
                (c as f64 + f) / (nx - 1) as f64,
                (j as f64 + t) / (ny - 1) as f64,
            ],
            // The mixture's density at the point: every weighted slice, bilinear in the cell.
            self.mix(k, c, f, j, t),
        )
    }
}

/// A draw from the density 2t (`rising` = 1: t = √v) or 2(1 − t) (t = 1 − √(1 − v)) on
/// [0, 1], for v ∈ [0, 1].
#[inline(always)]
fn rise_or_fall(rising: usize, v: f64) -> f64 {
    let rising = rising as f64;
    // The same square root either way: of v or of 1 − v.
    let q = (rising * v + (1.0 - rising) * (1.0 - v)).max(0.0).sqrt();
    (rising * q + (1.0 - rising) * (1.0 - q)).min(1.0)
}

#[cfg(test)]
mod tests;
