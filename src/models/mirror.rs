//! Ideal reflection and ideal refraction: the two Dirac-delta BRDFs of the lecture.
//!
//! Lecture: "Radiance is reflected only to the ideal mirror direction; BRDF is a Dirac-delta
//! function f_r(ω′, x, ω) = δ(ω − ω_r) k_r / cos θ′". A delta has no finite value, so `eval`
//! returns 0 and the lobe lives in [`Brdf::sample`]: it returns the one direction, `pdf` 1 and
//! `delta = true`, and the weight k_r (the lecture's `Albedo`). Likewise for refraction with
//! k_t = 1 − F.
//!
//! Directions follow the lecture's classes `Reflector::ReflectDir` (L = 2 (N·V) N − V) and
//! `Refractor::RefractionDir` (L = N (cos α / n − sqrt(1 − (1 − cos² α) / n²)) − V / n, with n
//! replaced by 1/n when the viewer is inside), written here for the local frame N = z.

use glam::{DVec2, DVec3};

use crate::brdf::{Brdf, BrdfSample, Flags};
use crate::error::Result;
use crate::fresnel::{self, Fresnel, FresnelSpec};
use crate::geometry;
use crate::spectrum::{Channels, Value};

/// The ideal refraction direction of `w` (pointing away from the surface, unit) through a
/// surface with unit normal `n`, for relative index `eta` = (index on the far side) / (index on
/// the side of `w`). Returns `None` on total internal reflection.
///
/// This is the lecture's `RefractionDir` with cos α = N·V:
/// ω_t = N (cos α / η − sqrt(1 − (1 − cos² α) / η²)) − ω / η. When `w` lies on the other side of
/// `n` (n·w < 0) the normal is flipped first, so the result is always on the far side of `w`.
/// Snell's law holds: sin θ_w = η sin θ_t.
#[inline]
pub fn refract(w: DVec3, n: DVec3, eta: f64) -> Option<DVec3> {
    let (n, cos_a) = {
        let c = n.dot(w);
        if c < 0.0 { (-n, -c) } else { (n, c) }
    };
    let disc = 1.0 - (1.0 - cos_a * cos_a) / (eta * eta);
    if disc.is_nan() || disc < 0.0 || eta.is_nan() || eta <= 0.0 {
        return None;
    }
    Some(n * (cos_a / eta - disc.sqrt()) - w / eta)
}

/// Ideal mirror: reflects `wo` to 2(N·V)N − V with k_r = Fresnel at N·V.
#[derive(Debug, Clone)]
pub struct Mirror {
    channels: Channels,
    fresnel_spec: FresnelSpec,
    fresnel: Fresnel,
}

impl Mirror {
    /// A mirror whose reflectance k_r is the Fresnel term `fresnel` (`FresnelSpec::None`: k_r = 1).
    pub fn new(fresnel: &FresnelSpec, channels: &Channels) -> Result<Self> {
        channels.validate()?;
        Ok(Mirror {
            channels: channels.clone(),
            fresnel: Fresnel::new(fresnel, channels, "fresnel")?,
            fresnel_spec: fresnel.clone(),
        })
    }

    /// The lecture's k_r for channel `c` at incidence cosine `cos` (N·V).
    #[inline]
    pub fn k_r(&self, cos: f64, c: usize) -> f64 {
        self.fresnel.eval(cos, c)
    }
}

impl Brdf for Mirror {
    fn channels(&self) -> &Channels {
        &self.channels
    }

    /// A delta: 0 for every pair (the lobe is in [`Brdf::sample`]).
    fn eval(&self, _wi: DVec3, _wo: DVec3, out: &mut [f32]) {
        out[..self.channels.len()].fill(0.0);
    }

    fn eval_wavelength(&self, _wi: DVec3, _wo: DVec3, nm: f64) -> f64 {
        if crate::spectrum::is_wavelength(nm) {
            0.0
        } else {
            f64::NAN
        }
    }

    fn flags(&self) -> Flags {
        Flags {
            delta: true,
            lobes: crate::brdf::Lobes::DELTA,
            ..Flags::SMOOTH_SYMMETRIC
        }
    }

