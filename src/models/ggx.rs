//! GGX / Trowbridge-Reitz microfacet reflection with Smith height-correlated masking-shadowing.
//!
//! With h = normalize(wi + wo), the local tangent x as the α_x direction, and unit directions:
//!
//! ```text
//! D(h)   = 1 / (π α_x α_y cos⁴θh (1 + tan²θh (cos²φh/α_x² + sin²φh/α_y²))²)
//!        = 1 / (π α_x α_y (h_x²/α_x² + h_y²/α_y² + h_z²)²)
//! Λ(w)   = (√(1 + (α_x² w_x² + α_y² w_y²)/w_z²) − 1) / 2
//! G1(w)  = 1 / (1 + Λ(w))
//! G2     = 1 / (1 + Λ(wi) + Λ(wo))                    (height-correlated Smith)
//! f_r    = k_s D(h) G2 F(wi·h) / (4 cos θi cos θo)
//! ```
//!
//! (Walter et al. 2007, "Microfacet models for refraction through rough surfaces"; Heitz 2014,
//! "Understanding the masking-shadowing function in microfacet-based BRDFs".) D is normalized so
//! that ∫ D(h) cos θh dω_h = 1. F is any [`Fresnel`] term, evaluated at wi·h (= wo·h).
//!
//! The model is reciprocal and bilaterally symmetric (D and Λ depend on h_y², w_y² only); it is
//! isotropic exactly when α_x = α_y.
//!
//! # Sampling
//!
//! [`Brdf::sample`] draws visible normals (Heitz 2018, "Sampling the GGX distribution of visible
//! normals", by the spherical-cap construction of Dupuy & Benyoub 2023): h with density D_wo(h) = G1(wo) max(0, wo·h) D(h) / cos θo, reflected about h. The
//! Jacobian 1/(4 wo·h) gives
//!
//! ```text
//! pdf(wi | wo) = G1(wo) D(h) / (4 cos θo),     weight = k_s F(wo·h) G2 / G1(wo) ≤ k_s.
//! ```
//!
//! [`Ggx::sample_half_vector`] draws h from D(h) cos θh instead (the classic method: a GGX slope
//! drawn from the stretched unit distribution), with [`Ggx::pdf_half_vector`] its density; it
//! is kept for comparison and for callers that need the plain NDF sampler.

use glam::{DVec2, DVec3};
use std::f64::consts::PI;

use crate::brdf::{Brdf, BrdfSample, Flags};
use crate::error::{Error, Result};
use crate::fresnel::{Fresnel, FresnelSpec};
use crate::geometry;
use crate::spectrum::{Channels, Value};

/// GGX microfacet BRDF, isotropic or anisotropic (α_x along the local x axis).
#[derive(Debug, Clone)]
pub struct Ggx {
    channels: Channels,
    alpha_x: f64,
    alpha_y: f64,
    /// (1/α_x, 1/α_y) and 1/(π α_x α_y), so that D needs one division.
    inv_alpha: (f64, f64),
    inv_pi_axay: f64,
    ks_spec: Value,
    ks: Vec<f64>,
    fresnel_spec: FresnelSpec,
    fresnel: Fresnel,
}

impl Ggx {
    /// An isotropic GGX model with roughness `alpha` > 0.
    pub fn isotropic(
        alpha: f64,
        ks: Value,
        fresnel: FresnelSpec,
        channels: &Channels,
    ) -> Result<Self> {
        Self::new(alpha, alpha, ks, fresnel, channels)
    }

    /// A GGX model with roughness `alpha_x` along the local x axis and `alpha_y` along y (both
    /// > 0), scale `ks` and Fresnel term `fresnel`.
    pub fn new(
        alpha_x: f64,
        alpha_y: f64,
        ks: Value,
        fresnel: FresnelSpec,
        channels: &Channels,
    ) -> Result<Self> {
        channels.validate()?;
        for (name, a) in [("alpha_x", alpha_x), ("alpha_y", alpha_y)] {
            if !(a.is_finite() && a > 0.0) {
                return Err(Error::spec(
                    name,
                    format!("{a} must be a finite number > 0"),
                ));
            }
            crate::spectrum::check_range(a, name)?;
        }
        ks.validate("ks", 0.0)?;
        Ok(Ggx {
            channels: channels.clone(),
            alpha_x,
            alpha_y,
            inv_alpha: (1.0 / alpha_x, 1.0 / alpha_y),
            inv_pi_axay: 1.0 / (PI * alpha_x * alpha_y),
            ks: ks.resolve(channels),
            ks_spec: ks,
            fresnel: Fresnel::new(&fresnel, channels, "fresnel")?,
            fresnel_spec: fresnel,
        })
    }

    /// (α_x, α_y).
    pub fn alpha(&self) -> (f64, f64) {
        (self.alpha_x, self.alpha_y)
    }

    /// The normal distribution D(h) for a unit `h` (0 below the horizon).
    #[inline]
    pub fn ndf(&self, h: DVec3) -> f64 {
        if h.z.is_nan() || h.z <= 0.0 {
            return 0.0;
        }
        let (x, y) = (h.x * self.inv_alpha.0, h.y * self.inv_alpha.1);
        let e = x * x + y * y + h.z * h.z;
        self.inv_pi_axay / (e * e)
    }

