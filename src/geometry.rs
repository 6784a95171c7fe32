//! Directions in the local shading frame: validation, spherical angles, reflection, the
//! Rusinkiewicz half/difference transform, orthonormal frames and the basic warps.
//!
//! Everything here is small, `Copy` and allocation-free, because it sits on the hot path of every
//! evaluation and lookup. Where vector algebra suffices it is used instead of trigonometry
//! (e.g. the half/diff rotation uses cos θh = h_z and sin θh = |h_xy|, not `acos` and `sin`).

use glam::{DVec2, DVec3};
use std::f64::consts::FRAC_PI_4;

/// Normalizes `v`, or returns `None` for zero, infinite or NaN vectors.
///
/// Any other vector is a direction, however short or long: one whose squared length is not a
/// normal f64 (|v| below 1.5e-154, where it is subnormal and inexact or 0, or above 1.3e154,
/// where it overflows) is scaled to a largest component of 1 first.
#[inline]
pub fn normalize(v: DVec3) -> Option<DVec3> {
    let l2 = v.length_squared();
    if (f64::MIN_POSITIVE..f64::INFINITY).contains(&l2) {
        Some(v / l2.sqrt())
    } else {
        normalize_scaled(v)
    }
}

/// [`normalize`] of a vector whose squared length under- or overflows (out of line: rare).
#[cold]
#[inline(never)]
pub(crate) fn normalize_scaled(v: DVec3) -> Option<DVec3> {
    if !v.is_finite() {
        return None;
    }
    let m = v.abs().max_element();
    if m == 0.0 {
        return None;
    }
    let s = v / m;
    Some(s / s.length())
}

/// Like [`normalize`], but returns `v` unchanged when it is already unit to within 2⁻⁴⁰ in
/// squared length, and corrects it without a square root or division when it is unit to
/// within 2⁻²⁰ ([`near_unit`]). Renderers pass unit directions — in f64 exactly, from f32
/// (pbrt-v4, Mitsuba 3, any C or numpy float32 caller) only to the f32 rounding of their
/// normalization, |l² − 1| up to a few 2⁻²⁴ — and either way this saves the square root and
/// division that would otherwise head the dependency chain of every sampler and lookup.
#[inline]
pub fn unit(v: DVec3) -> Option<DVec3> {
    let l2 = v.length_squared();
    if is_unit_l2(l2) {
        Some(v)
    } else if is_near_unit_l2(l2) {
        Some(near_unit(v, l2))
    } else {
        normalize(v)
    }
}

/// True when a squared length is 1 to within 2⁻⁴⁰: the vector counts as unit and is used as is
/// (see [`unit()`]).
#[inline]
pub fn is_unit_l2(l2: f64) -> bool {
    (l2 - 1.0).abs() <= 1.0 / (1u64 << 40) as f64
}

/// How far from 1 a squared length may be for [`near_unit`]: 2⁻²⁰, 16× the deviation of a unit
/// vector rounded to f32 and renormalized in f32 (|l² − 1| ≤ ~2⁻²⁴ · 3).
pub const NEAR_UNIT_L2: f64 = 1.0 / (1u64 << 20) as f64;

/// True when a squared length is 1 to within [`NEAR_UNIT_L2`]: [`near_unit`] makes the vector
/// unit to within 2⁻⁴⁰ ([`is_unit_l2`]).
#[inline]
pub fn is_near_unit_l2(l2: f64) -> bool {
    (l2 - 1.0).abs() <= NEAR_UNIT_L2
}

/// `v` (squared length `l2`, with [`is_near_unit_l2`]) made unit by one Newton step of
/// 1/√l2 from 1: v (3 − l2)/2. For l2 = 1 + δ the result's squared length is
/// (1 + δ)(1 − δ/2)² = 1 − ¾δ² + ¼δ³, within ¾ · 2⁻⁴⁰ of 1 for |δ| ≤ 2⁻²⁰ — what
/// [`normalize`] gives to the same tolerance, at the cost of two multiplications instead of a
/// square root and a division (the reference version: `normalize`, tested against).
#[inline(always)]
pub fn near_unit(v: DVec3, l2: f64) -> DVec3 {
    v * (1.5 - 0.5 * l2)
}

