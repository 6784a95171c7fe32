//! What the kernel computes besides the blend: the warp variables of a pair from its direction
//! vectors ([`warp_vars`], and [`reference_vars`], the same from the angles), and the
//! projection of an interpolated quantity back to f_r ([`project_out`], [`project_f32`],
//! [`project_f32_lanes`], all dividing by at least [`MIN_COS_PRODUCT`]).
//!
//! Why a file of its own: these are free functions used beyond the kernel — the device layouts
//! (`table::device`) state them for devices, and `TabulatedBrdf`'s general lookup projects with
//! [`project_out`] — while the kernel's own lookups call them or, on the RGB path, do the same
//! operations in lanes.

use glam::DVec3;

use crate::geometry;
use crate::simd::F4;
use crate::table::calibration::Calibration;
use crate::table::grid::Quantity;
use crate::table::warp::WarpVar;

/// The smallest factor (cos θi cos θo, cos θo) a lookup of a [`Quantity`] divides by (a normal
/// f32; pairs closer to the horizon keep a finite value).
pub const MIN_COS_PRODUCT: f32 = 1e-30;

/// f_r from an interpolated `quantity`: `out` divided by the quantity's factor for the pair
/// (unit vectors made here) and clamped at 0 (extrapolated nodes beyond the horizon may pull
/// the blend below 0; f_r itself is left as it is), then multiplied by the `calibration`'s
/// k_in(θi) k_out(θo) if there is one; 0 for pairs below the horizon.
pub fn project_out(
    quantity: Quantity,
    calibration: Option<&Calibration>,
    wi: DVec3,
    wo: DVec3,
    out: &mut [f32],
) {
    match geometry::upper_pair(wi, wo) {
        Some((wi, wo)) => {
            if quantity != Quantity::Fr {
                let s = 1.0 / quantity.factor(wi.z, wo.z).max(MIN_COS_PRODUCT as f64);
                for x in out.iter_mut() {
                    *x = ((*x as f64 * s) as f32).max(0.0);
                }
            }
            if let Some(c) = calibration {
                c.apply(wi.z as f32, wo.z as f32, out);
            }
        }
        None => out.fill(0.0),
    }
}

/// The warp variables (v_h, v_d, v_φ) of a pair in f32 and (cos θi, cos θo), or `None` below
/// the horizon: [`Kernel::vars`] (and `table::device`'s `KernelLayout::vars`). With h = ωi + ωo
/// (not normalized), e = ωi − ωo and r² = h_x² + h_y²: v_h = (r²/|h|²)^¼, or
/// (r²/(|h|² + |h| h_z))^¼ for `h_quarter_power`; v_d = (|e|²/(2(2 + |h|)))^½; the
/// difference vector's d_x = h_z(h_x ωi_x + h_y ωi_y) − r² ωi_z, d_y = ||h|(h_x ωi_y − h_y ωi_x)|
/// give v_φ = d_y/(|d_x| + d_y) (`quarter`) or ½ − ½ d_x/(|d_x| + d_y), 0 when both vanish.
///
/// [`Kernel::vars`]: super::Kernel::vars
#[inline(always)]
pub(crate) fn warp_vars(
    wi: DVec3,
    wo: DVec3,
    h_quarter_power: bool,
    quarter: bool,
) -> Option<([f32; 3], [f32; 2])> {
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
    // sin θh = r/|h|, or 1 − cos θh = r²/(|h|(|h| + hz)): no cancellation near θh = 0.
    let vh = if h_quarter_power {
        (r2 / (r2 + hz * hz + hl * hz)).sqrt().sqrt()
    } else {
        (r2 / (r2 + hz * hz)).sqrt().sqrt()
    };
    let dx = hz * (hx * ix + hy * iy) - r2 * iz;
    let dy = (hl * (hx * iy - hy * ix)).abs();
    let den = dx.abs() + dy;
    let vp = if !(den > 0.0) {
        0.0
    } else if quarter {
        dy / den
    } else {
        0.5 - 0.5 * (dx / den)
    };
    Some(([vh, vd, vp], [iz, oz]))
}

/// The kernel's projection of an interpolated `quantity` at unit directions with z = `cos_i`,
/// `cos_o`, in f32: other than f_r, times 1/max(factor, [`MIN_COS_PRODUCT`]) and clamped at 0;
/// then times the `calibration`'s k_in(θi) k_out(θo) — what [`Kernel::eval`] does for every
/// channel count (the RGB path in lanes), and what `table::device` states for devices.
///
/// [`Kernel::eval`]: super::Kernel::eval
pub(crate) fn project_f32(
    quantity: Quantity,
    calibration: Option<&Calibration>,
    [cos_i, cos_o]: [f32; 2],
    out: &mut [f32],
) {
    if quantity != Quantity::Fr {
        let inv = inverse_factor(quantity, [cos_i, cos_o]);
        for x in out.iter_mut() {
            *x = (*x * inv).max(0.0);
        }
    }
    if let Some(c) = calibration {
        c.apply(cos_i, cos_o, out);
    }
}

/// 1/max(factor, [`MIN_COS_PRODUCT`]) of a stored `quantity` at cosines (cos θi, cos θo).
#[inline(always)]
fn inverse_factor(quantity: Quantity, [cos_i, cos_o]: [f32; 2]) -> f32 {
    let f = match quantity {
        Quantity::FrCosOut => cos_o,
        _ => cos_i * cos_o,
    };
    1.0 / f.max(MIN_COS_PRODUCT)
}

/// [`project_f32`] four channels at a time (the same operations lane by lane, tested equal).
#[inline(always)]
pub(crate) fn project_f32_lanes(
    quantity: Quantity,
    calibration: Option<&Calibration>,
    [cos_i, cos_o]: [f32; 2],
    out: &mut [f32],
) {
    if quantity != Quantity::Fr {
        let inv = inverse_factor(quantity, [cos_i, cos_o]);
        let (iv, zero) = (F4::splat(inv), F4::splat(0.0));
        let mut chunks = out.chunks_exact_mut(4);
        for x4 in &mut chunks {
            if let Some(x) = F4::load(x4) {
                x4.copy_from_slice(&(x * iv).max(zero).to_array());
            }
        }
        for x in chunks.into_remainder() {
            *x = (*x * inv).max(0.0);
        }
    }
    if let Some(c) = calibration {
        c.apply_lanes(cos_i, cos_o, out);
    }
}

/// Both directions made unit (out of the hot path).
#[cold]
#[inline(never)]
pub(super) fn unit_pair(wi: DVec3, wo: DVec3) -> Option<(DVec3, DVec3)> {
    Some((geometry::unit(wi)?, geometry::unit(wo)?))
}

/// The warp variables of a pair from its Rusinkiewicz angles (the reference for
/// [`Kernel::vars`]): `None` below the horizon.
///
/// [`Kernel::vars`]: super::Kernel::vars
pub fn reference_vars(wi: DVec3, wo: DVec3, quarter: bool, h_var: WarpVar) -> Option<[f64; 3]> {
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
        h_var.of_angle(hd.theta_h, std::f64::consts::FRAC_PI_2),
        WarpVar::HalfPower.of_angle(hd.theta_d, std::f64::consts::FRAC_PI_2),
        WarpVar::PseudoAngle.of_angle(p, hi),
    ])
}