    /// Smith's Λ(w) for a unit `w` above the horizon.
    #[inline]
    pub fn lambda(&self, w: DVec3) -> f64 {
        // Λ = (√(1 + α²tan²θ) − 1)/2 = (r − w_z)/(2 w_z) with s² = (α_x w_x)² + (α_y w_y)² and
        // r = √(w_z² + s²), written without cancellation (and with one root, one division) as
        // s² / (2 w_z (r + w_z)).
        let (s2, q) = self.lambda_parts(w);
        s2 / q
    }

    /// Λ(w) as the quotient s² / q, s² = (α_x w_x)² + (α_y w_y)², q = 2 w_z (√(w_z² + s²) + w_z),
    /// for callers that combine several Λ under one division.
    #[inline]
    fn lambda_parts(&self, w: DVec3) -> (f64, f64) {
        let s2 = (self.alpha_x * w.x).powi(2) + (self.alpha_y * w.y).powi(2);
        let r = (w.z * w.z + s2).sqrt();
        (s2, 2.0 * w.z * (r + w.z))
    }

    /// D(h/|h|) of a tiny unnormalized `h`, scaled to a largest component of 1 first; out of
    /// line, so that the common path does not compute it as a select.
    #[cold]
    #[inline(never)]
    fn ndf_scaled(&self, h: DVec3) -> f64 {
        let hs = h / h.abs().max_element();
        let (x, y) = (hs.x * self.inv_alpha.0, hs.y * self.inv_alpha.1);
        let t = hs.length_squared() / (x * x + y * y + hs.z * hs.z);
        self.inv_pi_axay * (t * t)
    }

    /// Λ(w)'s parts with the cosine taken out of q: (s², q / w_z = 2 (√(w_z² + s²) + w_z)).
    #[inline]
    fn lambda_parts_per_cos(&self, w: DVec3) -> (f64, f64) {
        let s2 = (self.alpha_x * w.x).powi(2) + (self.alpha_y * w.y).powi(2);
        let r = (w.z * w.z + s2).sqrt();
        (s2, 2.0 * (r + w.z))
    }