    fn describe(&self) -> String {
        format!(
            "mirror fresnel={}",
            serde_json::to_string(&self.fresnel_spec).unwrap_or_default()
        )
    }

    /// The lecture's `Albedo`: k_r at the incidence angle.
    fn albedo(&self, wi: DVec3, out: &mut [f64]) {
        let cos = geometry::normalize(wi).map_or(0.0, |w| w.z);
        for (c, o) in out[..self.channels.len()].iter_mut().enumerate() {
            *o = if cos > 0.0 { self.k_r(cos, c) } else { 0.0 };
        }
    }

    /// The lecture's `ReflectDir`: L = 2 (N·V) N − V, weight k_r(N·V), pdf 1, delta.
    fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
        let wo = geometry::unit(wo)?;
        if wo.z <= 0.0 || !geometry::in_unit_square(u) {
            return None;
        }
        let wi = geometry::reflect(wo, DVec3::Z);
        for (c, w) in weight[..self.channels.len()].iter_mut().enumerate() {
            *w = self.k_r(wo.z, c) as f32;
        }
        Some(BrdfSample {
            wi,
            pdf: 1.0,
            delta: true,
        })
    }

    fn pdf(&self, _wi: DVec3, _wo: DVec3) -> f64 {
        0.0
    }

    /// The reflection direction, weight k_r(N·V) at each wavelength from the Fresnel term's
    /// spectral data.
    fn sample_wavelengths(
        &self,
        wo: DVec3,
        u: DVec2,
        nm: &[f64],
        weight: &mut [f32],
    ) -> Option<BrdfSample> {
        let mut buf = [0.0f32; crate::spectrum::MAX_CHANNELS];
        let s = self.sample(wo, u, &mut buf[..self.channels.len()])?;
        let cos = geometry::unit(wo)?.z;
        for (w, &x) in weight.iter_mut().zip(nm) {
            *w = self.fresnel.eval_at(cos, x) as f32;
        }
        Some(s)
    }
}

/// Ideal refraction into (or out of) a dielectric of relative index η = n_inside / n_outside,
/// weighted by k_t = 1 − F (dielectric Fresnel).
///
/// The outside is the side of +z. A viewer direction `wo` with z < 0 is inside (the lecture's
/// `out` flag is false) and the relative index becomes 1/η.
///
/// **Radiance convention.** The weight is the lecture's k_t = 1 − F with **no** (η_t/η_i)²
/// factor (light crosses from `wi`'s side, index η_i, into `wo`'s, index η_t; radiance L/η² is
/// what an interface conserves, so the radiance reaching `wo` is (η_t/η_i)² (1 − F) that of
/// `wi`): the sample carries the fraction of energy (and of importance) transmitted, which is
/// the same in both directions. A renderer that tracks radiance across an interface and wants the
/// radiance compression of a ray entering a denser medium must apply that factor itself. Because
/// of this the model is not declared reciprocal (the radiance BTDF of a real interface is only
/// reciprocal after dividing by η²).
///
/// With per-channel η the sampled *direction* uses the mean η over the channels (one sample has
/// one direction; dispersion is not represented), while the weight 1 − F uses each channel's η.
/// Use a single-wavelength channel set to trace dispersion.
#[derive(Debug, Clone)]
pub struct Refractor {
    channels: Channels,
    eta_spec: Value,
    eta: Vec<f64>,
    eta_direction: f64,
}

impl Refractor {
    /// A refractor of relative index `eta` (> 0) per channel.
    pub fn new(eta: Value, channels: &Channels) -> Result<Self> {
        channels.validate()?;
        eta.validate("eta", 0.0)?;
        if eta.numbers().iter().any(|&x| x <= 0.0) {
            return Err(crate::Error::spec("eta", "must be > 0"));
        }
        let per = eta.resolve(channels);
        let mean = per.iter().sum::<f64>() / per.len() as f64;
        Ok(Refractor {
            channels: channels.clone(),
            eta_spec: eta,
            eta: per,
            eta_direction: mean,
        })
    }

