//! The lecture's models (Lambert, mirror, refractor, the Phong family, Cook-Torrance) as
//! specifications: samplers pass chi-square tests, weights are f·cos/pdf, energy is what the
//! closed forms say, reciprocity holds where it is claimed and fails where it is not.

use brdftab::analysis::albedo::quadrature;
use brdftab::analysis::chi2::{self, Chi2Options};
use brdftab::geometry;
use brdftab::spec::ModelSpec;
use brdftab::testkit::Pcg32;
use brdftab::{Brdf, Channels};
use glam::{DVec2, DVec3};
use proptest::prelude::*;

fn build(json: &str) -> Box<dyn Brdf + Send + Sync> {
    ModelSpec::parse(json)
        .unwrap_or_else(|e| panic!("{json}: {e}"))
        .build(&Channels::Rgb)
        .unwrap_or_else(|e| panic!("{json}: {e}"))
}

/// Every smooth (non-delta) lecture model with parameters that exercise sharp and broad lobes.
const SMOOTH: &[&str] = &[
    r#"{"model": "lambert", "kd": [0.1, 0.2, 0.3]}"#,
    r#"{"model": "phong", "ks": 0.3, "n": 12}"#,
    r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 2}"#,
    r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 60}"#,
    r#"{"model": "max_phong", "ks": 0.5, "n": 20}"#,
    r#"{"model": "pumped_phong", "ks": 0.5, "n": 20, "x": "mean"}"#,
    r#"{"model": "pumped_phong", "ks": 0.5, "n": 20, "x": "product"}"#,
    r#"{"model": "pumped_phong", "ks": 0.5, "n": 20, "x": "sqrt"}"#,
    r#"{"model": "cook_torrance", "m": 0.15, "fresnel": {"conductor": "Au"}}"#,
    r#"{"model": "cook_torrance", "m": 0.5, "ks": 0.7, "fresnel": {"eta": 1.5}}"#,
    r#"{"model": "cook_torrance", "m": 1.2}"#,
];

/// Viewing angles for sampler tests, from normal to grazing (degrees).
const THETAS: &[f64] = &[0.0, 40.0, 75.0, 88.0];

