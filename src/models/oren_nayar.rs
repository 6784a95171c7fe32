//! Oren-Nayar rough diffuse reflection (1994), the "qualitative model".
//!
//! ```text
//! f_r = k_d (A + B max(0, cos(φi − φo)) sin α tan β)
//! A = 1 − 0.5 σ² / (σ² + 0.33),   B = 0.45 σ² / (σ² + 0.09),
//! α = max(θi, θo),   β = min(θi, θo)
//! ```
//!
//! (M. Oren and S. K. Nayar, "Generalization of Lambert's reflectance model", SIGGRAPH 1994,
//! eq. 30.) σ is the standard deviation of the facet slope angle in radians; `kd` is the BRDF
//! value of the σ = 0 case, which is exactly [`Lambert`](super::lambert::Lambert) (A = 1, B = 0).
//!
//! No trigonometry is needed. For unit directions, sin θ = |w_xy| and
//! cos(φi − φo) = (wi_xy · wo_xy) / (sin θi sin θo). Since {sin α, sin β} = {sin θi, sin θo} and
//! tan β = sin β / cos β with cos β = max(cos θi, cos θo),
//!
//! ```text
//! max(0, cos(φi − φo)) sin α tan β = max(0, wi_xy · wo_xy) / max(cos θi, cos θo),
//! ```
//!
//! which is also well defined at the pole, where φ is not.
//!
//! The model is reciprocal, isotropic and bilaterally symmetric. Sampling is the trait's
//! default, cosine-weighted: the lobe is nearly Lambertian, so cosine sampling is close to ideal;
//! its weight f_r·π = k_d π (A + B max(0, wi_xy·wo_xy)/max(cos θi, cos θo)) is bounded by
//! k_d π (A + B tan θo).

use glam::{DVec2, DVec3};

use crate::brdf::{Brdf, BrdfSample, Flags};
use crate::error::{Error, Result};
use crate::geometry;
use crate::spectrum::{Channels, Value};

/// Oren-Nayar qualitative model, f_r = k_d (A + B max(0, cos Δφ) sin α tan β).
#[derive(Debug, Clone)]
pub struct OrenNayar {
    channels: Channels,
    kd_spec: Value,
    kd: Vec<f64>,
    sigma: f64,
    a: f64,
    b: f64,
}

impl OrenNayar {
    /// An Oren-Nayar surface with diffuse coefficient `kd` (as in Lambert) and slope-angle
    /// deviation `sigma` ≥ 0 in radians.
    pub fn new(kd: Value, sigma: f64, channels: &Channels) -> Result<Self> {
        channels.validate()?;
        kd.validate("kd", 0.0)?;
        if !(sigma.is_finite() && sigma >= 0.0) {
            return Err(Error::spec(
                "sigma",
                format!("{sigma} must be a finite number ≥ 0"),
            ));
        }
        crate::spectrum::check_range(sigma, "sigma")?;
        let s2 = sigma * sigma;
        Ok(OrenNayar {
            channels: channels.clone(),
            kd: kd.resolve(channels),
            kd_spec: kd,
            sigma,
            a: 1.0 - 0.5 * s2 / (s2 + 0.33),
            b: 0.45 * s2 / (s2 + 0.09),
        })
    }

    /// The coefficients (A, B).
    pub fn coefficients(&self) -> (f64, f64) {
        (self.a, self.b)
    }

    /// A + B max(0, cos(φi − φo)) sin α tan β for unit directions above the horizon.
    #[inline]
    fn factor(&self, wi: DVec3, wo: DVec3) -> f64 {
        let dot_xy = wi.x * wo.x + wi.y * wo.y;
        self.a + self.b * dot_xy.max(0.0) / wi.z.max(wo.z)
    }
}

impl Brdf for OrenNayar {
    fn channels(&self) -> &Channels {
        &self.channels
    }

