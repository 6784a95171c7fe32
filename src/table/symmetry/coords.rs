//! The symmetry maps themselves: a direction pair (or Rusinkiewicz angles, or a corner of packed
//! `inout` reciprocity) to canonical stored coordinates. The lookups' hot path, kept in one file.

use glam::DVec3;
use std::f64::consts::{PI, TAU};

use super::Symmetry;
use crate::geometry;
use crate::table::param::Param;

/// Canonical coordinates of a pair in the stored domains of a grid with parameterization
/// `param` and symmetry `sym`: `[θ1, φ1, θ2, φ2]` (`inout` isotropic: `[θi, 0, θo, Δφ]`;
/// `halfdiff` isotropic: `[θh, 0, θd, φd]`). `None` below the horizon or for invalid input.
///
/// Angles come from vector algebra where possible (one `atan2` for Δφ instead of two) and from
/// the exact `libm` functions; [`canonical_coords_fast`] uses polynomial approximations.
#[inline]
pub fn canonical_coords(param: Param, sym: Symmetry, wi: DVec3, wo: DVec3) -> Option<[f64; 4]> {
    coords::<false>(param, sym, wi, wo)
}

/// [`canonical_coords`] with polynomial `acos`/`atan2` (absolute error below 2e-7 rad): for
/// linear interpolation, where that is far below a node spacing. Nearest lookups use the exact
/// version so that cell boundaries (MERL's `int(...)`) are reproduced exactly.
#[inline]
pub fn canonical_coords_fast(
    param: Param,
    sym: Symmetry,
    wi: DVec3,
    wo: DVec3,
) -> Option<[f64; 4]> {
    coords::<true>(param, sym, wi, wo)
}

#[inline(always)]
fn acos<const FAST: bool>(x: f64) -> f64 {
    if FAST {
        fast_acos(x)
    } else {
        x.clamp(-1.0, 1.0).acos()
    }
}

#[inline(always)]
fn atan2<const FAST: bool>(y: f64, x: f64) -> f64 {
    if FAST { fast_atan2(y, x) } else { y.atan2(x) }
}

/// acos with absolute error ≤ 2e-8 (Abramowitz & Stegun 4.4.46); input clamped to [−1, 1].
#[inline(always)]
pub fn fast_acos(x: f64) -> f64 {
    let a = x.abs().min(1.0);
    let p = -0.0012624911;
    let p = p * a + 0.0066700901;
    let p = p * a - 0.0170881256;
    let p = p * a + 0.0308918810;
    let p = p * a - 0.0501743046;
    let p = p * a + 0.0889789874;
    let p = p * a - 0.2145988016;
    let p = p * a + 1.5707963050;
    let r = (1.0 - a).sqrt() * p;
    if x < 0.0 { PI - r } else { r }
}

/// atan2 with absolute error ≤ 2e-7 (Cephes `atanf` range reduction and polynomial), same
/// quadrant conventions as `f64::atan2` for finite input: result in [−π, π].
#[inline(always)]
pub fn fast_atan2(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let (num, den, swap) = if ay > ax {
        (ax, ay, true)
    } else {
        (ay, ax, false)
    };
    // z = min/max in [0, 1]; reduce to [0, tan(π/8)].
    let z = if den > 0.0 { num / den } else { 0.0 };
    let (base, t) = if z > 0.414_213_562_373_095 {
        (std::f64::consts::FRAC_PI_4, (z - 1.0) / (z + 1.0))
    } else {
        (0.0, z)
    };
    let t2 = t * t;
    let mut r = base
        + (((8.053_744_495_38e-2 * t2 - 1.387_768_560_32e-1) * t2 + 1.997_771_064_78e-1) * t2
            - 3.333_294_915_39e-1)
            * t2
            * t
        + t;
    if swap {
        r = std::f64::consts::FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 { -r } else { r }
}

#[inline(always)]
fn coords<const FAST: bool>(param: Param, sym: Symmetry, wi: DVec3, wo: DVec3) -> Option<[f64; 4]> {
    let (wi, wo) = if FAST {
        // Unit inputs (the usual case) skip the two normalizations.
        let (wi, wo) = (geometry::unit(wi)?, geometry::unit(wo)?);
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return None;
        }
        (wi, wo)
    } else {
        geometry::upper_pair(wi, wo)?
    };
    match param {
        Param::InOut => {
            let ti = acos::<FAST>(wi.z);
            let to = acos::<FAST>(wo.z);
            if sym.isotropic {
                let dot = wi.x * wo.x + wi.y * wo.y;
                let cross = wi.x * wo.y - wi.y * wo.x;
                let mut d = atan2::<FAST>(cross, dot);
                let (mut t1, mut t2) = (ti, to);
                if sym.reciprocal && t1 > t2 {
                    std::mem::swap(&mut t1, &mut t2);
                    d = -d;
                }
                if sym.bilateral {
                    d = d.abs();
                } else if d < 0.0 {
                    d += TAU;
                }
                Some([t1, 0.0, t2, d])
            } else {
                let mut a = [ti, atan2::<FAST>(wi.y, wi.x), to, atan2::<FAST>(wo.y, wo.x)];
                if sym.reciprocal && a[0] > a[2] {
                    a.swap(0, 2);
                    a.swap(1, 3);
                }
                if sym.bilateral && a[1] < 0.0 {
                    a[1] = -a[1];
                    a[3] = -a[3];
                }
                if a[1] < 0.0 {
                    a[1] += TAU;
                }
                if a[3] < 0.0 {
                    a[3] += TAU;
                }
                Some(a)
            }
        }
        Param::HalfDiff => {
            let (th, td, pd, h) = if FAST {
                half_diff_angles_fast(wi, wo)?
            } else {
                let (h, d) = geometry::half_diff_vectors(wi, wo)?;
                (
                    acos::<FAST>(h.z),
                    acos::<FAST>(d.z),
                    atan2::<FAST>(d.y, d.x),
                    h,
                )
            };
            let ph = if sym.isotropic {
                0.0
            } else {
                atan2::<FAST>(h.y, h.x)
            };
            Some(fold_half_diff(sym, th, ph, td, pd))
        }
    }
}