/// Chi-square tests of every model in `specs` at every angle of [`THETAS`], Šidák-corrected over
/// all [`SMOOTH`] × [`THETAS`] cases (overall level 1%).
fn chi_square(specs: &[&str]) {
    let opts = Chi2Options {
        samples: 100_000,
        cos_bins: 24,
        phi_bins: 48,
        seed: 7,
        ..Default::default()
    };
    let alpha = chi2::sidak(0.01, SMOOTH.len() * THETAS.len());
    let mut failures = Vec::new();
    for json in specs {
        let brdf = build(json);
        for &deg in THETAS {
            let wo = geometry::spherical(deg.to_radians(), 0.7);
            let r = chi2::test(&*brdf, wo, &opts);
            if !r.passes(alpha) {
                failures.push(format!("{json} at {deg}°: {r:?}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "chi-square failures:\n{}",
        failures.join("\n")
    );
}

#[test]
fn chi_square_lambert_and_phong_family() {
    chi_square(&SMOOTH[..8]);
}

#[test]
fn chi_square_cook_torrance() {
    chi_square(&SMOOTH[8..]);
}

#[test]
fn every_smooth_spec_is_sampled_by_a_chi_square_test() {
    // Guards the index split above when SMOOTH grows.
    assert!(SMOOTH[..8].iter().all(|s| !s.contains("cook_torrance")));
    assert!(SMOOTH[8..].iter().all(|s| s.contains("cook_torrance")));
}

/// The chi-square test has power: a Phong sampler with a lying pdf (claims n+1 when it samples n)
/// must fail. This guards against a harness that passes everything.
#[test]
fn chi_square_rejects_a_wrong_pdf() {
    struct Wrong(Box<dyn Brdf + Send + Sync>, Box<dyn Brdf + Send + Sync>);
    impl Brdf for Wrong {
        fn channels(&self) -> &Channels {
            self.0.channels()
        }
        fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
            self.0.eval(wi, wo, out)
        }
        fn flags(&self) -> brdftab::Flags {
            self.0.flags()
        }
        fn describe(&self) -> String {
            "wrong".into()
        }
        fn sample(&self, wo: DVec3, u: DVec2, w: &mut [f32]) -> Option<brdftab::BrdfSample> {
            self.0.sample(wo, u, w)
        }
        fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
            self.1.pdf(wi, wo)
        }
    }
    let w = Wrong(
        build(r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 20}"#),
        build(r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 24}"#),
    );
    let opts = Chi2Options {
        samples: 100_000,
        cos_bins: 24,
        phi_bins: 48,
        ..Default::default()
    };
    let r = chi2::test(&w, geometry::spherical(0.5, 0.0), &opts);
    assert!(!r.passes(0.01), "{r:?}");
}

#[test]
fn sample_weight_is_f_cos_over_pdf_and_pdf_agrees() {
    let mut rng = Pcg32::new(11);
    for json in SMOOTH {
        let brdf = build(json);
        for &deg in THETAS {
            let wo = geometry::spherical(deg.to_radians(), 1.9);
            let mut accepted = 0;
            for _ in 0..2000 {
                let mut w = [0.0f32; 3];
                let Some(s) = brdf.sample(wo, rng.next_dvec2(), &mut w) else {
                    continue;
                };
                accepted += 1;
                assert!(!s.delta && s.wi.z > 0.0 && (s.wi.length() - 1.0).abs() < 1e-9);
                let pdf = brdf.pdf(s.wi, wo);
                assert!(
                    (pdf - s.pdf).abs() <= 1e-9 * s.pdf,
                    "{json} {deg}°: pdf() {pdf} vs sample {}",
                    s.pdf
                );
                let mut f = [0.0f32; 3];
                brdf.eval(s.wi, wo, &mut f);
                for c in 0..3 {
                    let expect = f[c] as f64 * s.wi.z / s.pdf;
                    assert!(
                        (w[c] as f64 - expect).abs() <= 1e-5 * expect.abs() + 1e-12,
                        "{json} {deg}°: weight {} vs f cos/pdf {expect}",
                        w[c]
                    );
                }
            }
            assert!(
                accepted > 1000,
                "{json} {deg}°: only {accepted} of 2000 accepted"
            );
        }
    }
}

#[test]
fn white_furnace_lambert_one_over_pi() {
    let brdf = build(&format!(
        r#"{{"model": "lambert", "kd": {}}}"#,
        1.0 / std::f64::consts::PI
    ));
    let mut rng = Pcg32::new(3);
    for &deg in THETAS {
        let wo = geometry::spherical(deg.to_radians(), 0.3);
        let n = 10_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let mut w = [0.0f32; 3];
            let s = brdf
                .sample(wo, rng.next_dvec2(), &mut w)
                .expect("lambert always samples");
            assert!(s.pdf > 0.0);
            sum += w[1] as f64;
        }
        // Every weight is exactly k_d π = 1 (up to f32 rounding of k_d).
        assert!(
            (sum / n as f64 - 1.0).abs() < 1e-6,
            "{deg}°: {}",
            sum / n as f64
        );
    }
}

/// The mean sampled weight is a Monte Carlo estimate of the albedo ∫ f cos dωi, which for the
/// reciprocal models equals the quadrature albedo a(wo). Checks sampler, pdf and weight together
/// against an independent integration.
#[test]
fn mean_weight_estimates_the_albedo() {
    let specs = [
        r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 10}"#,
        r#"{"model": "max_phong", "ks": 0.5, "n": 10}"#,
        r#"{"model": "pumped_phong", "ks": 0.5, "n": 10, "x": "mean"}"#,
        r#"{"model": "cook_torrance", "m": 0.5, "fresnel": {"conductor": "Cu"}}"#,
    ];
    let mut rng = Pcg32::new(99);
    for json in specs {
        let brdf = build(json);
        for deg in [0.0f64, 30.0, 60.0] {
            let wo = geometry::spherical(deg.to_radians(), 0.0);
            let mut a = [0.0; 3];
            quadrature(&*brdf, wo, &mut a);
            let n = 200_000;
            let (mut sum, mut sum2) = (0.0, 0.0);
            for _ in 0..n {
                let mut w = [0.0f32; 3];
                if brdf.sample(wo, rng.next_dvec2(), &mut w).is_some() {
                    sum += w[0] as f64;
                    sum2 += (w[0] as f64).powi(2);
                }
            }
            let mean = sum / n as f64;
            let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
            assert!(
                (mean - a[0]).abs() < 5.0 * se + 1e-4 * a[0],
                "{json} {deg}°: MC {mean} ± {se} vs quadrature {}",
                a[0]
            );
        }
    }
}

