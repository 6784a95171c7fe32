//! The fast lookup of isotropic `halfdiff` tables — adaptive (warped) ones and the presets' and
//! MERL-style fixed mappings: what a renderer calls per shading point on a measured material or
//! a baked analytic model.
//!
//! The general lookup ([`super::lookup`]) computes the four Rusinkiewicz angles with acos and
//! atan2 and maps each through its axis. On a table whose θh, θd and φd axes are all
//! [`Warp`]s ([`super::adaptive`]), every axis only needs its warp *variable*, and
//! those come from the direction vectors without any transcendental function. With
//! h = ωi + ωo (not normalized) and unit ωi, ωo:
//!
//! - cos θd = ωi·ĥ = (1 + ωi·ωo)/|h| = |h|/2, so v_d = (1 − |h|/2)^½;
//! - sin²θh = (h_x² + h_y²)/|h|², so v_h = (sin θh)^½ needs no |h| first;
//! - the Rusinkiewicz difference vector d = R_y(−θh) R_z(−φh) ωi has, up to the common positive
//!   factor sin θh |h|², d_x ∝ h_z (h_x ωi_x + h_y ωi_y) − (h_x² + h_y²) ωi_z and
//!   d_y ∝ |h| (h_x ωi_y − h_y ωi_x), and the pseudo-angle of φd is a ratio of these.
//!
//! Then per axis one line on the variable's knot interval (one eight-byte load) gives the
//! fractional node index, and eight corners (λ innermost: two runs of 2 × channels adjacent
//! values per (θh, θd) pair) are blended in f32 from the table's f16 codes ([`Packed`]: half
//! the bytes, so a measured material's table stays in L2; expanded with F16C when the CPU has
//! it, chosen once per kernel).
//!
//! Grids on fixed mappings — the presets' (sqrt θh, cos θd, uniform φd) and MERL-style ones
//! (uniform θd: `--grid 90x1x90x180 --param halfdiff`) — take the same path: their mappings
//! are *resampled* as knot lines in the same variables ([`RESAMPLED_KNOTS`] per axis, within
//! [`RESAMPLE_TOLERANCE`] node units of the exact mapping), θh in (1 − cos θh)^¼
//! ([`WarpVar::QuarterPower`]), in which sqrt θh is smooth up to 90° (in √sin θh it has a
//! square-root singularity there), θd and φd in their usual variables. An axis whose knot lines
//! strayed from the mapping beyond some interval would get a *cut* there, pairs beyond it going
//! to the general lookup ([`Kernel::eval`] returns false); none of these mappings has one.
//! Such a table keeps exact f32 values ([`Packed::exact`]): it is what a user baked an
//! analytic model on (a Lambert table gives kd to f32 rounding), and the stored f32 values
//! stay what [`super::TabulatedBrdf::to_table`] and nearest lookups read. (The MERL-size grid
//! used to read f16 codes beyond 1 MiB of values: a median 1.17× faster, L3-bound, at a
//! rounding of up to 2^-11 of a value — given up when the presets, analytic tables, came to
//! this path; BENCHMARKS.md.)
//!
//! [`Kernel::eval`] is tested against the reference path (angles through
//! [`super::symmetry::canonical_coords`] and [`super::StoredAxis::linear`]) in this module's
//! tests.
//!
//! [`Warp`]: super::warp::Warp
//! [`WarpVar::QuarterPower`]: super::warp::WarpVar::QuarterPower

use glam::DVec3;

use crate::geometry;
use crate::simd::F4;

use crate::table::calibration::Calibration;
use crate::table::grid::Quantity;
#[cfg(test)]
use crate::table::warp::WarpVar;

// One concern per file; the public names are re-exported here, so every path stays
// `table::kernel::NAME`:
// - build: the kernel made from a grid (`Kernel::new`, which grids it takes) and what it tells
//   of itself;
// - packed: the values as lookups read them (`Packed`: f16 codes or exact f32);
// - axis: the knot lines of the three axes (warped or resampled), the resampling constants,
//   `KernelAxis`;
// - project: the warp variables of a pair and the projection of a quantity to f_r;
// - blend: the blends from the variables to the values (`impl Kernel`, all inlined);
// - x8: eight lookups at once in AVX2 lanes;
// - tests: the kernel against its references.
mod axis;
mod blend;
mod build;
mod packed;
mod project;
mod x8;