/// The symmetry folds of `halfdiff` coordinates: (θh, φh, θd, φd) with φh, φd in [−π, π] (φh
/// ignored for isotropic grids) to the stored domains.
#[inline(always)]
fn fold_half_diff(sym: Symmetry, th: f64, mut ph: f64, td: f64, mut pd: f64) -> [f64; 4] {
    if sym.isotropic {
        ph = 0.0;
    } else {
        if sym.bilateral && ph < 0.0 {
            ph = -ph;
            pd = -pd;
        }
        if ph < 0.0 {
            ph += TAU;
        }
    }
    let iso_bilat = sym.isotropic && sym.bilateral;
    if sym.reciprocal && iso_bilat {
        let a = pd.abs();
        pd = a.min(PI - a);
    } else if sym.reciprocal {
        // As the MERL reader: φd + π when negative.
        if pd < 0.0 {
            pd += PI;
        }
    } else if iso_bilat {
        pd = pd.abs();
    } else if pd < 0.0 {
        pd += TAU;
    }
    [th, ph, td, pd]
}

/// Canonical stored `halfdiff` coordinates of Rusinkiewicz angles under `sym`: the folds of
/// [`canonical_coords`] applied to angles directly, without going through directions (so a pair
/// with a direction below the horizon still has coordinates). Azimuths may be given in any
/// period; they are first brought to (−π, π].
pub fn canonical_half_diff(sym: Symmetry, hd: geometry::HalfDiff) -> [f64; 4] {
    let wrap = |a: f64| {
        let a = a.rem_euclid(TAU);
        if a > PI { a - TAU } else { a }
    };
    let [th, ph, td, pd] =
        fold_half_diff(sym, hd.theta_h, wrap(hd.phi_h), hd.theta_d, wrap(hd.phi_d));
    // φd = π folds to π under reciprocity alone (the reader's φd + π applies to negative φd
    // only); it is the same direction pair as φd = 0.
    let pd = if sym.reciprocal && !(sym.isotropic && sym.bilateral) && pd >= PI {
        pd - PI
    } else {
        pd
    };
    [th, ph, td, pd]
}

/// (θh, θd, φd, h) of a pair of unit directions with the unnormalized half vector
/// h = wi + wo, one square root and one reciprocal (besides the polynomial `atan2`):
/// cos θh = h_z/|h|, cos θd = wi·h/|h|, and φd = atan2(d_y, d_x) where the difference vector's
/// components, multiplied by the positive |h|·|h_xy|, are
/// d_y ∝ (wi_y h_x − wi_x h_y)|h| and d_x ∝ (wi_x h_x + wi_y h_y) h_z − wi_z |h_xy|²
/// (rotate wi by −φh about z, then by −θh about y; `geometry::half_diff_vectors` step by
/// step). At the pole (h_xy = 0, φh = 0 by convention) d = wi.
#[inline(always)]
fn half_diff_angles_fast(wi: DVec3, wo: DVec3) -> Option<(f64, f64, f64, DVec3)> {
    let h = wi + wo;
    let hxy2 = h.x * h.x + h.y * h.y;
    let hh = hxy2 + h.z * h.z;
    if !(hh > 1e-300) {
        return None;
    }
    let len = hh.sqrt();
    let inv = 1.0 / len;
    let th = fast_acos(h.z * inv);
    let td = fast_acos(wi.dot(h) * inv);
    let pd = if hxy2 > 1e-24 * hh {
        let y = (wi.y * h.x - wi.x * h.y) * len;
        let x = (wi.x * h.x + wi.y * h.y) * h.z - wi.z * hxy2;
        fast_atan2(y, x)
    } else {
        fast_atan2(wi.y, wi.x)
    };
    Some((th, td, pd, h))
}

/// Canonicalizes a corner `[a, p, b, q]` of packed `inout` reciprocity (stored θ1 ≤ θ2): when
/// a > b, the reciprocal node is returned. `n1`, `n3` are the full φ sizes (φi, φo);
/// the stored axis-1/axis-3 conventions follow the grid (see the module table).
#[inline]
pub fn canonical_corner_inout(sym: Symmetry, idx: [usize; 4], n3: usize) -> [usize; 4] {
    let [a, p, b, q] = idx;
    if a <= b {
        return idx;
    }
    if sym.isotropic {
        // (θi, θo, Δφ) → (θo, θi, −Δφ); with bilateral symmetry the stored |Δφ| is unchanged.
        let q2 = if sym.bilateral || q == 0 { q } else { n3 - q };
        [b, 0, a, q2]
    } else if sym.bilateral && q > n3 / 2 {
        // Swap, then reflect both φ through the x–z plane to bring φ1 into [0, π].
        let p2 = if p == 0 { 0 } else { n3 - p };
        [b, n3 - q, a, p2]
    } else {
        [b, q, a, p]
    }
}