/// `v` (squared length `l2`, with [`is_near_unit_l2`]) as [`unit()`] returns it: unchanged
/// when it is unit to within 2⁻⁴⁰ (multiplied by exactly 1), else [`near_unit`]. A select,
/// not a branch: exact and f32-rounded inputs take the same path.
#[inline(always)]
pub fn unit_or_near(v: DVec3, l2: f64) -> DVec3 {
    v * if is_unit_l2(l2) { 1.0 } else { 1.5 - 0.5 * l2 }
}

/// True when `v` is finite and strictly above the horizon (z > 0): all a sampler needs to know
/// about `wo` when only the sign of cos θo matters. Agrees with
/// `normalize(v).is_some_and(|w| w.z > 0.0)`.
#[inline]
pub fn is_upper(v: DVec3) -> bool {
    v.z > 0.0 && v.z < f64::INFINITY && v.x.is_finite() && v.y.is_finite()
}

/// True when `u` lies in [0, 1)², the square every sampler maps: false beyond its edges (1
/// included), for an infinite or NaN coordinate. [`Brdf::sample`](crate::Brdf::sample) and
/// [`Brdf::sample_batch`](crate::Brdf::sample_batch) draw nothing for any other `u`.
#[inline]
pub fn in_unit_square(u: DVec2) -> bool {
    (0.0..1.0).contains(&u.x) && (0.0..1.0).contains(&u.y)
}

/// Normalizes a pair of directions and checks that both lie strictly above the horizon
/// (z > 0). Returns `None` otherwise — the caller then returns 0 (see the `Brdf` conventions).
///
/// The hot path of every model's evaluation: directions unit to within 2⁻⁴⁰ in squared length
/// are returned unchanged and ones unit to within 2⁻²⁰ (a renderer's f32 directions) corrected
/// without a root ([`unit_or_near`]) — one branch, taken the same way for both —; any other
/// pair is normalized out of line with one division (1 / (|wi| |wo|)) instead of six.
/// Symmetric: swapping the arguments swaps the results bit for bit.
#[inline]
pub fn upper_pair(wi: DVec3, wo: DVec3) -> Option<(DVec3, DVec3)> {
    let (l2, v2) = (wi.length_squared(), wo.length_squared());
    if !(wi.z > 0.0 && wo.z > 0.0) {
        return None;
    }
    if is_near_unit_l2(l2) & is_near_unit_l2(v2) {
        return Some((unit_or_near(wi, l2), unit_or_near(wo, v2)));
    }
    other_lengths(wi, wo, l2, v2)
}

/// [`upper_pair`] of a pair whose lengths are not both near 1 (out of the hot path).
#[cold]
#[inline(never)]
fn other_lengths(wi: DVec3, wo: DVec3, l2: f64, v2: f64) -> Option<(DVec3, DVec3)> {
    let normal = f64::MIN_POSITIVE..f64::INFINITY;
    if !(normal.contains(&l2) && normal.contains(&v2)) {
        // Lengths whose squares under- or overflow (or NaN, infinite): scaled one by one.
        let (wi, wo) = (normalize(wi)?, normalize(wo)?);
        return (wi.z > 0.0 && wo.z > 0.0).then_some((wi, wo));
    }
    // 1/(|wi| |wo|) ≤ 1/MIN_POSITIVE: finite.
    let (sl, sv) = (l2.sqrt(), v2.sqrt());
    let r = 1.0 / (sl * sv);
    Some((wi * (sv * r), wo * (sl * r)))
}

/// The unit direction with polar angle `theta` from +z and azimuth `phi` from +x:
/// (sin θ cos φ, sin θ sin φ, cos θ).
#[inline]
pub fn spherical(theta: f64, phi: f64) -> DVec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    DVec3::new(st * cp, st * sp, ct)
}

/// Polar angle θ ∈ [0, π] and azimuth φ ∈ (−π, π] of a unit direction.
#[inline]
pub fn to_spherical(w: DVec3) -> (f64, f64) {
    (w.z.clamp(-1.0, 1.0).acos(), w.y.atan2(w.x))
}