    /// The lecture's `RefractionDir` for a viewer direction `wo` in the local frame: `Some(wi)`
    /// on the other side of the surface, `None` on total internal reflection (or invalid `wo`).
    pub fn refraction_dir(&self, wo: DVec3) -> Option<DVec3> {
        let wo = geometry::unit(wo)?;
        if wo.z == 0.0 {
            return None;
        }
        // out = the viewer is outside: relative index η; inside: 1/η. `refract` flips the normal
        // to the viewer's side, so cos α = |N·V| as in the lecture.
        let out = wo.z > 0.0;
        let cn = if out {
            self.eta_direction
        } else {
            1.0 / self.eta_direction
        };
        refract(wo, DVec3::Z, cn)
    }

    /// k_t = 1 − F for channel `c` at the signed incidence cosine `cos` (negative: from inside).
    #[inline]
    fn k_t(&self, cos: f64, c: usize) -> f64 {
        1.0 - fresnel::dielectric(cos, self.eta[c])
    }
}

impl Brdf for Refractor {
    fn channels(&self) -> &Channels {
        &self.channels
    }

    /// A delta: 0 for every pair.
    fn eval(&self, _wi: DVec3, _wo: DVec3, out: &mut [f32]) {
        out[..self.channels.len()].fill(0.0);
    }

    fn eval_wavelength(&self, _wi: DVec3, _wo: DVec3, nm: f64) -> f64 {
        if crate::spectrum::is_wavelength(nm) {
            0.0
        } else {
            f64::NAN
        }
    }

    fn flags(&self) -> Flags {
        Flags {
            delta: true,
            reciprocal: false,
            isotropic: true,
            bilateral: true,
            transmission: true,
            lobes: crate::brdf::Lobes::DELTA,
        }
    }

    fn describe(&self) -> String {
        format!(
            "refractor eta={}",
            serde_json::to_string(&self.eta_spec).unwrap_or_default()
        )
    }

    /// The transmitted fraction k_t = 1 − F for light arriving along `wi` (from either side;
    /// 0 under total internal reflection).
    fn albedo(&self, wi: DVec3, out: &mut [f64]) {
        let cos = geometry::normalize(wi).map_or(0.0, |w| w.z);
        for (c, o) in out[..self.channels.len()].iter_mut().enumerate() {
            *o = if cos != 0.0 { self.k_t(cos, c) } else { 0.0 };
        }
    }

