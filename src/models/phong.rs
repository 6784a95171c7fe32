//! The Phong family of the lecture: one lobe k_s cos^n ψ, four ways to divide it.
//!
//! ψ is the angle between the viewer direction ω (`wo`) and the ideal reflection of the light
//! direction ω′ (`wi`); cos ψ is clamped at 0. Because cos ψ = wo · reflect(wi) = wi · reflect(wo),
//! the lobe itself is symmetric in its two directions; whether a model is reciprocal depends only
//! on the divisor X:
//!
//! | variant | f_r | reciprocal |
//! |---|---|---|
//! | [`PhongVariant::Original`] | k_s cos^n ψ / cos θ′ (L^ref = L^ir k_s cos^n ψ) | no |
//! | [`PhongVariant::Reciprocal`] | k_s cos^n ψ | yes |
//! | [`PhongVariant::Max`] | k_s cos^n ψ / max(cos θ′, cos θ) | yes |
//! | [`PhongVariant::Pumped`] | k_s cos^n ψ / X, X = mean, product or sqrt of cos θ′, cos θ | yes |
//!
//! The lecture's albedo of the reciprocal model at perpendicular illumination is
//! a_max = 2π k_s / (n + 2); the pumped-up versions do not lose energy at grazing angles like the
//! reciprocal one does (the product and sqrt versions gain without bound there).
//!
//! Importance sampling draws the lobe cos^n ψ around the reflection of `wo` alone: f_r cos θi
//! over the lobe's density is (2π k_s/(n + 1)) cos θi / X, bounded for every variant (constant
//! for the original model, 1/cos θ for the product one; see [`Phong::sample`]). A draw the lobe
//! sends below the horizon is folded back above it (z → −z) rather than refused, so grazing views
//! waste no samples; the density of a direction is then the lobe's at it plus at its mirror image
//! below the horizon (which is exact, and never larger: the folded direction is the nearer to the
//! lobe's axis).

use glam::{DVec2, DVec3};
use std::f64::consts::PI;

use crate::brdf::{Brdf, BrdfSample, Flags};
use crate::error::Result;
use crate::geometry::{self, Frame};
use crate::spectrum::{Channels, Value};
use serde::{Deserialize, Serialize};

/// How the pumped-up Phong model symmetrizes cos θ′ (the lecture's X).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PumpX {
    /// X = (cos θ′ + cos θ) / 2.
    Mean,
    /// X = cos θ′ · cos θ.
    Product,
    /// X = sqrt(cos θ′ · cos θ).
    Sqrt,
}

/// Which divisor X the Phong lobe k_s cos^n ψ is divided by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PhongVariant {
    /// The original Phong model: X = cos θ′ (not reciprocal).
    Original,
    /// The reciprocal Phong model: X = 1.
    Reciprocal,
    /// The max Phong model: X = max(cos θ′, cos θ).
    Max,
    /// The pumped-up reciprocal Phong model with a symmetric X.
    Pumped(PumpX),
}

/// A member of the Phong family (see the module docs): k_s cos^n ψ / X.
#[derive(Debug, Clone)]
pub struct Phong {
    channels: Channels,
    variant: PhongVariant,
    ks_spec: Value,
    ks: Vec<f64>,
    n: f64,
    /// `n` as an integer when it is one (≤ 2¹⁶): `powi` is several times faster than `powf`.
    n_int: Option<i32>,
    /// (n + 1) / 2π: normalization of cos^n ψ over the hemisphere around the reflection direction.
    lobe_norm: f64,
    /// 1 / (n + 1): the exponent that inverts the lobe's CDF.
    inv_n1: f64,
}