    /// Smith's masking G1(w) = 1 / (1 + Λ(w)) (0 below the horizon).
    #[inline]
    pub fn g1(&self, w: DVec3) -> f64 {
        if w.z.is_nan() || w.z <= 0.0 {
            return 0.0;
        }
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing G2 = 1 / (1 + Λ(wi) + Λ(wo)) for unit directions
    /// above the horizon.
    #[inline]
    pub fn g2(&self, wi: DVec3, wo: DVec3) -> f64 {
        1.0 / (1.0 + self.lambda(wi) + self.lambda(wo))
    }

    /// D G2 / (4 cos θi cos θo), wi·h and the sampling density G1(wo) D / (4 cos θo) of a pair
    /// (any lengths; `None` when invalid or below the horizon): one pass for `eval`, `pdf` and
    /// `eval_pdf`.
    ///
    /// Written with the half vector unnormalized, h = l + v for unit l, v: D(h/|h|) =
    /// |h|⁴ / (π α_x α_y e²) with e = (h_x/α_x)² + (h_y/α_y)² + h_z², l·h/|h| = |h|/2, and
    /// G2 = q_l q_v / (q_l q_v + s_l q_v + s_v q_l) from Λ = s/q ([`Ggx::lambda`]), so each
    /// output costs one division. Each q = w_z q′ carries its cosine, q′ = 2 (√(w_z² + s²) + w_z),
    /// which cancels against 4 cos θi cos θo, so a pair within 1e-100 of the horizon (f_r grows
    /// like 1/cos θ there) neither underflows to 0/0 nor loses its value. Every product is formed
    /// symmetrically in (l, v), so reciprocity holds bit for bit.
    #[inline(always)]
    fn lobe(&self, wi: DVec3, wo: DVec3) -> Option<Lobe> {
        let (l, v) = crate::geometry::upper_pair(wi, wo)?;
        let h = l + v;
        let hh = h.length_squared();
        let (x, y) = (h.x * self.inv_alpha.0, h.y * self.inv_alpha.1);
        let e = x * x + y * y + h.z * h.z;
        // D's |h|⁴/e² is scale-free; near the mirror configuration at grazing both |h|² and e
        // are ~4 cos², whose squares underflow below cos ~ 1e-77 (and they themselves below
        // ~1e-154): there take the ratio of h scaled to a largest component of 1.
        let (d_num, e2) = if e > TINY_E {
            (self.inv_pi_axay * (hh * hh), e * e)
        } else {
            (self.ndf_scaled(h), 1.0)
        };
        let (sl, pl) = self.lambda_parts_per_cos(l);
        let (sv, pv) = self.lambda_parts_per_cos(v);
        // G2 / (4 cos θi cos θo) = p_l p_v / (4 g), g = cos θi cos θo p_l p_v + s_l cos θo p_v
        // + s_v cos θi p_l (q = cos θ p).
        let g = (l.z * v.z) * (pl * pv) + (sl * (v.z * pv) + sv * (l.z * pl));
        Some(Lobe {
            // At subnormal cosines g underflows to 0 and f_r overflows (it grows like 1/cos θ):
            // held at f64::MAX, so that a Fresnel term or k_s of 0 gives 0 rather than 0·∞.
            dg: (d_num * (pl * pv) / (e2 * g * 4.0)).min(f64::MAX),
            l_dot_h: 0.5 * hh.sqrt(),
            pdf: d_num * pv / (e2 * (v.z * pv + sv) * 4.0),
        })
    }

    /// Draws a half vector with density D(h) cos θh ([`Ggx::pdf_half_vector`]): the slope of a
    /// unit-roughness isotropic GGX surface (|m|² = u₁/(1 − u₁), azimuth 2π u₂) stretched by
    /// (α_x, α_y).
    pub fn sample_half_vector(&self, u: DVec2) -> DVec3 {
        let r = (u.x / (1.0 - u.x)).sqrt();
        let (sp, cp) = crate::fastmath::sin_cos_2pi(u.y);
        let slope = DVec2::new(self.alpha_x * r * cp, self.alpha_y * r * sp);
        DVec3::new(-slope.x, -slope.y, 1.0).normalize()
    }

    /// The density D(h) cos θh of [`Ggx::sample_half_vector`] (solid angle).
    pub fn pdf_half_vector(&self, h: DVec3) -> f64 {
        self.ndf(h) * h.z.max(0.0)
    }

    /// Draws a microfacet normal visible from the unit direction `wo` (above the horizon) with
    /// density [`Ggx::pdf_visible_normal`].
    ///
    /// In the stretched configuration of unit roughness the visible normals are distributed like
    /// the points of a uniformly sampled spherical cap of directions c with c·z ≥ −v_z, offset
    /// by the stretched view direction v (Dupuy & Benyoub 2023, "Sampling visible GGX normals
    /// with spherical caps"): h ∝ c + v, then unstretched. The same density as Heitz's (2018)
    /// projected-disk construction, with three square roots and two divisions instead of five
    /// and three.
    #[inline]
    pub fn sample_visible_normal(&self, wo: DVec3, u: DVec2) -> DVec3 {
        self.visible_normal_unnormalized(wo, u).0.normalize()
    }

    /// The visible normal of [`Ggx::sample_visible_normal`] before its final normalization,
    /// g = (α_x h_x, α_y h_y, h_z) for the stretched-space normal h = c + v (times |s|, see
    /// below), together with |h|² (h_z clamped at 0). With n = g/|g|, the NDF's e = (n_x/α_x)² + (n_y/α_y)² + n_z²
    /// is |h|² / |g|², so callers get D without normalizing.
    #[inline]
    fn visible_normal_unnormalized(&self, wo: DVec3, u: DVec2) -> (DVec3, f64) {
        let (ax, ay) = (self.alpha_x, self.alpha_y);
        // The stretched view direction s, |s| = l, v = s/l. Everything below is scaled by l
        // (only the direction of g matters, and |h|²/|g|² is scale-free), which spares the
        // division that normalizing v would cost: l·z = (1 − u₁) l − u₁ s_z for z uniform on
        // the cap [−v_z, 1], l·sin θ = √(l² − (l z)²), and l·h = l·c + s.
        let s = DVec3::new(ax * wo.x, ay * wo.y, wo.z);
        let l2 = s.length_squared();
        let l = l2.sqrt();
        let lz = (1.0 - u.x) * l - u.x * s.z;
        let lsin = (l2 - lz * lz).max(0.0).sqrt();
        let (sp, cp) = crate::fastmath::sin_cos_2pi(u.y);
        let h = DVec3::new(lsin * cp + s.x, lsin * sp + s.y, (lz + s.z).max(0.0));
        (DVec3::new(ax * h.x, ay * h.y, h.z), h.length_squared())
    }

    /// The density of visible normals D_wo(h) = G1(wo) max(0, wo·h) D(h) / cos θo for unit `wo`
    /// above the horizon and unit `h`.
    pub fn pdf_visible_normal(&self, wo: DVec3, h: DVec3) -> f64 {
        if wo.z.is_nan() || wo.z <= 0.0 {
            return 0.0;
        }
        self.g1(wo) * wo.dot(h).max(0.0) * self.ndf(h) / wo.z
    }
}

/// Below this e (the NDF's quadratic form of the unnormalized half vector, ~4 cos² θ at the
/// mirror configuration) [`Ggx::lobe`] forms D from |h|²/e rather than |h|⁴ and e² apart.
const TINY_E: f64 = 1e-100;

/// What [`Ggx::lobe`] computes for a pair.
struct Lobe {
    /// D G2 / (4 cos θi cos θo).
    dg: f64,
    /// wi·h, the Fresnel cosine.
    l_dot_h: f64,
    /// G1(wo) D / (4 cos θo), the density of visible-normal sampling.
    pdf: f64,
}

impl Brdf for Ggx {
    fn channels(&self) -> &Channels {
        &self.channels
    }