    /// The refraction direction of `wo`, weight k_t = 1 − F per channel, pdf 1, delta; `None` on
    /// total internal reflection.
    fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
        if !geometry::in_unit_square(u) {
            return None;
        }
        let wi = self.refraction_dir(wo)?;
        let cos = geometry::unit(wo)?.z;
        for (c, w) in weight[..self.channels.len()].iter_mut().enumerate() {
            *w = self.k_t(cos, c) as f32;
        }
        Some(BrdfSample {
            wi,
            pdf: 1.0,
            delta: true,
        })
    }

    fn pdf(&self, _wi: DVec3, _wo: DVec3) -> f64 {
        0.0
    }

    /// The refraction direction (from the mean η, as [`Brdf::sample`]), weight k_t = 1 − F at
    /// each wavelength from η's spectral data.
    fn sample_wavelengths(
        &self,
        wo: DVec3,
        u: DVec2,
        nm: &[f64],
        weight: &mut [f32],
    ) -> Option<BrdfSample> {
        let mut buf = [0.0f32; crate::spectrum::MAX_CHANNELS];
        let s = self.sample(wo, u, &mut buf[..self.channels.len()])?;
        let cos = geometry::unit(wo)?.z;
        for (w, &x) in weight.iter_mut().zip(nm) {
            *w = match crate::spectrum::is_wavelength(x) {
                true => (1.0 - fresnel::dielectric(cos, self.eta_spec.at(x))) as f32,
                false => f32::NAN,
            };
        }
        Some(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ag() -> Mirror {
        Mirror::new(&FresnelSpec::Conductor("Ag".into()), &Channels::Rgb).unwrap()
    }

    #[test]
    fn mirror_reflects_and_weights_with_fresnel() {
        let m = ag();
        let wo = geometry::spherical(0.6, 1.1);
        let mut w = [0.0f32; 3];
        let s = m.sample(wo, DVec2::new(0.3, 0.7), &mut w).unwrap();
        assert!(s.delta && s.pdf == 1.0);
        // 2 (N·V) N − V
        assert!((s.wi - (2.0 * wo.z * DVec3::Z - wo)).length() < 1e-15);
        for (c, &x) in w.iter().enumerate() {
            assert_eq!(x, m.k_r(wo.z, c) as f32);
        }
        assert_eq!(m.pdf(s.wi, wo), 0.0);
        let mut f = [1.0f32; 3];
        m.eval(s.wi, wo, &mut f);
        assert_eq!(f, [0.0; 3]);
        assert!(m.flags().delta && m.flags().reciprocal);
    }

    /// At normal incidence k_r = ((n − 1)² + k²) / ((n + 1)² + k²) and k_t = 1 − ((η − 1)/(η + 1))²,
    /// with n, k and η interpolated linearly between their spectral nodes.
    #[test]
    fn spectral_sample_weights_are_the_closed_form_at_each_wavelength() {
        let spectral = |a: f64, b: f64| Value::Spectral {
            wavelengths: vec![400.0, 700.0],
            values: vec![a, b],
        };
        let m = Mirror::new(
            &FresnelSpec::Complex {
                n: spectral(0.2, 1.4),
                k: spectral(3.0, 1.0),
            },
            &Channels::Rgb,
        )
        .unwrap();
        let r = Refractor::new(spectral(1.8, 1.2), &Channels::Rgb).unwrap();
        let nm = [400.0, 475.0, 550.0, 700.0];
        let (mut wm, mut wr) = ([0.0f32; 4], [0.0f32; 4]);
        let sm = m
            .sample_wavelengths(DVec3::Z, DVec2::splat(0.5), &nm, &mut wm)
            .unwrap();
        let sr = r
            .sample_wavelengths(DVec3::Z, DVec2::splat(0.5), &nm, &mut wr)
            .unwrap();
        assert!(sm.delta && sr.delta && sm.wi.z > 0.0 && sr.wi.z < 0.0);
        for (i, &x) in nm.iter().enumerate() {
            let t = (x - 400.0) / 300.0;
            let (n, k) = (0.2 + 1.2 * t, 3.0 - 2.0 * t);
            let kr = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
            let eta = 1.8 - 0.6 * t;
            let kt = 1.0 - ((eta - 1.0) / (eta + 1.0)).powi(2);
            assert!(
                (wm[i] as f64 - kr).abs() < 1e-6,
                "{x} nm: k_r {} vs {kr}",
                wm[i]
            );
            assert!(
                (wr[i] as f64 - kt).abs() < 1e-6,
                "{x} nm: k_t {} vs {kt}",
                wr[i]
            );
        }
    }

    #[test]
    fn mirror_k_r_at_normal_incidence_is_the_closed_form() {
        let m = Mirror::new(
            &FresnelSpec::Complex {
                n: Value::Rgb([0.2, 0.9, 1.5]),
                k: Value::Rgb([3.0, 2.5, 0.0]),
            },
            &Channels::Rgb,
        )
        .unwrap();
        let mut a = [0.0; 3];
        m.albedo(DVec3::Z, &mut a);
        for (c, (n, k)) in [(0.2, 3.0), (0.9, 2.5), (1.5, 0.0)].into_iter().enumerate() {
            let expect = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
            assert!((a[c] - expect).abs() < 1e-12, "{c}: {} vs {expect}", a[c]);
        }
        // k_r = 1 without Fresnel.
        let plain = Mirror::new(&FresnelSpec::None, &Channels::Rgb).unwrap();
        let mut w = [0.0f32; 3];
        plain
            .sample(DVec3::new(0.3, 0.0, 1.0), DVec2::ZERO, &mut w)
            .unwrap();
        assert_eq!(w, [1.0; 3]);
    }

    #[test]
    fn mirror_rejects_bad_wo() {
        let m = ag();
        let mut w = [0.0f32; 3];
        assert!(
            m.sample(DVec3::new(0.0, 0.0, -1.0), DVec2::ZERO, &mut w)
                .is_none()
        );
        assert!(m.sample(DVec3::ZERO, DVec2::ZERO, &mut w).is_none());
        assert!(
            m.sample(DVec3::new(f64::NAN, 0.0, 1.0), DVec2::ZERO, &mut w)
                .is_none()
        );
    }

    #[test]
    fn refraction_obeys_snell_from_both_sides() {
        let eta = 1.5;
        for deg in [0.0f64, 10.0, 30.0, 60.0, 89.0] {
            let wo = geometry::spherical(deg.to_radians(), 0.7);
            let t = refract(wo, DVec3::Z, eta).unwrap();
            assert!((t.length() - 1.0).abs() < 1e-12);
            assert!(t.z < 0.0 || deg == 90.0);
            let sin_o = (1.0 - wo.z * wo.z).sqrt();
            let sin_t = (1.0 - t.z * t.z).sqrt();
            // sin θ′ = n sin θ with θ′ outside (viewer), θ inside.
            assert!((sin_o - eta * sin_t).abs() < 1e-12, "{deg}");
            // Same plane, opposite azimuth side: t_xy ∝ −wo_xy.
            assert!(t.truncate().perp_dot(wo.truncate()).abs() < 1e-12);
            assert!(t.truncate().dot(wo.truncate()) <= 0.0);
            // Going back out retraces the ray.
            let back = refract(t, DVec3::Z, 1.0 / eta).unwrap();
            assert!((back - wo).length() < 1e-12);
        }
    }

    #[test]
    fn total_internal_reflection_gives_none() {
        let r = Refractor::new(Value::Grey(1.5), &Channels::Rgb).unwrap();
        let crit = (1.0f64 / 1.5).asin();
        let mut w = [0.0f32; 3];
        // Inside, beyond the critical angle: none.
        let inside = |theta: f64| {
            let v = geometry::spherical(theta, 0.2);
            DVec3::new(v.x, v.y, -v.z)
        };
        assert!(r.sample(inside(crit + 0.01), DVec2::ZERO, &mut w).is_none());
        assert!(refract(inside(crit + 0.01), DVec3::Z, 1.0 / 1.5).is_none());
        // Just inside the critical angle: a grazing exit.
        let s = r.sample(inside(crit - 0.01), DVec2::ZERO, &mut w).unwrap();
        assert!(s.wi.z > 0.0 && s.delta);
        assert!(w.iter().all(|&x| (0.0..1.0).contains(&x)));
        // Outside never has TIR.
        for deg in [0.0f64, 45.0, 89.9] {
            assert!(
                r.sample(
                    geometry::spherical(deg.to_radians(), 0.0),
                    DVec2::ZERO,
                    &mut w
                )
                .is_some()
            );
        }
    }

    #[test]
    fn refractor_weight_is_one_minus_fresnel() {
        let r = Refractor::new(Value::Rgb([1.3, 1.5, 1.7]), &Channels::Rgb).unwrap();
        let wo = geometry::spherical(0.4, 0.0);
        let mut w = [0.0f32; 3];
        let s = r.sample(wo, DVec2::ZERO, &mut w).unwrap();
        assert!(s.wi.z < 0.0);
        for (c, eta) in [1.3, 1.5, 1.7].into_iter().enumerate() {
            let expect = 1.0 - fresnel::dielectric(wo.z, eta);
            assert!((w[c] as f64 - expect).abs() < 1e-7);
        }
        // At normal incidence 1 − ((η−1)/(η+1))².
        let mut a = [0.0; 3];
        r.albedo(DVec3::Z, &mut a);
        assert!((a[1] - (1.0 - 0.04)).abs() < 1e-12);
        assert_eq!(r.pdf(s.wi, wo), 0.0);
        let fl = r.flags();
        assert!(fl.delta && fl.transmission && !fl.reciprocal);
    }
}