pub use axis::{KernelAxis, RESAMPLE_TOLERANCE, RESAMPLED_KNOTS, RESAMPLED_MAX_VALUES};
pub use packed::Packed;
pub use project::{MIN_COS_PRODUCT, project_out, reference_vars};
pub(crate) use project::{project_f32, project_f32_lanes, warp_vars};
pub use x8::LANES;

use axis::Axis;
use project::unit_pair;

/// The fast linear lookup of a table on an adaptive grid (see the module docs).
#[derive(Debug, Clone)]
pub struct Kernel {
    axes: [Axis; 3],
    /// φd folded onto [0, π/2] (reciprocity) instead of [0, π].
    quarter: bool,
    /// θh's variable is [`WarpVar::QuarterPower`](crate::table::warp::WarpVar::QuarterPower)
    /// ((1 − cos θh)^¼) instead of [`WarpVar::SqrtSine`](crate::table::warp::WarpVar::SqrtSine).
    h_quarter_power: bool,
    channels: usize,
    /// Values per θd row of a chunk (stored φd nodes × channels).
    row: usize,
    /// Values per chunk (θh node).
    chunk: usize,
    /// Lane constants of [`Kernel::eval_rgb`]: K per axis, K − ½ (the last knot interval's
    /// truncation bound), n − 1 and n − 1.5 per axis; lane 3 is unused (0).
    lanes: [F4; 4],
    /// The CPU has F16C (checked once, at construction): RGB lookups expand codes with it.
    /// (x86-64 only: elsewhere codes are expanded with integer operations.)
    #[cfg(target_arch = "x86_64")]
    f16c: bool,
    /// Per axis the variable from which lookups take the general path (resampled axes; 2 on
    /// warped ones, never; lane 3: 2).
    cut: F4,
    /// Some axis is resampled (a fixed mapping).
    resampled: bool,
    /// Some axis has a cut (< 2): RGB lookups check it.
    cuts: bool,
    /// What the values are: lookups of a quantity other than f_r divide by its factor.
    quantity: Quantity,
    /// The albedo calibration lookups multiply by, if any.
    calibration: Option<Calibration>,
    /// Values are read exact ([`Packed::exact`]): some axis is resampled.
    exact: bool,
    /// [`Kernel::eval_x8`] runs: offsets within i32, and the CPU has AVX2 and F16C (checked
    /// once, at construction).
    x8: bool,
}

impl Kernel {
    /// The warp variables (v_h, v_d, v_φ) of a pair, or `None` below the horizon (the fast
    /// path; [`reference_vars`] is the same in the paper's terms).
    #[inline(always)]
    pub fn vars(&self, wi: DVec3, wo: DVec3) -> Option<[f32; 3]> {
        warp_vars(wi, wo, self.h_quarter_power, self.quarter).map(|(v, _)| v)
    }