/// Ideal mirror reflection of `w` about the normal `n` (both unit): 2 (n·w) n − w.
/// With n = z this is the lecture's ω_r = 2 cos α N − ω.
#[inline]
pub fn reflect(w: DVec3, n: DVec3) -> DVec3 {
    2.0 * n.dot(w) * n - w
}

/// Elevation of a unit vector, 2·asin(|d − z| / 2): equal to acos(d.z) but accurate near the
/// pole (the RGL reader's form).
#[inline]
pub fn elevation(d: DVec3) -> f64 {
    let dist = (d.x * d.x + d.y * d.y + (d.z - 1.0) * (d.z - 1.0)).sqrt();
    2.0 * (0.5 * dist).min(1.0).asin()
}

/// Mirror image across the surface plane: (x, y, −z). Samplers that fold a draw below the
/// horizon back above it (rather than refuse it) give the folded direction the density of both
/// its preimages, `w` and `mirror_z(w)`.
#[inline]
pub fn mirror_z(w: DVec3) -> DVec3 {
    DVec3::new(w.x, w.y, -w.z)
}

/// Mirror reflection about the local normal z: (−x, −y, z).
#[inline]
pub fn reflect_z(w: DVec3) -> DVec3 {
    DVec3::new(-w.x, -w.y, w.z)
}

/// Rusinkiewicz (1998) half/difference angles of a direction pair, as in the MERL reader.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfDiff {
    /// Polar angle of the half vector, [0, π/2].
    pub theta_h: f64,
    /// Azimuth of the half vector, (−π, π].
    pub phi_h: f64,
    /// Polar angle of the difference vector, [0, π/2].
    pub theta_d: f64,
    /// Azimuth of the difference vector, (−π, π].
    pub phi_d: f64,
}

/// Half vector and difference vector (unit) of a pair: h = normalize(wi + wo); d is `wi` rotated
/// by −φh about z and then by −θh about y. Computed with vector algebra only.
///
/// `wi` and `wo` must be unit; returns `None` when they are opposite (no half vector).
#[inline]
pub fn half_diff_vectors(wi: DVec3, wo: DVec3) -> Option<(DVec3, DVec3)> {
    let h = normalize(wi + wo)?;
    let sin_th = (h.x * h.x + h.y * h.y).sqrt();
    let cos_th = h.z;
    // cos φh, sin φh (φh = 0 at the pole, as atan2(0, 0) = 0 in the MERL reader).
    let (cos_ph, sin_ph) = if sin_th > 1e-12 {
        (h.x / sin_th, h.y / sin_th)
    } else {
        (1.0, 0.0)
    };
    // Rotate wi by −φh about z.
    let tx = wi.x * cos_ph + wi.y * sin_ph;
    let ty = -wi.x * sin_ph + wi.y * cos_ph;
    let tz = wi.z;
    // Rotate by −θh about y.
    let d = DVec3::new(tx * cos_th - tz * sin_th, ty, tz * cos_th + tx * sin_th);
    Some((h, d))
}

/// Half/difference angles of a pair of unit directions (see [`half_diff_vectors`]).
#[inline]
pub fn to_half_diff(wi: DVec3, wo: DVec3) -> Option<HalfDiff> {
    let (h, d) = half_diff_vectors(wi, wo)?;
    let (theta_h, phi_h) = to_spherical(h);
    let (theta_d, phi_d) = to_spherical(d);
    Some(HalfDiff {
        theta_h,
        phi_h,
        theta_d,
        phi_d,
    })
}

/// The direction pair `(wi, wo)` of half/difference angles (inverse of [`to_half_diff`]).
pub fn from_half_diff(hd: HalfDiff) -> (DVec3, DVec3) {
    let d = spherical(hd.theta_d, hd.phi_d);
    let rot = |v: DVec3| -> DVec3 {
        // Rotate by +θh about y, then by +φh about z.
        let (st, ct) = hd.theta_h.sin_cos();
        let x = v.x * ct + v.z * st;
        let z = -v.x * st + v.z * ct;
        let (sp, cp) = hd.phi_h.sin_cos();
        DVec3::new(x * cp - v.y * sp, x * sp + v.y * cp, z)
    };
    (rot(d), rot(DVec3::new(-d.x, -d.y, d.z)))
}

