//! Lambert's diffuse model: the BRDF is a constant, f_r = k_d.
//!
//! Lecture: "Radiance is independent of the out direction; Helmholtz: independent of the in
//! direction; BRDF is constant". The albedo has the closed form
//! a = ∫ k_d cos θ dω = k_d π, so energy is conserved only for k_d ≤ 1/π.

use glam::{DVec2, DVec3};

use crate::brdf::{Brdf, BrdfSample, Flags};
use crate::error::Result;
use crate::geometry;
use crate::spectrum::{Channels, Value};

/// Lambertian (diffuse) reflection, f_r = k_d(λ).
#[derive(Debug, Clone)]
pub struct Lambert {
    channels: Channels,
    kd_spec: Value,
    kd: Vec<f32>,
    /// k_d π per channel: the albedo, and the weight of every cosine-weighted sample.
    kd_pi: Vec<f32>,
}

impl Lambert {
    /// A Lambert model with diffuse coefficient `kd` (the BRDF value; albedo kd·π).
    pub fn new(kd: Value, channels: &Channels) -> Result<Self> {
        channels.validate()?;
        kd.validate("kd", 0.0)?;
        let kd32: Vec<f32> = kd.resolve(channels).iter().map(|&x| x as f32).collect();
        Ok(Lambert {
            channels: channels.clone(),
            kd_pi: kd32
                .iter()
                .map(|&k| (k as f64 * std::f64::consts::PI) as f32)
                .collect(),
            kd: kd32,
            kd_spec: kd,
        })
    }
}

impl Brdf for Lambert {
    fn channels(&self) -> &Channels {
        &self.channels
    }

    #[inline]
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        // Only the horizon test needs the directions; no normalization is needed for the sign.
        let above = wi.z > 0.0 && wo.z > 0.0 && wi.is_finite() && wo.is_finite();
        super::put_channels(out, &self.kd, above);
    }

    fn eval_wavelength(&self, wi: DVec3, wo: DVec3, nm: f64) -> f64 {
        if !crate::spectrum::is_wavelength(nm) {
            return f64::NAN; // not a wavelength: no value (Channels::mix_at)
        }
        if geometry::upper_pair(wi, wo).is_some() {
            self.kd_spec.at(nm)
        } else {
            0.0
        }
    }

    fn flags(&self) -> Flags {
        Flags {
            lobes: crate::brdf::Lobes::DIFFUSE,
            ..Flags::SMOOTH_SYMMETRIC
        }
    }

    fn describe(&self) -> String {
        format!(
            "lambert kd={}",
            serde_json::to_string(&self.kd_spec).unwrap_or_default()
        )
    }

    /// Closed form: a = k_d · π for every incident direction above the horizon.
    fn albedo(&self, wi: DVec3, out: &mut [f64]) {
        let above = geometry::normalize(wi).is_some_and(|w| w.z > 0.0);
        for (o, &k) in out.iter_mut().zip(&self.kd) {
            *o = if above {
                k as f64 * std::f64::consts::PI
            } else {
                0.0
            };
        }
    }

    /// Cosine-weighted sampling, pdf cos θi / π: the weight f·cos θi / pdf = k_d π is constant.
    fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
        // Only the sign of cos θo matters, so `wo` is checked, not normalized.
        if !(geometry::is_upper(wo) && geometry::in_unit_square(u)) {
            return None;
        }
        let wi = geometry::cosine_hemisphere(u);
        let pdf = wi.z * std::f64::consts::FRAC_1_PI;
        if !(pdf > 0.0) {
            return None;
        }
        super::put_channels(weight, &self.kd_pi, true);
        Some(BrdfSample {
            wi,
            pdf,
            delta: false,
        })
    }

    /// k_d and cos θi / π; `wi` is normalized only when it is not already unit (the density
    /// needs its cosine; `wo` only its sign).
    fn eval_pdf(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) -> f64 {
        let l2 = wi.length_squared();
        let above = wi.z > 0.0 && l2 < f64::INFINITY && geometry::is_upper(wo);
        super::put_channels(out, &self.kd, above);
        if !above {
            0.0
        } else if geometry::is_unit_l2(l2) {
            wi.z * std::f64::consts::FRAC_1_PI
        } else {
            wi.z / l2.sqrt() * std::f64::consts::FRAC_1_PI
        }
    }

    /// The cosine density cos θi / π (0 below the horizon or for invalid directions).
    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        match geometry::upper_pair(wi, wo) {
            Some((wi, _)) => wi.z * std::f64::consts::FRAC_1_PI,
            None => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::albedo::quadrature;

    #[test]
    fn albedo_is_kd_pi_at_several_angles() {
        let l = Lambert::new(Value::Rgb([0.1, 0.2, 0.3]), &Channels::Rgb).unwrap();
        for deg in [0.0f64, 30.0, 60.0, 85.0] {
            let wi = geometry::spherical(deg.to_radians(), 0.4);
            let mut a = [0.0; 3];
            l.albedo(wi, &mut a);
            let mut q = [0.0; 3];
            quadrature(&l, wi, &mut q);
            for c in 0..3 {
                let expect = [0.1, 0.2, 0.3][c] as f32 as f64 * std::f64::consts::PI;
                assert!((a[c] - expect).abs() < 1e-12);
                // The default quadrature must agree with the closed form to 1e-4.
                assert!(
                    (q[c] - expect).abs() < 1e-4 * expect,
                    "{deg}: {} vs {expect}",
                    q[c]
                );
            }
        }
    }

    #[test]
    fn eval_pdf_does_not_depend_on_the_length_of_wi() {
        let l = Lambert::new(Value::Rgb([0.1, 0.2, 0.3]), &Channels::Rgb).unwrap();
        let wo = geometry::spherical(0.4, 1.0);
        for deg in [1.0f64, 30.0, 60.0, 89.0] {
            let wi = geometry::spherical(deg.to_radians(), 2.0);
            let mut f = [0.0f32; 3];
            let p = l.eval_pdf(wi, wo, &mut f);
            let expect = wi.z * std::f64::consts::FRAC_1_PI;
            assert!((p - expect).abs() <= 1e-15, "{p} vs {expect}");
            assert_eq!(f, [0.1, 0.2, 0.3]);
            for scale in [1e-3, 0.5, 7.0, 1e6] {
                let q = l.eval_pdf(wi * scale, wo * scale, &mut f);
                assert!((q - p).abs() <= 1e-15, "{scale}: {q} vs {p}");
                assert_eq!(q, l.pdf(wi * scale, wo));
            }
        }
        let mut f = [1.0f32; 3];
        assert_eq!(
            l.eval_pdf(DVec3::Z, DVec3::new(f64::NAN, 0.0, 1.0), &mut f),
            0.0
        );
        assert_eq!(f, [0.0; 3]);
    }

    #[test]
    fn below_horizon_and_nan_give_zero() {
        let l = Lambert::new(Value::Grey(0.3), &Channels::Rgb).unwrap();
        let mut f = [1.0f32; 3];
        l.eval(DVec3::new(0.0, 0.0, -1.0), DVec3::Z, &mut f);
        assert_eq!(f, [0.0; 3]);
        let mut f = [1.0f32; 3];
        l.eval(DVec3::new(f64::NAN, 0.0, 1.0), DVec3::Z, &mut f);
        assert_eq!(f, [0.0; 3]);
    }
}