    #[inline]
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let out = &mut out[..self.ks.len()];
        let Some(lobe) = self.lobe(wi, wo) else {
            out.fill(0.0);
            return;
        };
        // k_s · D G2 / (4 cos θi cos θo) · F per channel; RGB conductors run as packed lanes.
        self.fresnel
            .eval_scaled(lobe.l_dot_h, &self.ks, lobe.dg, out);
    }

    /// One pass of the shared lobe gives f and the visible-normal density.
    fn eval_pdf(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) -> f64 {
        let out = &mut out[..self.ks.len()];
        let Some(lobe) = self.lobe(wi, wo) else {
            out.fill(0.0);
            return 0.0;
        };
        self.fresnel
            .eval_scaled(lobe.l_dot_h, &self.ks, lobe.dg, out);
        lobe.pdf
    }

    fn eval_wavelength(&self, wi: DVec3, wo: DVec3, nm: f64) -> f64 {
        if !crate::spectrum::is_wavelength(nm) {
            return f64::NAN; // not a wavelength: no value (Channels::mix_at)
        }
        match self.lobe(wi, wo) {
            Some(lobe) => self.ks_spec.at(nm) * lobe.dg * self.fresnel.eval_at(lobe.l_dot_h, nm),
            None => 0.0,
        }
    }

    fn flags(&self) -> Flags {
        Flags {
            isotropic: self.alpha_x == self.alpha_y,
            ..Flags::SMOOTH_SYMMETRIC
        }
    }

    fn describe(&self) -> String {
        let alpha = if self.alpha_x == self.alpha_y {
            format!("alpha={}", self.alpha_x)
        } else {
            format!("alpha_x={} alpha_y={}", self.alpha_x, self.alpha_y)
        };
        format!(
            "ggx {alpha} ks={} fresnel={}",
            serde_json::to_string(&self.ks_spec).unwrap_or_default(),
            serde_json::to_string(&self.fresnel_spec).unwrap_or_default()
        )
    }

    fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
        let wo = geometry::unit(wo)?;
        if wo.z <= 0.0 || !geometry::in_unit_square(u) {
            return None;
        }
        // The reflection about n = g/|g| needs only 1/|g|² (wi = 2 (wo·g)/|g|² g − wo, unit to
        // rounding); the square root for wo·n runs beside it, off the critical path.
        let (g, hh) = self.visible_normal_unnormalized(wo, u);
        let gg = g.length_squared();
        let wo_g = wo.dot(g);
        if !(wo_g > 0.0 && gg > 0.0) {
            return None;
        }
        let inv_gg = 1.0 / gg;
        let wi = (2.0 * wo_g * inv_gg) * g - wo;
        if wi.z.is_nan() || wi.z <= 0.0 {
            return None;
        }
        // Λ = s²/q for both directions (see `lambda_parts`), so that pdf and weight each take
        // one division:
        // pdf = D / (4 cos θo (1 + Λo)) = q_o / (π α_x α_y e² · 4 cos θo (q_o + s_o²)),
        // f cos θi / pdf = k_s F G2 / G1(wo) = k_s F (1 + Λo) / (1 + Λi + Λo)
        //                = k_s F (q_o + s_o²) q_i / (q_i q_o + s_i² q_o + s_o² q_i).
        // q_o = cos θo p_o: the cosine cancels in the pdf. Formed as q_o / cos θo it left
        // |h|⁴ · 4 cos θo, which at a grazing view and a small α (|h|² ~ α², cos θo 1e-300) is
        // subnormal: the pdf was 50 % off pdf(wi, wo) there.
        let (s2o, po) = self.lambda_parts_per_cos(wo);
        let qo = wo.z * po;
        let (s2i, qi) = self.lambda_parts(wi);
        // e = |h|²/|g|² (see `visible_normal_unnormalized`).
        let pdf = self.inv_pi_axay * po * (gg * gg) / (hh * hh * 4.0 * (qo + s2o));
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let ratio = (qo + s2o) * qi / (qi * qo + s2i * qo + s2o * qi);
        // Fresnel at wo·n = (wo·g)/|g|, from wo·g and |g|² directly (no 1/|g|² on its path).
        self.fresnel
            .eval_scaled_dot(wo_g, gg, &self.ks, ratio, &mut weight[..self.ks.len()]);
        Some(BrdfSample {
            wi,
            pdf,
            delta: false,
        })
    }

    /// The quadrature's albedo, or where the lobe is far narrower than any quadrature resolves
    /// (max(α_x, α_y) < 1e-6) and than the light's height above the horizon (< 1e-3 cos θi),
    /// its α → 0 limit k_s F(cos θi): D tends to δ(h − n), where wi·h = cos θi and G2 / G1 → 1
    /// (corrections of order (α tan θi)²). There the quadrature, whose directions cannot resolve
    /// a lobe ~α cos θi across, read up to 27.8 (α = 1e-12, cos θi = 1e-6) and ∞ (cos θi = 1e-9)
    /// where the sampler's weights, all k_s F, average to 1.
    fn albedo(&self, wi: DVec3, out: &mut [f64]) {
        let cos = geometry::normalize(wi).map_or(0.0, |w| w.z);
        let alpha = self.alpha_x.max(self.alpha_y);
        if alpha < 1e-6 && alpha < 1e-3 * cos {
            for (c, o) in out[..self.ks.len()].iter_mut().enumerate() {
                *o = self.ks[c] * self.fresnel.eval(cos, c);
            }
            return;
        }
        crate::analysis::albedo::quadrature(self, wi, out)
    }

    /// The visible-normal density G1(wo) D(h) / (4 cos θo).
    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.lobe(wi, wo).map_or(0.0, |l| l.pdf)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::albedo::gauss_legendre;
    use crate::models::test_util::*;
    use crate::rng::Pcg32;
    use proptest::prelude::*;

    fn iso(alpha: f64) -> Ggx {
        Ggx::isotropic(alpha, Value::Grey(1.0), FresnelSpec::None, &Channels::Rgb).unwrap()
    }

    fn aniso(ax: f64, ay: f64) -> Ggx {
        Ggx::new(ax, ay, Value::Grey(1.0), FresnelSpec::None, &Channels::Rgb).unwrap()
    }

    fn conductor() -> FresnelSpec {
        FresnelSpec::Complex {
            n: Value::Rgb([0.2, 0.9, 1.1]),
            k: Value::Rgb([3.9, 2.4, 2.2]),
        }
    }

    /// A lobe far narrower than the quadrature resolves, seen near the horizon: the albedo read
    /// 2.81 (α = 1e-12, cos θi = 1e-5), 27.8 (1e-6) and ∞ (1e-9); its limit is k_s F(cos θi),
    /// to (α tan θi)² ≤ 1e-6, which the sampler's mean weight confirms.
    #[test]
    fn albedo_of_a_near_mirror_at_grazing_is_its_limit() {
        let fresnel = conductor();
        let m = Ggx::new(
            1e-12,
            1e-12,
            Value::Grey(0.8),
            fresnel.clone(),
            &Channels::Rgb,
        )
        .unwrap();
        let f = Fresnel::new(&fresnel, &Channels::Rgb, "fresnel").unwrap();
        for cos in [1e-2f64, 1e-5, 1e-6, 1e-7, 1e-9] {
            let wi = DVec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
            let mut a = [0.0; 3];
            m.albedo(wi, &mut a);
            for (c, &x) in a.iter().enumerate() {
                let want = 0.8 * f.eval(cos, c);
                assert!(
                    (x - want).abs() <= 1e-6 * want,
                    "cos {cos:e} channel {c}: {x} vs {want}"
                );
            }
            let mut rng = Pcg32::new(7);
            let mut w = [0.0f32; 3];
            for _ in 0..64 {
                if m.sample(wi, rng.next_dvec2(), &mut w).is_some() {
                    assert!((w[0] as f64 - 0.8 * f.eval(cos, 0)).abs() < 1e-6, "{w:?}");
                }
            }
        }
    }

    #[test]
    fn ndf_is_normalized() {
        for (ax, ay) in [
            (0.01, 0.01),
            (0.1, 0.1),
            (0.5, 0.5),
            (1.0, 1.0),
            (0.05, 0.4),
            (0.8, 0.2),
        ] {
            let m = aniso(ax, ay);
            let nphi = if ax == ay { 1 } else { 256 };
            let width = ax.min(ay);
            let integral = integrate_hemisphere(|h| m.ndf(h) * h.z, width, nphi, 32);
            // The anisotropic φ integrand is smooth and periodic: the midpoint rule converges
            // geometrically, so both cases reach quadrature accuracy.
            assert!(
                (integral - 1.0).abs() < 1e-7,
                "α = ({ax}, {ay}): ∫ D cos = {integral}"
            );
        }
    }

    /// ∫ g(h) dω_h over the half vectors visible from `wo` (wo·h > 0): for each θh the arc of
    /// φh where wo·h > 0 is integrated by composite Gauss-Legendre (16 panels × 16 nodes), so
    /// the kink of max(0, wo·h) falls on panel ends and does not spoil the quadrature.
    fn integrate_visible(m: &Ggx, wo: DVec3, g: impl Fn(DVec3) -> f64) -> f64 {
        let (theta_o, phi_o) = geometry::to_spherical(wo);
        let (xt, wt_) = gauss_legendre(48);
        let (xp, wp) = gauss_legendre(16);
        let panels = 16;
        let (ax, ay) = m.alpha();
        let mut breaks = vec![0.0];
        let mut t = ax.min(ay) / 16.0;
        while t < std::f64::consts::FRAC_PI_2 {
            breaks.push(t);
            t *= 2.0;
        }
        breaks.push(std::f64::consts::FRAC_PI_2);
        let mut sum = 0.0;
        for seg in breaks.windows(2) {
            let (a, b) = (seg[0], seg[1]);
            for (xi, wi) in xt.iter().zip(&wt_) {
                let th = 0.5 * (a + b) + 0.5 * (b - a) * xi;
                let wt = 0.5 * (b - a) * wi * th.sin();
                // wo·h = sin θo sin θh cos(φ − φo) + cos θo cos θh > 0 on φo ± half.
                let c = -theta_o.cos() * th.cos() / (theta_o.sin() * th.sin()).max(1e-300);
                let half = if c <= -1.0 {
                    PI
                } else if c >= 1.0 {
                    0.0
                } else {
                    c.acos()
                };
                let width = 2.0 * half / panels as f64;
                for p in 0..panels {
                    let p0 = phi_o - half + p as f64 * width;
                    for (xj, wj) in xp.iter().zip(&wp) {
                        let phi = p0 + 0.5 * width * (xj + 1.0);
                        sum += wt * 0.5 * width * wj * g(geometry::spherical(th, phi));
                    }
                }
            }
        }
        sum
    }

    #[test]
    fn visible_normals_project_to_cos_theta_o() {
        // ∫ G1(wo) max(0, wo·h) D(h) dω_h = cos θo: the projected area of the visible microfacets
        // equals that of the geometric surface (Heitz 2014, eq. 2 with Smith's G1).
        for (ax, ay) in [(0.1, 0.1), (0.5, 0.5), (1.0, 1.0), (0.05, 0.4), (0.9, 0.3)] {
            let m = aniso(ax, ay);
            for wo in test_wos() {
                let lhs = integrate_visible(&m, wo, |h| m.g1(wo) * wo.dot(h).max(0.0) * m.ndf(h));
                assert!(
                    (lhs - wo.z).abs() < 1e-6 * wo.z.max(0.01),
                    "α = ({ax}, {ay}), wo = {wo}: {lhs} vs cos θo = {}",
                    wo.z
                );
            }
        }
    }

    #[test]
    fn matches_the_trigonometric_formulas() {
        // D and Λ as the papers write them, with θ and φ from atan2/acos.
        let (ax, ay) = (0.15, 0.45);
        let m = Ggx::new(ax, ay, Value::Grey(0.7), FresnelSpec::None, &Channels::Rgb).unwrap();
        let mut rng = Pcg32::new(12);
        for _ in 0..2000 {
            let wi = geometry::uniform_hemisphere(rng.next_dvec2());
            let wo = geometry::uniform_hemisphere(rng.next_dvec2());
            let h = (wi + wo).normalize();
            let (th, ph) = geometry::to_spherical(h);
            let d = 1.0
                / (PI
                    * ax
                    * ay
                    * th.cos().powi(4)
                    * (1.0
                        + th.tan().powi(2)
                            * (ph.cos().powi(2) / (ax * ax) + ph.sin().powi(2) / (ay * ay)))
                        .powi(2));
            let lambda = |w: DVec3| {
                let (t, p) = geometry::to_spherical(w);
                let a2 = p.cos().powi(2) * ax * ax + p.sin().powi(2) * ay * ay;
                0.5 * (-1.0 + (1.0 + a2 * t.tan().powi(2)).sqrt())
            };
            let g2 = 1.0 / (1.0 + lambda(wi) + lambda(wo));
            let expect = 0.7 * d * g2 / (4.0 * wi.z * wo.z);
            let mut f = [0.0f32; 3];
            m.eval(wi, wo, &mut f);
            assert!(
                (f[0] as f64 - expect).abs() <= 1e-6 * expect + 1e-12,
                "{wi} {wo}: {} vs {expect}",
                f[0]
            );
        }
    }

    #[test]
    fn anisotropic_with_equal_alphas_equals_isotropic() {
        let a = Ggx::isotropic(0.3, Value::Grey(0.8), conductor(), &Channels::Rgb).unwrap();
        // Through the spec, as a user would write it.
        let spec = crate::spec::ModelSpec::parse(
            r#"{"model": "ggx", "alpha_x": 0.3, "alpha_y": 0.3, "ks": 0.8,
                "fresnel": {"n": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.2]}}"#,
        )
        .unwrap();
        let b = spec.build(&Channels::Rgb).unwrap();
        assert!(a.flags().isotropic && b.flags().isotropic);
        assert!(!aniso(0.3, 0.31).flags().isotropic);
        let mut rng = Pcg32::new(9);
        for _ in 0..1000 {
            let wi = geometry::uniform_hemisphere(rng.next_dvec2());
            let wo = geometry::uniform_hemisphere(rng.next_dvec2());
            let (mut f, mut g) = ([0.0f32; 3], [0.0f32; 3]);
            a.eval(wi, wo, &mut f);
            b.eval(wi, wo, &mut g);
            assert_eq!(f, g);
        }
    }

    #[test]
    fn isotropic_model_is_invariant_under_rotation() {
        let m = iso(0.25);
        let mut rng = Pcg32::new(3);
        for _ in 0..500 {
            let wi = geometry::uniform_hemisphere(rng.next_dvec2());
            let wo = geometry::uniform_hemisphere(rng.next_dvec2());
            let rot = glam::DQuat::from_rotation_z(rng.next_f64() * 6.0);
            let (mut f, mut g) = ([0.0f32; 3], [0.0f32; 3]);
            m.eval(wi, wo, &mut f);
            m.eval(rot * wi, rot * wo, &mut g);
            assert!((f[0] - g[0]).abs() <= 1e-5 * f[0].abs());
        }
    }

    #[test]
    fn bilateral_symmetry_holds_for_anisotropic() {
        let m = aniso(0.1, 0.5);
        let mut rng = Pcg32::new(4);
        let flip = |v: DVec3| DVec3::new(v.x, -v.y, v.z);
        for _ in 0..500 {
            let wi = geometry::uniform_hemisphere(rng.next_dvec2());
            let wo = geometry::uniform_hemisphere(rng.next_dvec2());
            let (mut f, mut g) = ([0.0f32; 3], [0.0f32; 3]);
            m.eval(wi, wo, &mut f);
            m.eval(flip(wi), flip(wo), &mut g);
            assert!((f[0] - g[0]).abs() <= 1e-5 * f[0].abs());
        }
    }

    #[test]
    fn peak_value_in_closed_form() {
        // wi = wo = z: h = z, D = 1/(π α²), Λ = 0, f = k_s F(1) / (4 π α²).
        let m = Ggx::isotropic(0.2, Value::Grey(0.5), conductor(), &Channels::Rgb).unwrap();
        let mut f = [0.0f32; 3];
        m.eval(DVec3::Z, DVec3::Z, &mut f);
        for (c, (&n, &k)) in [0.2, 0.9, 1.1].iter().zip(&[3.9, 2.4, 2.2]).enumerate() {
            let f0 = ((n - 1.0f64).powi(2) + k * k) / ((n + 1.0f64).powi(2) + k * k);
            let expect = 0.5 * f0 / (4.0 * PI * 0.04);
            assert!(
                (f[c] as f64 - expect).abs() < 1e-6 * expect,
                "{c}: {} vs {expect}",
                f[c]
            );
        }
    }

    #[test]
    fn white_furnace_loses_only_multiple_scattering() {
        // With F = 1 and k_s = 1, single-scattering GGX loses the energy of multiple bounces but
        // never gains: ∫ f cos θi dωi = ∫_{visible h, wi above} D G2 (wo·h) / cos θo dω_h ≤ 1
        // (in h, as dωi = 4 (wo·h) dωh), and the loss vanishes for smooth surfaces at normal
        // incidence.
        for (ax, ay) in [(0.02, 0.02), (0.3, 0.3), (1.0, 1.0), (0.05, 0.5)] {
            let m = aniso(ax, ay);
            for wo in test_wos() {
                let a = integrate_visible(&m, wo, |h| {
                    let wi = 2.0 * wo.dot(h) * h - wo;
                    if wi.z <= 0.0 {
                        return 0.0;
                    }
                    m.ndf(h) * m.g2(wi, wo) * wo.dot(h) / wo.z
                });
                assert!(
                    a <= 1.0 + 1e-6 && a > 0.2,
                    "α = ({ax}, {ay}), wo = {wo}: albedo {a}"
                );
                if ax == 0.02 && wo.z > 0.9 {
                    assert!(a > 0.999, "{a}");
                }
                if ax == 0.3 {
                    // The default quadrature resolves a lobe this wide.
                    let mut q = [0.0; 3];
                    m.albedo(wo, &mut q);
                    assert!((q[0] - a).abs() < 2e-3, "wo = {wo}: {} vs {a}", q[0]);
                }
            }
        }
    }

    #[test]
    fn below_horizon_and_nan_give_zero() {
        check_invalid_inputs_give_zero(&aniso(0.2, 0.4));
        let _ = Ggx::isotropic(0.2, Value::Grey(1.0), conductor(), &Channels::Rgb).unwrap();
    }

    #[test]
    fn invalid_parameters_are_errors() {
        for a in [0.0, -0.1, f64::NAN, f64::INFINITY] {
            assert!(
                Ggx::isotropic(a, Value::Grey(1.0), FresnelSpec::None, &Channels::Rgb).is_err()
            );
        }
    }

    #[test]
    fn spectral_parameters_follow_eval_wavelength() {
        let ch = Channels::linspace(400.0, 700.0, 5).unwrap();
        let fresnel = FresnelSpec::Complex {
            n: Value::Spectral {
                wavelengths: vec![400.0, 700.0],
                values: vec![1.2, 0.2],
            },
            k: Value::Spectral {
                wavelengths: vec![400.0, 700.0],
                values: vec![2.0, 4.0],
            },
        };
        let m = Ggx::new(0.2, 0.3, Value::Grey(0.9), fresnel, &ch).unwrap();
        check_eval_wavelength_matches_channels(&m);
    }

    #[test]
    fn sample_weight_and_pdf_are_consistent() {
        for (ax, ay) in [(0.01, 0.01), (0.2, 0.2), (1.0, 1.0), (0.05, 0.5)] {
            let m = Ggx::new(ax, ay, Value::Grey(0.9), conductor(), &Channels::Rgb).unwrap();
            check_sampling_consistency(&m, &test_wos(), 2000);
        }
    }

    #[test]
    fn visible_normal_sampler_passes_chi_square_isotropic() {
        chi2_models(&[&aniso(0.05, 0.05), &aniso(0.3, 0.3), &aniso(1.0, 1.0)]);
    }

    #[test]
    fn visible_normal_sampler_passes_chi_square_anisotropic() {
        chi2_models(&[&aniso(0.1, 0.6), &aniso(0.7, 0.15)]);
    }

    #[test]
    fn half_vector_sampler_passes_chi_square() {
        let models: Vec<Ggx> = [(0.05, 0.05), (0.5, 0.5), (0.1, 0.6)]
            .iter()
            .map(|&(ax, ay)| aniso(ax, ay))
            .collect();
        let samplers: Vec<_> = models
            .iter()
            .map(|m| FnSampler {
                sample: move |u| Some(m.sample_half_vector(u)),
                pdf: move |h: DVec3| m.pdf_half_vector(h),
                name: format!("GGX D·cos half vectors, {}", m.describe()),
            })
            .collect();
        let cases: Vec<(&dyn Brdf, DVec3)> = samplers
            .iter()
            .map(|s| (s as &dyn Brdf, DVec3::Z))
            .collect();
        chi2_cases(&cases);
    }

    #[test]
    fn chi_square_detects_a_slightly_wrong_density() {
        // The tests above can fail: half vectors of α = 0.3 against the density of α = 0.33.
        use crate::analysis::chi2::{Chi2Options, test};
        let (a, b) = (aniso(0.3, 0.3), aniso(0.33, 0.33));
        let wrong = FnSampler {
            sample: |u| Some(a.sample_half_vector(u)),
            pdf: |h: DVec3| b.pdf_half_vector(h),
            name: "mismatched".into(),
        };
        let o = Chi2Options {
            samples: 200_000,
            ..Default::default()
        };
        let r = test(&wrong, DVec3::Z, &o);
        assert!(!r.passes(0.01), "{r:?}");
    }

    #[test]
    fn pairs_a_hair_above_the_horizon_keep_their_limit() {
        // At grazing G2 ~ cos θ / α and f_r ~ 1/cos θ (height-correlated Smith), so f_r cos θ and
        // the density G1(wo) D / (4 cos θo) have finite limits as both cosines go to 0, which a
        // pair at cos 1e-300 must reproduce (the quadratic terms are below 1e-20 of them there).
        let m = Ggx::new(0.1, 0.3, Value::Grey(0.9), conductor(), &Channels::Rgb).unwrap();
        let pair = |z: f64, o: DVec3| {
            let r = (1.0 - z * z).sqrt();
            (DVec3::new(0.0, r, z), DVec3::new(o.x * r, o.y * r, z))
        };
        for o in [DVec3::new(0.0, -1.0, 0.0), DVec3::new(-0.6, -0.8, 0.0)] {
            let (wi, wo) = pair(1e-20, o);
            let (f_ref, p_ref) = (m.eval_wavelength(wi, wo, 550.0) * 1e-20, m.pdf(wi, wo));
            assert!(f_ref > 0.0 && f_ref.is_finite() && p_ref > 0.0 && p_ref.is_finite());
            for z in [1e-60, 1e-100, 1e-160, 1e-200, 1e-300] {
                let (wi, wo) = pair(z, o);
                let (f, p) = (m.eval_wavelength(wi, wo, 550.0) * z, m.pdf(wi, wo));
                assert!(
                    (f / f_ref - 1.0).abs() < 1e-12,
                    "{o} z={z:e}: f cos {f:e} vs {f_ref:e}"
                );
                assert!(
                    (p / p_ref - 1.0).abs() < 1e-12,
                    "{o} z={z:e}: pdf {p:e} vs {p_ref:e}"
                );
                // The f32 value overflows (f_r really is beyond f32 there), but is never NaN.
                let mut out = [0f32; 3];
                m.eval(wi, wo, &mut out);
                assert!(out.iter().all(|x| *x > 0.0), "{o} z={z:e}: {out:?}");
            }
        }
    }

    #[test]
    fn a_sample_at_a_grazing_view_has_the_density_pdf_gives() {
        // The sampler's closed-form pdf left |h|⁴ · 4 cos θo in its denominator, subnormal at
        // cos θo = 1e-300 for α ≤ 1e-3 (50 % off pdf(wi, wo) at α = 1e-4) and at the subnormal
        // cosine 5e-324 for any α (2.1× at α = 1). What it must agree with is pdf(), which
        // `pairs_a_hair_above_the_horizon_keep_their_limit` holds to its limit.
        for (ax, ay) in [
            (1e-4, 1e-4),
            (1e-3, 1e-3),
            (1e-3, 0.5),
            (1.0, 1.0),
            (10.0, 0.3),
        ] {
            let m = aniso(ax, ay);
            let wos: Vec<DVec3> = [1e-100, 1e-300, f64::from_bits(1)]
                .into_iter()
                .flat_map(|z| [DVec3::new(1.0, 0.0, z), DVec3::new(0.6, -0.8, z)])
                .collect();
            check_sampling_consistency(&m, &wos, 2000);
        }
    }

    proptest! {
        #[test]
        fn reciprocal(a in dir_strategy(), b in dir_strategy(), ax in 0.01f64..1.5, ay in 0.01f64..1.5) {
            let m = Ggx::new(ax, ay, Value::Grey(0.9), conductor(), &Channels::Rgb).unwrap();
            check_reciprocity(&m, a, b)?;
        }
    }
}
