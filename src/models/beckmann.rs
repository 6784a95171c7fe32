//! The Beckmann distribution of microfacet normals, normalized.
//!
//! The lecture writes Pr(H) = exp(−tan² α / m²) / (m² cos² α) (up to a constant), where α is the
//! angle between the facet normal H and N and m the RMS slope. As a *density of normals per solid
//! angle* (the D of microfacet theory) it needs the projected-area normalization
//! ∫ D(H) cos α dω_H = 1, which gives
//!
//! ```text
//! D(α) = exp(−tan² α / m²) / (π m² cos⁴ α).
//! ```
//!
//! D cos α is then a probability density over the hemisphere and can be sampled exactly:
//! tan² α = −m² ln(1 − u₁), φ = 2π u₂ (inverting the CDF 1 − exp(−tan² α / m²)).

use glam::{DVec2, DVec3};
use std::f64::consts::PI;

/// Beckmann normal distribution with RMS slope `m` (> 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beckmann {
    /// RMS slope m.
    pub m: f64,
    inv_m2: f64,
    inv_pi_m2: f64,
}

impl Beckmann {
    /// The distribution for roughness `m` (finite, > 0; the caller validates).
    pub fn new(m: f64) -> Self {
        let m2 = m * m;
        Beckmann {
            m,
            inv_m2: 1.0 / m2,
            inv_pi_m2: 1.0 / (PI * m2),
        }
    }

    /// 1 / m².
    #[inline]
    pub fn inv_m2(&self) -> f64 {
        self.inv_m2
    }

    /// 1 / (π m²).
    #[inline]
    pub fn inv_pi_m2(&self) -> f64 {
        self.inv_pi_m2
    }

    /// D for a facet normal with cos α = `cos_a` (N·H); 0 for cos α ≤ 0.
    #[inline]
    pub fn d(&self, cos_a: f64) -> f64 {
        if cos_a.is_nan() || cos_a <= 0.0 {
            return 0.0;
        }
        let c2 = cos_a * cos_a;
        let tan2 = (1.0 - c2) / c2;
        let e = (-tan2 * self.inv_m2).exp();
        if e == 0.0 {
            // exp underflows long before c2² does (cos α ~ 1e-77): D = 0 there, not 0/0.
            return 0.0;
        }
        e * self.inv_pi_m2 / (c2 * c2)
    }

    /// D for a facet normal with tan² α = `tan2` (≥ 0):
    /// exp(−tan² α/m²) (1 + tan² α)² / (π m²), without the cancellation of 1 − cos² α that
    /// [`Beckmann::d`] has where tan² α is below ~1e-16 relative to 1 (a lobe of m ≲ 1e-7);
    /// 0 where exp underflows (and for NaN).
    #[inline]
    pub fn d_tan2(&self, tan2: f64) -> f64 {
        let x = tan2 * self.inv_m2;
        if !(x < 745.0) {
            // exp(−x) is 0 (the factor (1 + tan²)² may be infinite: not 0 · ∞).
            return 0.0;
        }
        let inv_c2 = 1.0 + tan2;
        (-x).exp() * self.inv_pi_m2 * (inv_c2 * inv_c2)
    }

    /// A facet normal drawn with density D(H) cos α (per solid angle of H) from `u` in [0,1)².
    #[inline]
    pub fn sample_h(&self, u: DVec2) -> DVec3 {
        self.sample_h_d(u).0
    }

    /// [`Beckmann::sample_h`] together with D(H) at the drawn normal, for free: the inversion
    /// sets exp(−tan² α / m²) = 1 − u₁, so D = (1 − u₁) / (π m² cos⁴ α) needs no `exp`.
    #[inline]
    pub fn sample_h_d(&self, u: DVec2) -> (DVec3, f64) {
        let one_minus = 1.0 - u.x;
        let tan2 = (-self.m * self.m * crate::fastmath::ln(one_minus)).max(0.0);
        // 1/cos² α = 1 + tan² α; cos α = 1/√(1 + tan²), sin α = tan α · cos α (two independent
        // roots, one division).
        let inv_c2 = 1.0 + tan2;
        let cos_a = 1.0 / inv_c2.sqrt();
        let sin_a = tan2.sqrt() * cos_a;
        let (s, c) = crate::fastmath::sin_cos_2pi(u.y);
        let d = one_minus * self.inv_pi_m2 * (inv_c2 * inv_c2);
        (DVec3::new(sin_a * c, sin_a * s, cos_a), d)
    }

    /// [`Beckmann::sample_h_d`] without normalizing the normal: returns the slope-space
    /// vector h′ = (tan α cos φ, tan α sin φ, 1) = H / cos α, |h′|² = 1 + tan² α = 1/cos² α,
    /// cos² α = 1/|h′|², and D(H). Samplers that only need ratios of dot products with H can use
    /// h′ directly and skip the square root and division that normalizing costs on their critical
    /// path (cos² α is a division, but one that runs alongside the square root for tan α).
    #[inline]
    pub fn sample_slope_d(&self, u: DVec2) -> (DVec3, f64, f64) {
        self.slope_d(1.0 - u.x, u.y)
    }