impl Phong {
    /// A Phong-family model with specular coefficient `ks` (≥ 0) and exponent `n` (≥ 0).
    pub fn new(variant: PhongVariant, ks: Value, n: f64, channels: &Channels) -> Result<Self> {
        channels.validate()?;
        ks.validate("ks", 0.0)?;
        if !n.is_finite() || n < 0.0 {
            return Err(crate::Error::spec(
                "n",
                format!("{n} must be a finite number ≥ 0"),
            ));
        }
        crate::spectrum::check_range(n, "n")?;
        Ok(Phong {
            channels: channels.clone(),
            variant,
            ks: ks.resolve(channels),
            ks_spec: ks,
            n,
            n_int: (n.fract() == 0.0 && n <= 65536.0).then_some(n as i32),
            lobe_norm: (n + 1.0) / (2.0 * PI),
            inv_n1: 1.0 / (n + 1.0),
        })
    }

    /// The original (non-reciprocal) Phong model, k_s cos^n ψ / cos θ′.
    pub fn original(ks: Value, n: f64, channels: &Channels) -> Result<Self> {
        Self::new(PhongVariant::Original, ks, n, channels)
    }

    /// The reciprocal Phong model, k_s cos^n ψ.
    pub fn reciprocal(ks: Value, n: f64, channels: &Channels) -> Result<Self> {
        Self::new(PhongVariant::Reciprocal, ks, n, channels)
    }

    /// The max Phong model, k_s cos^n ψ / max(cos θ′, cos θ).
    pub fn max(ks: Value, n: f64, channels: &Channels) -> Result<Self> {
        Self::new(PhongVariant::Max, ks, n, channels)
    }

    /// The pumped-up reciprocal Phong model, k_s cos^n ψ / X.
    pub fn pumped(ks: Value, n: f64, x: PumpX, channels: &Channels) -> Result<Self> {
        Self::new(PhongVariant::Pumped(x), ks, n, channels)
    }

    /// The variant.
    pub fn variant(&self) -> PhongVariant {
        self.variant
    }

    /// cos^n ψ for the angle ψ between the unit vectors `r` and `w` (0 where cos ψ ≤ 0).
    ///
    /// Taken from 1 − cos ψ = |r − w|²/2 rather than from r·w: a sharp lobe lives where
    /// cos ψ is within 1/n of 1, and the dot product, rounded to ~1e-16 and off by the 2⁻⁴⁰ in
    /// squared length that the library takes as unit ([`geometry::unit`]), moved cos^n ψ by
    /// n · 1e-16 and up to n · 9e-13 (4e-5 at n = 1e8, half the peak again at n = 1e12). The
    /// difference has neither error: for vectors of lengths 1 + ε it is 1 − cos ψ to relative
    /// ε plus (ε₁ − ε₂)², and it is symmetric in `r` and `w` bit for bit (reciprocity).
    #[inline]
    fn pow_cos(&self, r: DVec3, w: DVec3) -> f64 {
        let d = 0.5 * (r - w).length_squared();
        if !(d < 1.0) {
            return 0.0;
        }
        match self.n_int {
            // (1 − d)ⁿ rounds 1 − d to ~1e-16, n · 1e-16 ≤ 7e-12 here.
            Some(i) => (1.0 - d).powi(i),
            None => (self.n * (-d).ln_1p()).exp(),
        }
    }

    /// The shared core: cos^n ψ / X for unit directions above the horizon (0 when cos ψ ≤ 0).
    /// `wi` is ω′ (θ′), `wo` is ω (θ).
    #[inline]
    fn lobe_over_x(&self, wi: DVec3, wo: DVec3) -> f64 {
        // cos ψ = ω · (2 (N·ω′) N − ω′) = reflect_z(ω′) · ω.
        let lobe = self.pow_cos(geometry::reflect_z(wi), wo);
        if lobe == 0.0 {
            // cos^n ψ underflowed (a sharp lobe far from its axis) where X may have too (the
            // product and sqrt X at subnormal cosines): 0, not 0/0 (which `eval` saturated to
            // f32::MAX).
            return 0.0;
        }
        lobe / self.x(wi.z, wo.z)
    }