    /// [`Kernel::vars`] on four lanes: the three quotients in one division, the square roots
    /// in one (two for v_h); the same IEEE operations, so the same values (tested).
    /// Lane 0 of the one division also gives 1 / (cos θi cos θo) (returned beside the variables;
    /// the cosine product is kept at or above [`MIN_COS_PRODUCT`] so that it stays finite), and
    /// (cos θi, cos θo) come last.
    #[inline(always)]
    fn vars_lanes(&self, wi: DVec3, wo: DVec3) -> Option<(F4, f32, [f32; 2])> {
        // One branch for the usual unit pair (exact, or unit to f32 precision and corrected
        // without a root: `geometry::near_unit`); anything else goes through `geometry::unit`.
        let (li, lo) = (wi.length_squared(), wo.length_squared());
        let (wi, wo) = if geometry::is_unit_l2(li) & geometry::is_unit_l2(lo) {
            (wi, wo)
        } else if geometry::is_near_unit_l2(li) & geometry::is_near_unit_l2(lo) {
            (
                geometry::unit_or_near(wi, li),
                geometry::unit_or_near(wo, lo),
            )
        } else {
            unit_pair(wi, wo)?
        };
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return None;
        }
        let (ix, iy, iz) = (wi.x as f32, wi.y as f32, wi.z as f32);
        let (ox, oy, oz) = (wo.x as f32, wo.y as f32, wo.z as f32);
        let (hx, hy, hz) = (ix + ox, iy + oy, iz + oz);
        let r2 = hx * hx + hy * hy;
        let hh = r2 + hz * hz;
        let hl = hh.sqrt();
        // v_h's chain (a quotient, two roots); for SqrtSine it starts without waiting for |h|.
        let vh = if self.h_quarter_power {
            (r2 / (hh + hl * hz)).sqrt().sqrt()
        } else {
            (r2 / hh).sqrt().sqrt()
        };
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
        let cc = match self.quantity {
            Quantity::FrCosOut => oz,
            _ => iz * oz,
        }
        .max(MIN_COS_PRODUCT);
        let q = F4::new(1.0, e2, pn, 0.0) / F4::new(cc, 2.0 * (2.0 + hl), pd, 1.0);
        let [q0, q1, q2, _] = q.to_array();
        let p = if self.quarter { q2 } else { 0.5 - 0.5 * q2 };
        let v = F4::new(vh, q1.sqrt(), p, 0.0);
        Some((v, q0, [iz, oz]))
    }

    /// Evaluates into `out[..channels]` from the table's `values` (all chunks, in order, as
    /// [`Packed::for_kernel`] makes them; corners beyond its end — none for [`Packed::empty`], a
    /// table that could not be loaded — count as 0). Returns false, with `out` untouched, for a
    /// pair beyond a resampled axis's cut: the caller looks it up on the general path.
    #[inline]
    pub fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32], values: &Packed) -> bool {
        if self.channels == 3 {
            if self.exact {
                return self.rgb::<false, true, true>(wi, wo, out, values);
            }
            #[cfg(target_arch = "x86_64")]
            if self.f16c {
                // SAFETY: `f16c` is set only when the CPU has F16C (`has_f16c`).
                return unsafe {
                    if self.cuts {
                        self.rgb_f16c::<true>(wi, wo, out, values)
                    } else {
                        self.rgb_f16c::<false>(wi, wo, out, values)
                    }
                };
            }
            return if self.cuts {
                self.rgb::<false, false, true>(wi, wo, out, values)
            } else {
                self.rgb::<false, false, false>(wi, wo, out, values)
            };
        }
        // The RGB path's variables (the same values as `warp_vars`, tested; its one branch
        // for unit and near-unit pairs).
        let Some((v, _, cos)) = self.vars_lanes(wi, wo) else {
            out[..self.channels].fill(0.0);
            return true;
        };
        if v.any_ge(self.cut) {
            return false;
        }
        let [v0, v1, v2, _] = v.to_array();
        let v = [v0, v1, v2];
        // The calibration's cells first: they need only the cosines (see `rgb`).
        let cells = (self.calibration.as_ref()).map(|c| c.cells(cos[0], cos[1]));
        // Four channels per lane group on every target ([`F4`]: SSE2 on x86-64, four plain f32
        // elsewhere, left to LLVM to vectorize); only the F16C expansion is x86-64's.
        #[cfg(target_arch = "x86_64")]
        if !self.exact && self.f16c {
            // SAFETY: `f16c` is set only when the CPU has F16C (`has_f16c`).
            unsafe { self.blend_lanes_f16c(v, out, values) };
        } else {
            self.blend_lanes_plain(v, out, values);
        }
        #[cfg(not(target_arch = "x86_64"))]
        self.blend_lanes_plain(v, out, values);
        let out = &mut out[..self.channels];
        if self.quantity != Quantity::Fr {
            // In f32, as the RGB lookup does (one rule for every channel count).
            project_f32_lanes(self.quantity, None, cos, out);
        }
        if let (Some(c), Some(cells)) = (&self.calibration, cells) {
            c.apply_lanes_cells(cells, out);
        }
        true
    }

    /// The RGB lookup of f16 codes compiled with F16C (and the VEX encoding it brings).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "f16c")]
    fn rgb_f16c<const CUT: bool>(
        &self,
        wi: DVec3,
        wo: DVec3,
        out: &mut [f32],
        values: &Packed,
    ) -> bool {
        self.rgb::<true, false, CUT>(wi, wo, out, values)
    }

    /// The RGB lookup; `F16C`: expand codes with F16C (only inside [`Kernel::rgb_f16c`]);
    /// `EXACT`: read exact values; `CUT`: check the resampled axes' cut (warped axes have none:
    /// the check is left out).
    #[inline(always)]
    fn rgb<const F16C: bool, const EXACT: bool, const CUT: bool>(
        &self,
        wi: DVec3,
        wo: DVec3,
        out: &mut [f32],
        values: &Packed,
    ) -> bool {
        match self.vars_lanes(wi, wo) {
            // Only resampled axes have a cut (< 2).
            Some((v, _, _)) if CUT && v.any_ge(self.cut) => false,
            Some((v, inv_cc, [cos_i, cos_o])) => {
                // The calibration's factors first: they need only the cosines, and here they
                // run beside the blend's chain (after it, they lengthened the lookup by 5 ns).
                let k = (self.calibration.as_ref()).and_then(|c| c.factors_rgb(cos_i, cos_o));
                let x = self.eval_rgb::<F16C, EXACT>(v, values);
                let cal = |_: &Calibration, x| Calibration::times(x, k);
                let [r, g, b, _] = self.finish_rgb(x, inv_cc, cal).to_array();
                out[..3].copy_from_slice(&[r, g, b]);
                true
            }
            None => {
                out[..3].fill(0.0);
                true
            }
        }
    }

    /// f_r from the blended RGB `x` of a pair with 1/(its quantity's factor) `inv_cc`: a
    /// quantity other than f_r divided by its factor and clamped at 0, then the calibration
    /// applied by `cal` (at the pair's cosines; the one-pair and eight-lane paths' common end).
    #[inline(always)]
    fn finish_rgb(&self, mut x: F4, inv_cc: f32, cal: impl FnOnce(&Calibration, F4) -> F4) -> F4 {
        if self.quantity != Quantity::Fr {
            // Extrapolated nodes beyond the horizon may pull the blend below 0.
            x = (x * F4::splat(inv_cc)).max(F4::splat(0.0));
        }
        if let Some(c) = &self.calibration {
            x = cal(c, x);
        }
        x
    }

    /// [`Kernel::blend_lanes`] without F16C: exact values, or f16 codes expanded with integer
    /// operations ([`F4::from_f16_normal`]).
    #[inline(always)]
    fn blend_lanes_plain(&self, v: [f32; 3], out: &mut [f32], values: &Packed) {
        if self.exact {
            self.blend_lanes::<false, true>(v, out, values);
        } else {
            self.blend_lanes::<false, false>(v, out, values);
        }
    }

    /// [`Kernel::blend_lanes`] expanding f16 codes with F16C.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "f16c")]
    fn blend_lanes_f16c(&self, v: [f32; 3], out: &mut [f32], values: &Packed) {
        self.blend_lanes::<true, false>(v, out, values)
    }
}

/// The adaptive-grid cases the kernel's tests bake (reciprocity, stored quantity, θh's
/// variable): both θh variables, f_r and both projected quantities.
#[cfg(test)]
pub(crate) const TEST_CASES: [(bool, Quantity, WarpVar); 4] = [
    (false, Quantity::Fr, WarpVar::SqrtSine),
    (true, Quantity::Fr, WarpVar::QuarterPower),
    (false, Quantity::FrCosOut, WarpVar::QuarterPower),
    (true, Quantity::FrCosCos, WarpVar::SqrtSine),
];

/// The small adaptive grid the kernel's and the device layout's tests bake (24 × 16 × 9 nodes).
#[cfg(test)]
pub(crate) fn test_adaptive_options(
    quantity: Quantity,
    h_var: WarpVar,
) -> crate::table::adaptive::AdaptiveOptions {
    crate::table::adaptive::AdaptiveOptions {
        nodes: [24, 16, 9],
        fine: [64, 32, 16],
        quantity,
        h_var,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests;