    /// [`Beckmann::sample_slope_d`] from 1 − u.x (which callers that rescale u.x can compute
    /// directly) and u.y.
    #[inline]
    pub(crate) fn slope_d(&self, one_minus: f64, uy: f64) -> (DVec3, f64, f64) {
        let tan2 = (-self.m * self.m * crate::fastmath::ln(one_minus)).max(0.0);
        let inv_c2 = 1.0 + tan2;
        let cos2 = 1.0 / inv_c2;
        let tan_a = tan2.sqrt();
        let (s, c) = crate::fastmath::sin_cos_2pi(uy);
        let d = one_minus * self.inv_pi_m2 * (inv_c2 * inv_c2);
        (DVec3::new(tan_a * c, tan_a * s, 1.0), cos2, d)
    }

    /// The density of [`Beckmann::sample_h`]: D(H) cos α.
    #[inline]
    pub fn pdf_h(&self, h: DVec3) -> f64 {
        self.d(h.z) * h.z.max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::albedo::gauss_legendre;

    /// ∫ D cos α dω = 2π ∫₀¹ D(μ) μ dμ, by Gauss-Legendre in μ = cos α on sub-intervals
    /// (D is sharply peaked near μ = 1 for small m).
    fn projected_integral(b: &Beckmann) -> f64 {
        let (x, w) = gauss_legendre(64);
        let pieces = 200;
        let mut sum = 0.0;
        for p in 0..pieces {
            // Finer pieces towards μ = 1: μ = 1 − s², s uniform.
            let s0 = p as f64 / pieces as f64;
            let s1 = (p + 1) as f64 / pieces as f64;
            for (xi, wi) in x.iter().zip(&w) {
                let s = s0 + (s1 - s0) * 0.5 * (xi + 1.0);
                let ds = (s1 - s0) * 0.5 * wi;
                let mu = 1.0 - s * s;
                sum += b.d(mu) * mu * 2.0 * s * ds;
            }
        }
        2.0 * PI * sum
    }

    #[test]
    fn slope_space_sample_is_the_normal_divided_by_its_cosine() {
        let b = Beckmann::new(0.35);
        let mut rng = crate::rng::Pcg32::new(5);
        for _ in 0..5000 {
            let u = rng.next_dvec2();
            let (h, d) = b.sample_h_d(u);
            let (hp, cos2, d2) = b.sample_slope_d(u);
            assert_eq!(hp.z, 1.0);
            assert!((hp * h.z - h).length() < 1e-14, "{hp} {h}");
            assert!((cos2 - h.z * h.z).abs() < 1e-15);
            assert!((cos2 * hp.length_squared() - 1.0).abs() < 1e-14);
            assert!((d2 - d).abs() <= 1e-14 * d);
            assert!((d - b.d(h.z)).abs() <= 1e-9 * d);
        }
    }

    #[test]
    fn normalized_projected_area_is_one() {
        for m in [0.05, 0.1, 0.3, 0.6, 1.0, 2.0] {
            let i = projected_integral(&Beckmann::new(m));
            assert!((i - 1.0).abs() < 1e-9, "m={m}: ∫ D cos = {i}");
        }
    }

    #[test]
    fn lecture_shape_up_to_constant() {
        // D / (lecture's Pr(H)) = 1 / (π cos² α): the same exp(−tan²/m²) shape.
        let b = Beckmann::new(0.3);
        for a in [0.0f64, 0.2, 0.5, 1.0] {
            let c = a.cos();
            let lecture = (-(a.tan().powi(2)) / 0.09).exp() / (0.09 * c * c);
            assert!((b.d(c) - lecture / (PI * c * c)).abs() < 1e-12 * lecture.max(1.0));
        }
        assert_eq!(b.d(0.0), 0.0);
        assert_eq!(b.d(-0.5), 0.0);
        assert_eq!(b.d(f64::NAN), 0.0);
    }
    /// D from tan² α is D from cos α where the latter is well conditioned, keeps a lobe far
    /// narrower than 1e-8 (where 1 − cos² α is rounding), and is 0 rather than 0 · ∞ where the
    /// exponential underflows and (1 + tan² α)² overflows.
    #[test]
    fn d_of_tan2_agrees_with_d_and_resolves_narrow_lobes() {
        let b = Beckmann::new(0.3);
        for a in [0.0f64, 0.2, 0.5, 1.0, 1.5] {
            let (c, t) = (a.cos(), a.tan());
            assert!((b.d_tan2(t * t) - b.d(c)).abs() <= 1e-12 * b.d(c), "{a}");
        }
        let m = 1e-10;
        let narrow = Beckmann::new(m);
        // tan α = m: D = e⁻¹ (1 + m²)² / (π m²), which `d` cannot see (cos² α = 1 − 1e-20).
        let expect = (-1.0f64).exp() / (PI * m * m);
        assert!((narrow.d_tan2(m * m) / expect - 1.0).abs() < 1e-15);
        assert_eq!(narrow.d(m.atan().cos()), 1.0 / (PI * m * m));
        for t2 in [1e300, f64::INFINITY, f64::NAN] {
            assert_eq!(narrow.d_tan2(t2), 0.0, "{t2}");
            assert_eq!(b.d_tan2(t2), 0.0, "{t2}");
        }
    }
}