/// An orthonormal frame (tangent `s`, bitangent `t`, normal `n`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Tangent (local x).
    pub s: DVec3,
    /// Bitangent (local y).
    pub t: DVec3,
    /// Normal (local z).
    pub n: DVec3,
}

impl Frame {
    /// A frame around the unit normal `n` (Duff et al. 2017, branchless and continuous except
    /// across n.z = 0).
    pub fn from_normal(n: DVec3) -> Self {
        let sign = 1.0f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = DVec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    /// World → local coordinates.
    #[inline]
    pub fn to_local(&self, v: DVec3) -> DVec3 {
        DVec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local → world coordinates.
    #[inline]
    pub fn to_world(&self, v: DVec3) -> DVec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// Maps the unit square to the unit disk, preserving area (Shirley & Chiu's concentric map).
#[inline]
pub fn concentric_disk(u: DVec2) -> DVec2 {
    let a = 2.0 * u - DVec2::ONE;
    if a.x == 0.0 && a.y == 0.0 {
        return DVec2::ZERO;
    }
    // θ = π/4 · t with |t| ≤ 1 in the first case, π/2 − π/4 · t in the second (where sine and
    // cosine swap), so one bounded-range polynomial serves both. Written with selects rather
    // than two branches: which case applies is a coin flip, and mispredictions cost more than
    // the arithmetic.
    let swap = a.x.abs() <= a.y.abs();
    let (num, r) = if swap { (a.x, a.y) } else { (a.y, a.x) };
    let (s, c) = crate::fastmath::sin_cos_quarter(FRAC_PI_4 * (num / r));
    let (x, y) = if swap { (s, c) } else { (c, s) };
    DVec2::new(r * x, r * y)
}

/// Cosine-weighted direction on the upper hemisphere (density cos θ / π).
#[inline]
pub fn cosine_hemisphere(u: DVec2) -> DVec3 {
    // The disk point has radius r = max(|2u − 1|) (the concentric map's radius), so z = √(1 − r²)
    // needs only r and is computed alongside the sine and cosine rather than after them.
    let a = 2.0 * u - DVec2::ONE;
    let r = a.x.abs().max(a.y.abs());
    let z = (1.0 - r * r).max(0.0).sqrt();
    let d = concentric_disk(u);
    DVec3::new(d.x, d.y, z)
}

/// Uniform direction on the upper hemisphere (density 1 / 2π).
#[inline]
pub fn uniform_hemisphere(u: DVec2) -> DVec3 {
    let z = u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = crate::fastmath::sin_cos_2pi(u.y);
    DVec3::new(r * c, r * s, z)
}

/// Uniform direction on the whole sphere (density 1 / 4π).
#[inline]
pub fn uniform_sphere(u: DVec2) -> DVec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = crate::fastmath::sin_cos_2pi(u.y);
    DVec3::new(r * c, r * s, z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;
    use std::f64::consts::PI;

    #[test]
    fn cosine_hemisphere_gives_unit_vectors_above_the_horizon() {
        let n = 300;
        for i in 0..=n {
            for j in 0..=n {
                let u = DVec2::new(i as f64 / n as f64, j as f64 / n as f64);
                let w = cosine_hemisphere(u.min(DVec2::splat(1.0 - f64::EPSILON)));
                assert!((w.length_squared() - 1.0).abs() < 1e-15, "{u}: {w}");
                assert!(w.z >= 0.0);
            }
        }
    }

    #[test]
    fn upper_pair_keeps_unit_inputs_and_normalizes_others() {
        let mut rng = Pcg32::new(12);
        for _ in 0..2000 {
            let a = cosine_hemisphere(rng.next_dvec2());
            let b = cosine_hemisphere(rng.next_dvec2());
            let Some((l, v)) = upper_pair(a, b) else {
                continue;
            };
            assert_eq!((l, v), (a, b), "unit inputs are returned as they are");
            let (l2, v2) = upper_pair(a * 3.0, b * 0.25).unwrap();
            assert!((l2 - a).length() < 1e-15 && (v2 - b).length() < 1e-15);
            // Symmetric bit for bit.
            assert_eq!(upper_pair(b * 0.25, a * 3.0), Some((v2, l2)));
        }
        assert!(upper_pair(DVec3::new(0.0, 0.0, -1.0), DVec3::Z).is_none());
        assert!(upper_pair(DVec3::new(f64::NAN, 0.0, 1.0), DVec3::Z).is_none());
        assert!(upper_pair(DVec3::ZERO, DVec3::Z).is_none());
        let tiny = DVec3::new(1e-200, 0.0, 1e-200);
        let (t, _) = upper_pair(tiny, DVec3::Z).unwrap();
        assert!((t - DVec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-15);
    }

    /// Directions as renderers pass them — unit in f32, rounded and renormalized there, and
    /// anything within [`NEAR_UNIT_L2`] — come out of [`near_unit`] (and so of [`unit()`] and
    /// [`upper_pair`]) as unit as [`normalize`] makes them (within 2⁻⁴⁰ in squared length) and
    /// within 1e-12 of `normalize`'s direction: ¾δ² ≤ ¾ · 2⁻⁴⁰ by the Newton step's error.
    #[test]
    fn near_unit_directions_are_corrected_as_normalize_corrects_them() {
        let mut rng = Pcg32::new(5);
        let mut corrected = 0;
        for k in 0..20_000 {
            let exact = uniform_sphere(rng.next_dvec2());
            let v = match k % 3 {
                0 => exact.as_vec3().as_dvec3(),
                1 => exact.as_vec3().normalize().as_dvec3(),
                // Anywhere in the band, to its edges.
                _ => exact * (1.0 + NEAR_UNIT_L2 * (rng.next_f64() - 0.5) * 0.999).sqrt(),
            };
            let l2 = v.length_squared();
            assert!(is_near_unit_l2(l2), "{v}: {l2}");
            let reference = normalize(v).unwrap();
            let u = unit(v).unwrap();
            assert!(
                is_unit_l2(u.length_squared()),
                "{v}: |u|² − 1 = {}",
                u.length_squared() - 1.0
            );
            assert!(
                (u - reference).length() < 1e-12,
                "{v}: {u} against {reference}"
            );
            if !is_unit_l2(l2) {
                corrected += 1;
                assert_eq!(u, near_unit(v, l2));
            }
            if let Some((a, b)) = upper_pair(v, DVec3::new(0.0, 0.6, 0.8)) {
                assert_eq!(a, u);
                assert_eq!(b, DVec3::new(0.0, 0.6, 0.8));
            }
        }
        assert!(corrected > 10_000, "{corrected} inputs needed a correction");
        // Outside the band: normalized as before.
        let far = DVec3::new(0.0, 0.0, 1.0 + 2.0 * NEAR_UNIT_L2);
        assert!(!is_near_unit_l2(far.length_squared()));
        assert_eq!(unit(far), Some(DVec3::Z));
    }

    #[test]
    fn is_upper_agrees_with_normalize() {
        let cases = [
            DVec3::Z,
            DVec3::new(3.0, -4.0, 0.1),
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(f64::NAN, 0.0, 1.0),
            DVec3::new(0.0, f64::INFINITY, 1.0),
            DVec3::new(0.0, 0.0, f64::INFINITY),
            DVec3::ZERO,
            // Finite and nonzero whatever their squared lengths: directions.
            DVec3::new(1e-300, 0.0, 1e-300),
            DVec3::new(0.0, 0.0, f64::from_bits(1)),
            DVec3::new(1e300, -1e300, 1e300),
            DVec3::new(0.0, 0.0, -f64::MAX),
        ];
        for v in cases {
            assert_eq!(is_upper(v), normalize(v).is_some_and(|w| w.z > 0.0), "{v}");
        }
    }

    #[test]
    fn half_diff_round_trip() {
        let mut rng = Pcg32::new(7);
        for _ in 0..10_000 {
            let wi = uniform_hemisphere(rng.next_dvec2());
            let wo = uniform_hemisphere(rng.next_dvec2());
            let hd = to_half_diff(wi, wo).unwrap();
            let (a, b) = from_half_diff(hd);
            assert!((a - wi).length() < 1e-9, "{wi} {a}");
            assert!((b - wo).length() < 1e-9, "{wo} {b}");
        }
    }

    #[test]
    fn half_diff_of_specular_pair_has_theta_h_zero() {
        let wi = spherical(0.7, 0.3);
        let hd = to_half_diff(wi, reflect_z(wi)).unwrap();
        assert!(hd.theta_h.abs() < 1e-7);
        assert!((hd.theta_d - 0.7).abs() < 1e-9);
    }

    #[test]
    fn reciprocity_is_phi_d_plus_pi() {
        let mut rng = Pcg32::new(3);
        for _ in 0..1000 {
            let wi = uniform_hemisphere(rng.next_dvec2());
            let wo = uniform_hemisphere(rng.next_dvec2());
            let a = to_half_diff(wi, wo).unwrap();
            let b = to_half_diff(wo, wi).unwrap();
            assert!((a.theta_h - b.theta_h).abs() < 1e-9);
            assert!((a.theta_d - b.theta_d).abs() < 1e-9);
            let dphi = (a.phi_d - b.phi_d).rem_euclid(2.0 * PI);
            assert!((dphi - PI).abs() < 1e-7, "{dphi}");
        }
    }

    #[test]
    fn frame_is_orthonormal() {
        let mut rng = Pcg32::new(1);
        for _ in 0..1000 {
            let n = uniform_sphere(rng.next_dvec2());
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-12);
            assert!((f.t.length() - 1.0).abs() < 1e-12);
            assert!(f.s.dot(f.t).abs() < 1e-12 && f.s.dot(n).abs() < 1e-12);
            let v = uniform_sphere(rng.next_dvec2());
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-12);
        }
    }

    #[test]
    fn unit_keeps_unit_vectors_and_normalizes_the_rest() {
        let v = spherical(0.7, 2.0);
        assert_eq!(unit(v), Some(v));
        let w = unit(3.0 * v).unwrap();
        assert!((w.length() - 1.0).abs() < 1e-15 && (w - v).length() < 1e-15);
        let near = v * (1.0 + 1e-9);
        assert!((unit(near).unwrap().length() - 1.0).abs() < 1e-15);
        assert!(unit(DVec3::ZERO).is_none());
        assert!(unit(DVec3::new(f64::NAN, 0.0, 1.0)).is_none());
        assert!(unit(DVec3::new(f64::INFINITY, 0.0, 1.0)).is_none());
    }

    #[test]
    fn a_direction_of_any_finite_nonzero_length_normalizes() {
        // Squared lengths that underflow to 0 or a subnormal (which lost bits: 4e-7 off at
        // 1e-160) or overflow to ∞ used to give None.
        let v = DVec3::new(0.3, -0.2, 0.9);
        let want = v / v.length();
        for k in [1e-300, 1e-160, 1e-154, 1e154, 1e160, 1e300, f64::MAX] {
            let w = normalize(v * k).unwrap_or_else(|| panic!("{k:e}"));
            assert!((w - want).length() < 1e-15, "{k:e}: {w}");
            assert_eq!(unit(v * k), Some(w), "{k:e}");
            let p = upper_pair(v * k, want).unwrap_or_else(|| panic!("{k:e}"));
            assert!((p.0 - want).length() < 1e-15, "{k:e}");
        }
        // A subnormal component beside a normal one is kept as it is.
        assert_eq!(
            normalize(DVec3::new(5e-324, 0.0, 1.0)),
            Some(DVec3::new(5e-324, 0.0, 1.0))
        );
    }

    #[test]
    fn invalid_directions_are_rejected() {
        assert!(normalize(DVec3::ZERO).is_none());
        assert!(normalize(DVec3::new(f64::NAN, 0.0, 1.0)).is_none());
        assert!(upper_pair(DVec3::Z, DVec3::new(0.0, 1.0, -0.1)).is_none());
    }
}