#[test]
fn lambert_albedo_is_kd_pi() {
    let brdf = build(r#"{"model": "lambert", "kd": 0.25}"#);
    for deg in [0.0f64, 20.0, 50.0, 80.0, 89.0] {
        let wi = geometry::spherical(deg.to_radians(), 1.0);
        let (mut a, mut q) = ([0.0; 3], [0.0; 3]);
        brdf.albedo(wi, &mut a);
        quadrature(&*brdf, wi, &mut q);
        let expect = 0.25 * std::f64::consts::PI;
        assert!((a[0] - expect).abs() < 1e-12);
        assert!((q[0] - expect).abs() < 1e-6 * expect);
    }
}

#[test]
fn delta_models_sample_one_direction() {
    let mirror = build(r#"{"model": "mirror", "fresnel": {"conductor": "Au"}}"#);
    let refr = build(r#"{"model": "refractor", "eta": 1.5}"#);
    for b in [&mirror, &refr] {
        assert!(b.flags().delta);
        let wo = geometry::spherical(0.8, 0.1);
        let mut w1 = [0.0f32; 3];
        let mut w2 = [0.0f32; 3];
        let s1 = b.sample(wo, DVec2::new(0.1, 0.2), &mut w1).unwrap();
        let s2 = b.sample(wo, DVec2::new(0.9, 0.6), &mut w2).unwrap();
        assert_eq!(s1, s2);
        assert_eq!(w1, w2);
        assert!(s1.delta && s1.pdf == 1.0);
        assert!(w1.iter().all(|&x| x > 0.0 && x <= 1.0));
        assert_eq!(b.pdf(s1.wi, wo), 0.0);
        let mut f = [1.0f32; 3];
        b.eval(s1.wi, wo, &mut f);
        assert_eq!(f, [0.0; 3]);
    }
    // Gold mirror: red k_r above blue.
    let mut w = [0.0f32; 3];
    mirror.sample(DVec3::Z, DVec2::ZERO, &mut w).unwrap();
    assert!(w[0] > 0.9 && w[2] < 0.45, "{w:?}");
    assert!(refr.flags().transmission);
}

#[test]
fn eval_wavelength_agrees_with_channels_at_rgb_wavelengths() {
    // Spectral data (a metal's n, k) is read for RGB at the representative wavelengths, so a
    // model with spectral or grey parameters gives its RGB channels there.
    let wi = geometry::spherical(0.5, 0.0);
    let wo = geometry::spherical(0.45, 3.0);
    for json in SMOOTH.iter().filter(|j| !j.contains(": [")) {
        let brdf = build(json);
        let mut f = [0.0f32; 3];
        brdf.eval(wi, wo, &mut f);
        for (c, &nm) in brdftab::spectrum::RGB_WAVELENGTHS.iter().enumerate() {
            let v = brdf.eval_wavelength(wi, wo, nm);
            assert!(
                (v - f[c] as f64).abs() <= 1e-6 * v.abs() + 1e-12,
                "{json} {nm}: {v} vs {}",
                f[c]
            );
        }
    }
    // A spectral channel set uses the metal's own data.
    let spec =
        ModelSpec::parse(r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#)
            .unwrap();
    let ch = Channels::linspace(400.0, 700.0, 7).unwrap();
    let b = spec.build(&ch).unwrap();
    let mut f = [0.0f32; 7];
    b.eval(wi, wo, &mut f);
    for (i, &x) in f.iter().enumerate() {
        let nm = 400.0 + 50.0 * i as f64;
        assert!((b.eval_wavelength(wi, wo, nm) - x as f64).abs() < 1e-6 * x as f64);
    }
    assert!(
        f[6] > f[0] * 1.5,
        "gold reflects red much more than violet: {f:?}"
    );
}

#[test]
fn an_rgb_parameter_at_a_wavelength_keeps_its_colour() {
    // RGB parameters are read at a wavelength through the colour-preserving basis: a Lambertian
    // (linear in k_d) gives the basis mix of its RGB channels, a spectrum whose CIE projection
    // is its RGB value.
    let (wi, wo) = (
        geometry::spherical(0.5, 0.0),
        geometry::spherical(0.45, 3.0),
    );
    let brdf = build(SMOOTH[0]);
    let mut f = [0.0f32; 3];
    brdf.eval(wi, wo, &mut f);
    for nm in [380.0, 444.0, 500.0, 526.0, 600.0, 645.0, 720.0] {
        let b = brdftab::colour::rgb_basis_at(nm);
        let want: f64 = (0..3).map(|c| b[c] * f[c] as f64).sum();
        let v = brdf.eval_wavelength(wi, wo, nm);
        assert!((v - want).abs() <= 1e-7 * want, "{nm}: {v} vs {want}");
    }
    let back = brdftab::colour::srgb_of(|nm| brdf.eval_wavelength(wi, wo, nm));
    for c in 0..3 {
        assert!(
            (back[c] - f[c] as f64).abs() <= 1e-7 * f[c] as f64,
            "{back:?} vs {f:?}"
        );
    }
}

#[test]
fn original_phong_is_not_reciprocal_and_says_so() {
    let b = build(r#"{"model": "phong", "ks": 0.5, "n": 10}"#);
    assert!(!b.flags().reciprocal);
    let (wi, wo) = (geometry::spherical(0.3, 0.0), geometry::spherical(0.6, 3.0));
    let (mut a, mut c) = ([0.0f32; 3], [0.0f32; 3]);
    b.eval(wi, wo, &mut a);
    b.eval(wo, wi, &mut c);
    assert!(
        a[0] > 0.0 && (a[0] - c[0]).abs() > 0.05 * a[0],
        "{a:?} {c:?}"
    );
}

fn upper() -> impl Strategy<Value = DVec3> {
    (0.0f64..1.0, 0.0f64..1.0).prop_map(|(a, b)| geometry::uniform_hemisphere(DVec2::new(a, b)))
}

fn any_dir() -> impl Strategy<Value = DVec3> {
    (-2.0f64..2.0, -2.0f64..2.0, -2.0f64..2.0).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

const RECIPROCAL: &[&str] = &[
    r#"{"model": "lambert", "kd": 0.3}"#,
    r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 7}"#,
    r#"{"model": "max_phong", "ks": 0.5, "n": 7}"#,
    r#"{"model": "pumped_phong", "ks": 0.5, "n": 7, "x": "mean"}"#,
    r#"{"model": "pumped_phong", "ks": 0.5, "n": 7, "x": "product"}"#,
    r#"{"model": "pumped_phong", "ks": 0.5, "n": 7, "x": "sqrt"}"#,
    r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Ag"}}"#,
    r#"{"model": "mirror"}"#,
];

proptest! {
    #[test]
    fn reciprocity_where_claimed(wi in upper(), wo in upper()) {
        for json in RECIPROCAL {
            let b = build(json);
            prop_assert!(b.flags().reciprocal, "{}", json);
            let (mut a, mut c) = ([0.0f32; 3], [0.0f32; 3]);
            b.eval(wi, wo, &mut a);
            b.eval(wo, wi, &mut c);
            for k in 0..3 {
                let tol = 1e-5 * a[k].abs().max(c[k].abs()) + 1e-30;
                prop_assert!((a[k] - c[k]).abs() <= tol, "{}: {:?} vs {:?}", json, a, c);
            }
        }
    }

    #[test]
    fn below_horizon_nan_and_zero_give_zero(wi in any_dir(), wo in any_dir(), which in 0usize..4) {
        let (wi, wo) = match which {
            0 => (wi, DVec3::new(wo.x, wo.y, -wo.z.abs())),
            1 => (DVec3::new(wi.x, wi.y, -wi.z.abs()), wo),
            2 => (DVec3::new(f64::NAN, wi.y, wi.z), wo),
            _ => (wi, DVec3::ZERO),
        };
        for json in SMOOTH.iter().chain(RECIPROCAL) {
            let b = build(json);
            let mut f = [1.0f32; 3];
            b.eval(wi, wo, &mut f);
            prop_assert_eq!(f, [0.0f32; 3], "{}", json);
            prop_assert_eq!(b.pdf(wi, wo), 0.0);
            prop_assert_eq!(b.eval_wavelength(wi, wo, 550.0), 0.0);
        }
    }

    #[test]
    fn values_are_finite_and_nonnegative(wi in any_dir(), wo in any_dir()) {
        for json in SMOOTH {
            let b = build(json);
            let mut f = [0.0f32; 3];
            b.eval(wi, wo, &mut f);
            prop_assert!(f.iter().all(|x| x.is_finite() && *x >= 0.0), "{}: {:?}", json, f);
            let p = b.pdf(wi, wo);
            prop_assert!(p.is_finite() && p >= 0.0);
        }
    }
}
