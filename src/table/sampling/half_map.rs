//! The map of the unit square onto half vectors that every table sampler draws through:
//! s → θh, quadratic with a small linear part so the density stays finite at the mirror
//! direction; y → φh; its Jacobian and inverse (see the parent module's docs).

use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

use crate::fastmath;

/// Share of the θh map that is linear in s: θh = (π/2)(a s + (1 − a) s²), a = `HALF_MAP_LINEAR`.
/// The quadratic part puts the nodes close together at the pole (the RGL format's u(θ) = √(2θ/π)
/// is the pure quadratic); the linear part keeps dθh/ds > 0 there, so that the Jacobian
/// vanishes like s at the pole, as the bilinear density does — with the pure quadratic it
/// vanishes like s³ and the density of `wi` would be infinite at the mirror direction.
/// 0.02 rather than the 0.1 of sessions 9–26: the first cell narrows from 0.16° to 0.05°, so a
/// sharp peak spreads over more of them — GGX α = 0.002's weights' CV went from 0.85 to 0.18 on
/// 64 θh nodes and cg_sunflower's from 0.045–0.073 to 0.039–0.062 over views 3–75°, GGX
/// α = 0.05 unchanged (0.024–0.036); the outer cells barely change (2.7° → 2.8°).
pub const HALF_MAP_LINEAR: f64 = 0.02;
pub(super) const LINEAR: f64 = HALF_MAP_LINEAR;

/// θh of the square's first coordinate s.
#[inline]
pub(super) fn theta_of_s(s: f64) -> f64 {
    FRAC_PI_2 * s * (LINEAR + (1.0 - LINEAR) * s)
}

/// s of θh (inverse of [`theta_of_s`]): the positive root of (1 − a) s² + a s − 2θh/π = 0.
#[inline]
pub(super) fn s_of_theta(theta: f64) -> f64 {
    let q = theta / FRAC_PI_2;
    // 2q / (a + √(a² + 4(1 − a) q)): the root without cancellation.
    let s = 2.0 * q / (LINEAR + (LINEAR * LINEAR + 4.0 * (1.0 - LINEAR) * q).sqrt());
    s.clamp(0.0, 1.0)
}

/// Below this s the density of `wi` is the pole's (`TableSampler::pole_density`): at the
/// pole (h on the normal, wi the mirror direction of wo) the square's density and the Jacobian
/// both vanish like s, so their quotient is 0/0 there, while its limit along any y is finite
/// and reached to ~1e-9 at this s.
pub(super) const POLE_S: f64 = 1e-9;

/// |dωi / d(s, y)| / (4 (wo·h)) = sin θh · dθh/ds · dφh/dy.
#[inline]
pub(super) fn half_jacobian(s: f64, sin_th: f64) -> f64 {
    sin_th * FRAC_PI_2 * (LINEAR + 2.0 * (1.0 - LINEAR) * s) * TAU
}

/// The half vector of square point `u` = (s, y) in the frame of the nodes, with sin θh.
#[inline]
pub(super) fn half_of(u: [f64; 2]) -> (DVec3, f64) {
    let (st, ct) = fastmath::sin_cos_2pi(theta_of_s(u[0]) * (1.0 / TAU));
    // φh = 2π y − π: (sin, cos) of 2π y, negated.
    let (sp, cp) = fastmath::sin_cos_2pi(u[1]);
    (DVec3::new(-st * cp, -st * sp, ct), st)
}

/// The square point (s, y) of a half vector `h` of any positive length with h.z > 0 (inverse of
/// [`half_of`]): θh and φh are ratios of its components ([`fastmath::atan2`], no
/// normalization).
#[inline]
pub(super) fn square_of(h: DVec3) -> [f64; 2] {
    let rho = (h.x * h.x + h.y * h.y).sqrt();
    let s = s_of_theta(fastmath::atan2(rho, h.z));
    let y = (fastmath::atan2(h.y, h.x) + PI) * (1.0 / TAU);
    // atan2 ∈ [−π, π]: y ∈ [0, 1], and 1 is 0.
    [s, if y >= 1.0 { y - 1.0 } else { y }]
}