    /// The variant's divisor x(cos θi, cos θo) of cos^n ψ.
    #[inline]
    fn x(&self, ci: f64, co: f64) -> f64 {
        match self.variant {
            PhongVariant::Original => ci,
            PhongVariant::Reciprocal => 1.0,
            PhongVariant::Max => ci.max(co),
            PhongVariant::Pumped(PumpX::Mean) => 0.5 * (ci + co),
            PhongVariant::Pumped(PumpX::Product) => ci * co,
            PhongVariant::Pumped(PumpX::Sqrt) => (ci * co).sqrt(),
        }
    }

    /// Density of the cos^n ψ lobe around the reflection of `wo` (normalized over the
    /// hemisphere around that axis), at any direction `wi`, above the horizon or not.
    #[inline]
    fn lobe_pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.lobe_norm * self.pow_cos(geometry::reflect_z(wo), wi)
    }

    /// The density of [`Brdf::sample`] at a unit `wi` above the horizon: the lobe's at `wi` and
    /// at its mirror image below the horizon (the fold's other preimage).
    #[inline]
    fn folded_pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.lobe_pdf(wi, wo) + self.lobe_pdf(geometry::mirror_z(wi), wo)
    }
}

impl Brdf for Phong {
    fn channels(&self) -> &Channels {
        &self.channels
    }