    #[inline]
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let out = &mut out[..self.kd.len()];
        let Some((wi, wo)) = crate::geometry::upper_pair(wi, wo) else {
            out.fill(0.0);
            return;
        };
        let g = self.factor(wi, wo);
        for (o, &k) in out.iter_mut().zip(&self.kd) {
            *o = (k * g) as f32;
        }
    }

    fn eval_wavelength(&self, wi: DVec3, wo: DVec3, nm: f64) -> f64 {
        if !crate::spectrum::is_wavelength(nm) {
            return f64::NAN; // not a wavelength: no value (Channels::mix_at)
        }
        match crate::geometry::upper_pair(wi, wo) {
            Some((wi, wo)) => self.kd_spec.at(nm) * self.factor(wi, wo),
            None => 0.0,
        }
    }

    fn flags(&self) -> Flags {
        Flags {
            lobes: crate::brdf::Lobes::DIFFUSE,
            ..Flags::SMOOTH_SYMMETRIC
        }
    }

    /// Cosine-weighted sampling (pdf cos θi / π), so the weight is k_d π (A + B …): the
    /// trait's default strategy, with the factor taken directly from the (unit) directions.
    fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
        let wo = geometry::unit(wo)?;
        if wo.z <= 0.0 || !geometry::in_unit_square(u) {
            return None;
        }
        let wi = geometry::cosine_hemisphere(u);
        let pdf = wi.z * std::f64::consts::FRAC_1_PI;
        if !(pdf > 0.0) {
            return None;
        }
        let g = self.factor(wi, wo) * std::f64::consts::PI;
        for (w, &k) in weight[..self.kd.len()].iter_mut().zip(&self.kd) {
            *w = (k * g) as f32;
        }
        Some(BrdfSample {
            wi,
            pdf,
            delta: false,
        })
    }

    fn describe(&self) -> String {
        format!(
            "oren_nayar kd={} sigma={}",
            serde_json::to_string(&self.kd_spec).unwrap_or_default(),
            self.sigma
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::lambert::Lambert;
    use crate::models::test_util::*;
    use crate::rng::Pcg32;
    use proptest::prelude::*;
    use std::f64::consts::PI;

    #[test]
    fn sigma_zero_is_lambert_exactly() {
        let kd = Value::Rgb([0.1, 0.25, 0.3]);
        let on = OrenNayar::new(kd.clone(), 0.0, &Channels::Rgb).unwrap();
        let l = Lambert::new(kd, &Channels::Rgb).unwrap();
        let mut rng = Pcg32::new(1);
        for _ in 0..2000 {
            let wi = geometry::uniform_sphere(rng.next_dvec2());
            let wo = geometry::uniform_sphere(rng.next_dvec2());
            let (mut f, mut g) = ([0.0f32; 3], [0.0f32; 3]);
            on.eval(wi, wo, &mut f);
            l.eval(wi, wo, &mut g);
            assert_eq!(f, g, "{wi} {wo}");
        }
    }

    #[test]
    fn matches_the_trigonometric_formula() {
        let m = OrenNayar::new(Value::Grey(0.3), 0.4, &Channels::Rgb).unwrap();
        let (a, b) = m.coefficients();
        let s2: f64 = 0.16;
        assert!((a - (1.0 - 0.5 * s2 / (s2 + 0.33))).abs() < 1e-15);
        assert!((b - 0.45 * s2 / (s2 + 0.09)).abs() < 1e-15);
        let mut rng = Pcg32::new(2);
        for _ in 0..2000 {
            let (ti, pi) = (rng.next_f64() * 1.5, rng.next_f64() * 2.0 * PI);
            let (to, po) = (rng.next_f64() * 1.5, rng.next_f64() * 2.0 * PI);
            let (al, be) = (ti.max(to), ti.min(to));
            let expect = 0.3 * (a + b * (pi - po).cos().max(0.0) * al.sin() * be.tan());
            let mut f = [0.0f32; 3];
            m.eval(
                geometry::spherical(ti, pi),
                geometry::spherical(to, po),
                &mut f,
            );
            assert!(
                (f[0] as f64 - expect).abs() < 2e-7 * expect,
                "{} vs {expect}",
                f[0]
            );
        }
    }

    #[test]
    fn rough_surfaces_backscatter() {
        // Towards the light a rough surface is brighter than Lambert (A + B sin θ tan θ > 1 at
        // 60°), away from it (Δφ = π) darker (A < 1).
        let w = geometry::spherical(60f64.to_radians(), 0.3);
        let away = DVec3::new(-w.x, -w.y, w.z);
        for sigma in [0.2, 0.4, 0.8] {
            let m = OrenNayar::new(Value::Grey(0.3), sigma, &Channels::Rgb).unwrap();
            let (a, b) = m.coefficients();
            let (mut f, mut g) = ([0.0f32; 3], [0.0f32; 3]);
            m.eval(w, w, &mut f);
            m.eval(w, away, &mut g);
            let t = 60f64.to_radians();
            let back = 0.3 * (a + b * t.sin() * t.tan());
            assert!(
                (f[0] as f64 - back).abs() < 1e-6 && back > 0.3,
                "σ = {sigma}: {}",
                f[0]
            );
            assert!(
                (g[0] as f64 - 0.3 * a).abs() < 1e-6 && a < 1.0,
                "σ = {sigma}: {}",
                g[0]
            );
        }
    }

    #[test]
    fn below_horizon_and_nan_give_zero() {
        let m = OrenNayar::new(Value::Grey(0.3), 0.5, &Channels::Rgb).unwrap();
        check_invalid_inputs_give_zero(&m);
    }

    #[test]
    fn spectral_parameters_follow_eval_wavelength() {
        let ch = Channels::linspace(400.0, 700.0, 4).unwrap();
        let m = OrenNayar::new(Value::Rgb([0.1, 0.2, 0.3]), 0.3, &ch).unwrap();
        check_eval_wavelength_matches_channels(&m);
    }

    #[test]
    fn cosine_sampling_weight_and_pdf() {
        let m = OrenNayar::new(Value::Grey(0.3), 0.5, &Channels::Rgb).unwrap();
        check_sampling_consistency(&m, &test_wos(), 2000);
        chi2_models(&[&m]);
    }

    proptest! {
        #[test]
        fn reciprocal(a in dir_strategy(), b in dir_strategy(), sigma in 0.0f64..1.5) {
            let m = OrenNayar::new(Value::Grey(0.3), sigma, &Channels::Rgb).unwrap();
            check_reciprocity(&m, a, b)?;
        }
    }
}
