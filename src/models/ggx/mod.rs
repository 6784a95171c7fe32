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
mod tests;