    #[inline]
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let out = &mut out[..self.ks.len()];
        let Some((wi, wo)) = crate::geometry::upper_pair(wi, wo) else {
            out.fill(0.0);
            return;
        };
        // The product and sqrt X diverge at grazing angles (as the lecture warns); clamp so the
        // f32 output stays finite.
        let v = self.lobe_over_x(wi, wo);
        for (o, &k) in out.iter_mut().zip(&self.ks) {
            *o = (k * v).min(f32::MAX as f64) as f32;
        }
    }

    fn eval_wavelength(&self, wi: DVec3, wo: DVec3, nm: f64) -> f64 {
        if !crate::spectrum::is_wavelength(nm) {
            return f64::NAN; // not a wavelength: no value (Channels::mix_at)
        }
        match geometry::upper_pair(wi, wo) {
            Some((wi, wo)) => self.ks_spec.at(nm) * self.lobe_over_x(wi, wo),
            None => 0.0,
        }
    }

    fn flags(&self) -> Flags {
        Flags {
            reciprocal: self.variant != PhongVariant::Original,
            ..Flags::SMOOTH_SYMMETRIC
        }
    }

    /// The variants that divide by cos θ′ alone or by a product with it (1/cos θ′,
    /// 1/(cos θ′ cos θ), 1/√(cos θ′ cos θ)); the max and the mean stay bounded while the other
    /// direction is above the horizon.
    fn grows_at_horizon(&self) -> bool {
        matches!(
            self.variant,
            PhongVariant::Original
                | PhongVariant::Pumped(PumpX::Product)
                | PhongVariant::Pumped(PumpX::Sqrt)
        )
    }

    fn describe(&self) -> String {
        let name = match self.variant {
            PhongVariant::Original => "phong".to_string(),
            PhongVariant::Reciprocal => "reciprocal_phong".to_string(),
            PhongVariant::Max => "max_phong".to_string(),
            PhongVariant::Pumped(x) => format!(
                "pumped_phong x={}",
                serde_json::to_string(&x).unwrap_or_default()
            ),
        };
        format!(
            "{name} ks={} n={}",
            serde_json::to_string(&self.ks_spec).unwrap_or_default(),
            self.n
        )
    }

    /// The cos^n ψ lobe around reflect(wo), folded at the horizon (module docs); weight
    /// f_r cos θi / pdf with pdf the exact density of the fold (`Phong::folded_pdf`). The weight
    /// is (2π k_s/(n + 1)) · cos θi / X · cos^n ψ / (cos^n ψ + cos^n ψ′), ψ′ the mirror image's
    /// angle to the axis: the lobe's constant for the original model wherever nothing folds, and
    /// at least half of it where something does.
    fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
        let wo = geometry::unit(wo)?;
        if wo.z <= 0.0 || !geometry::in_unit_square(u) {
            return None;
        }
        // cos ψ = u₀^{1/(n+1)} has density (n + 1) cos^n ψ on [0, 1]. At u₀ = 0 the draw is
        // on the lobe's rim, where that density is 0: its pdf would be rounding noise. 1 − cos ψ
        // = −expm1(ln u₀ / (n + 1)) and sin ψ = √((1 − cos ψ)(1 + cos ψ)) keep a sharp lobe's
        // angle, which 1 − cos² ψ rounded to ~1e-16 (1e-4 of sin ψ at n = 1e12).
        let d = -(u.x.ln() * self.inv_n1).exp_m1();
        let cos_psi = 1.0 - d;
        if !(cos_psi > 0.0) {
            return None;
        }
        let sin_psi = (d * (2.0 - d)).max(0.0).sqrt();
        let (s, c) = crate::fastmath::sin_cos_2pi(u.y);
        let r = geometry::reflect_z(wo);
        let drawn = Frame::from_normal(r).to_world(DVec3::new(sin_psi * c, sin_psi * s, cos_psi));
        let wi = if drawn.z < 0.0 {
            geometry::mirror_z(drawn)
        } else {
            drawn
        };
        if !(wi.z > 0.0) {
            return None;
        }
        let pdf = self.folded_pdf(wi, wo);
        let v = self.lobe_over_x(wi, wo) * wi.z / pdf;
        if !(pdf > 0.0 && pdf.is_finite() && v.is_finite()) {
            return None;
        }
        for (w, &k) in weight[..self.ks.len()].iter_mut().zip(&self.ks) {
            *w = (k * v).min(f32::MAX as f64) as f32;
        }
        Some(BrdfSample {
            wi,
            pdf,
            delta: false,
        })
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let Some((wi, wo)) = geometry::upper_pair(wi, wo) else {
            return 0.0;
        };
        self.folded_pdf(wi, wo)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::albedo::quadrature;

    #[test]
    fn reciprocal_albedo_at_normal_incidence_is_2pi_ks_over_n_plus_2() {
        for n in [10.0, 50.0] {
            let p = Phong::reciprocal(Value::Rgb([0.2, 0.5, 0.9]), n, &Channels::Rgb).unwrap();
            let mut a = [0.0; 3];
            quadrature(&p, DVec3::Z, &mut a);
            for (c, ks) in [0.2, 0.5, 0.9].into_iter().enumerate() {
                let expect = 2.0 * PI * ks / (n + 2.0);
                // Gauss-Legendre in cos θ is exact for cos^(n+1) θ; the rest is f32 rounding.
                assert!(
                    (a[c] - expect).abs() < 1e-6 * expect,
                    "n={n}: {} vs {expect}",
                    a[c]
                );
            }
        }
    }

    #[test]
    fn lobe_peaks_at_the_mirror_direction() {
        let p = Phong::reciprocal(Value::Grey(0.5), 20.0, &Channels::Rgb).unwrap();
        let wi = geometry::spherical(0.5, 0.3);
        let mut f = [0.0f32; 3];
        p.eval(wi, geometry::reflect_z(wi), &mut f);
        assert!((f[0] - 0.5).abs() < 1e-6);
        // cos ψ < 0: zero.
        p.eval(wi, geometry::spherical(1.2, 0.3), &mut f);
        assert_eq!(f, [0.0; 3]);
    }

    #[test]
    fn variants_divide_as_the_lecture_says() {
        let (wi, wo) = (geometry::spherical(0.4, 0.0), geometry::spherical(0.6, 3.0));
        let base = Phong::reciprocal(Value::Grey(1.0), 5.0, &Channels::Rgb).unwrap();
        let mut f0 = [0.0f32; 3];
        base.eval(wi, wo, &mut f0);
        assert!(f0[0] > 0.0);
        let (ci, co) = (wi.z, wo.z);
        let cases = [
            (PhongVariant::Original, ci),
            (PhongVariant::Max, ci.max(co)),
            (PhongVariant::Pumped(PumpX::Mean), 0.5 * (ci + co)),
            (PhongVariant::Pumped(PumpX::Product), ci * co),
            (PhongVariant::Pumped(PumpX::Sqrt), (ci * co).sqrt()),
        ];
        for (v, x) in cases {
            let p = Phong::new(v, Value::Grey(1.0), 5.0, &Channels::Rgb).unwrap();
            let mut f = [0.0f32; 3];
            p.eval(wi, wo, &mut f);
            let expect = f0[0] as f64 / x;
            assert!((f[0] as f64 - expect).abs() < 1e-6 * expect, "{v:?}");
        }
    }

    #[test]
    fn original_phong_is_not_reciprocal() {
        let p = Phong::original(Value::Grey(1.0), 10.0, &Channels::Rgb).unwrap();
        assert!(!p.flags().reciprocal);
        let (wi, wo) = (geometry::spherical(0.2, 0.0), geometry::spherical(0.3, 3.1));
        let (mut a, mut b) = ([0.0f32; 3], [0.0f32; 3]);
        p.eval(wi, wo, &mut a);
        p.eval(wo, wi, &mut b);
        // The ratio is cos θ / cos θ′ ≠ 1.
        assert!((a[0] / b[0] - (wo.z / wi.z) as f32).abs() < 1e-5);
        assert!((a[0] - b[0]).abs() > 1e-3 * a[0]);
    }

    #[test]
    fn sampler_passes_chi_square() {
        use crate::models::test_util::chi2_models;
        let v = |variant, n| Phong::new(variant, Value::Grey(0.5), n, &Channels::Rgb).unwrap();
        chi2_models(&[
            &v(PhongVariant::Original, 20.0),
            &v(PhongVariant::Reciprocal, 2.0),
            &v(PhongVariant::Max, 0.0),
            &v(PhongVariant::Pumped(PumpX::Product), 200.0),
        ]);
    }

    /// The original model's f_r cos θi is k_s cos^n ψ, which the lobe's density (n + 1)/2π
    /// cos^n ψ follows exactly: every weight is 2π k_s/(n + 1) where nothing folds, and between
    /// half of that and that where the fold adds the mirror image's density (never larger than
    /// the direction's own). No draw is refused, at any view.
    #[test]
    fn original_phong_weights_are_the_lobe_constant_and_nothing_is_refused() {
        let n = 20.0;
        let p = Phong::original(Value::Grey(0.5), n, &Channels::Rgb).unwrap();
        let c = 2.0 * PI * 0.5 / (n + 1.0);
        let mut rng = crate::rng::Pcg32::new(3);
        for deg in [0.0f64, 30.0, 60.0, 80.0, 89.0] {
            let wo = geometry::spherical(deg.to_radians(), 0.7);
            let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
            for _ in 0..20_000 {
                let mut w = [0.0f32; 3];
                let s = p
                    .sample(wo, rng.next_dvec2(), &mut w)
                    .expect("no draw is refused");
                assert!(s.wi.z > 0.0);
                lo = lo.min(w[0] as f64);
                hi = hi.max(w[0] as f64);
            }
            assert!(
                hi <= c * (1.0 + 1e-6) && lo >= 0.5 * c * (1.0 - 1e-6),
                "{deg}°: {lo}..{hi} vs {c}"
            );
            if deg == 0.0 {
                // The lobe around the normal: nothing reaches the horizon's mirror side.
                assert!(lo >= c * (1.0 - 1e-6), "{lo} vs {c}");
            }
        }
    }

    /// At u.x = 0 the draw lies on the lobe's rim, where its density is 0: no sample. (Its
    /// pdf was rounding noise, 2.7e-300 at 40° where `pdf` gives 0.) A draw that is kept agrees
    /// with `pdf` to the contract's 1e-7 (both f64).
    #[test]
    fn a_draw_on_the_lobes_rim_is_none_or_has_its_density() {
        let p = Phong::original(Value::Grey(0.5), 20.0, &Channels::Rgb).unwrap();
        let mut w = [0.0f32; 3];
        for deg in [0.0f64, 20.0, 39.6, 60.0, 85.0] {
            for k in 0..64 {
                let wo = geometry::spherical(deg.to_radians(), 0.0914 + 0.1 * k as f64);
                for uy in (0..32)
                    .map(|j| j as f64 / 32.0)
                    .chain([0.15794286357332743])
                {
                    if let Some(s) = p.sample(wo, DVec2::new(0.0, uy), &mut w) {
                        let q = p.pdf(s.wi, wo);
                        assert!(
                            (s.pdf - q).abs() <= 1e-7 * q,
                            "{deg}° {k} u.y {uy}: {} vs {q}",
                            s.pdf
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn invalid_inputs_give_zero() {
        let p = Phong::max(Value::Grey(1.0), 10.0, &Channels::Rgb).unwrap();
        for (wi, wo) in [
            (DVec3::new(0.0, 0.0, -1.0), DVec3::Z),
            (DVec3::Z, DVec3::new(1.0, 0.0, 0.0)),
            (DVec3::ZERO, DVec3::Z),
            (DVec3::new(f64::NAN, 0.0, 1.0), DVec3::Z),
            (DVec3::Z, DVec3::splat(f64::INFINITY)),
        ] {
            let mut f = [1.0f32; 3];
            p.eval(wi, wo, &mut f);
            assert_eq!(f, [0.0; 3]);
            assert_eq!(p.pdf(wi, wo), 0.0);
            assert_eq!(p.eval_wavelength(wi, wo, 550.0), 0.0);
        }
        // Grazing pair for the product X: huge but finite.
        let p = Phong::pumped(Value::Grey(1.0), 10.0, PumpX::Product, &Channels::Rgb).unwrap();
        let mut f = [0.0f32; 3];
        p.eval(
            DVec3::new(1.0, 0.0, 1e-30),
            DVec3::new(-1.0, 0.0, 1e-30),
            &mut f,
        );
        assert!(f.iter().all(|x| x.is_finite() && *x > 1e30), "{f:?}");
        assert!(Phong::reciprocal(Value::Grey(1.0), -1.0, &Channels::Rgb).is_err());
        assert!(Phong::reciprocal(Value::Grey(-1.0), 1.0, &Channels::Rgb).is_err());
    }
    /// cos^n ψ of a huge exponent from 1 − cos ψ = |reflect(ω′) − ω|²/2, not from the dot
    /// product: cos ψ rounded to ~1e-16 and the 2⁻⁴⁰ in squared length that the library takes
    /// as unit moved cos^n ψ by n · 1e-16 and up to n · 9e-13. At the peak, pairs of lengths
    /// 1 ± 2e-13 read 0.50002 (n = 1e8), 0.502 (1e10) and 0.746 (1e12) for k_s = 0.5, and at
    /// n = 1e12 a draw from a rescaled view had a density 1e-4 from the unit view's.
    #[test]
    fn huge_exponents_keep_the_peak_and_their_density() {
        for variant in [PhongVariant::Reciprocal, PhongVariant::Original] {
            for n in [1e8, 1e10, 1e12] {
                let p = Phong::new(variant, Value::Grey(0.5), n, &Channels::Rgb).unwrap();
                let wi = geometry::spherical(0.5, 0.3);
                let wo = geometry::reflect_z(wi);
                let peak = 0.5
                    / if variant == PhongVariant::Original {
                        wi.z
                    } else {
                        1.0
                    };
                for (a, b) in [(1.0, 1.0), (1.0 + 2e-13, 1.0), (1.0, 1.0 - 2e-13)] {
                    let mut f = [0.0f32; 3];
                    p.eval(wi * a, wo * b, &mut f);
                    // f32 rounding of the value.
                    assert!(
                        (f[0] as f64 / peak - 1.0).abs() < 1e-7,
                        "{variant:?} n = {n:e}, lengths {a}, {b}: {} vs {peak}",
                        f[0]
                    );
                }
                if n == 1e12 {
                    let opts = crate::testkit::Contract::default();
                    if let Err(v) = crate::testkit::check_contract(&p, &opts) {
                        panic!("{variant:?} n = {n:e}:\n{}", v.join("\n"));
                    }
                }
            }
        }
    }
}
