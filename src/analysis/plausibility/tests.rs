//! The plausibility check's unit tests: the albedo angles it refuses, the lecture's models, and a
//! deterministic, serializable report.

use super::*;

/// [`super::check`] with angles every test gives inside [0°, 90°).
fn check(brdf: &dyn Brdf, opts: &Options) -> Report {
    super::check(brdf, opts).unwrap()
}
use crate::models::lambert::Lambert;
use crate::spectrum::{Channels, Value};

/// Test-only original Phong: k_s cos^n ψ / cos θ′ (θ′ = angle of wi).
struct OriginalPhong;

impl Brdf for OriginalPhong {
    fn channels(&self) -> &Channels {
        &Channels::Rgb
    }
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let v = match geometry::upper_pair(wi, wo) {
            Some((wi, wo)) => 0.5 * geometry::reflect_z(wi).dot(wo).max(0.0).powi(20) / wi.z,
            None => 0.0,
        };
        out[..3].fill(v as f32);
    }
    fn flags(&self) -> Flags {
        Flags {
            reciprocal: false,
            ..Flags::SMOOTH_SYMMETRIC
        }
    }
    fn describe(&self) -> String {
        "test original phong".into()
    }
}

/// Test-only Cook-Torrance with F = 1: normalized Beckmann D, V-cavity G, D G / (4 cos θ cos θ′).
struct CookTorrance {
    m: f64,
}

impl Brdf for CookTorrance {
    fn channels(&self) -> &Channels {
        &Channels::Rgb
    }
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let v = match geometry::upper_pair(wi, wo) {
            Some((l, v)) => {
                let h = (l + v).normalize();
                let (nh, nl, nv, vh) = (h.z, l.z, v.z, v.dot(h));
                let tan2 = (1.0 - nh * nh) / (nh * nh);
                let m2 = self.m * self.m;
                let d = (-tan2 / m2).exp() / (std::f64::consts::PI * m2 * nh.powi(4));
                let g = (2.0 * nh * nv / vh).min(2.0 * nh * nl / vh).min(1.0);
                d * g / (4.0 * nl * nv)
            }
            None => 0.0,
        };
        out[..3].fill(v as f32);
    }
    fn flags(&self) -> Flags {
        Flags::SMOOTH_SYMMETRIC
    }
    fn describe(&self) -> String {
        "test cook-torrance".into()
    }
}

/// Test-only BRDF with a negative value somewhere.
struct Negative;

impl Brdf for Negative {
    fn channels(&self) -> &Channels {
        &Channels::Rgb
    }
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let v = if wi.z > 0.0 && wo.z > 0.0 {
            0.1 - wi.x * wo.x
        } else {
            0.0
        };
        out[..3].fill(v as f32);
    }
    fn flags(&self) -> Flags {
        Flags::SMOOTH_SYMMETRIC
    }
    fn describe(&self) -> String {
        "test negative".into()
    }
}

fn quick() -> Options {
    Options {
        pairs: 4000,
        thetas_deg: vec![0.0, 30.0, 60.0, 80.0, 89.0],
        ..Options::default()
    }
}

#[test]
fn albedo_angles_at_or_beyond_the_horizon_are_refused() {
    // Ward's albedo at θ′ = 90° has no finite limit: a report with it would be a number
    // of the quadrature, not of the model.
    let ward = crate::spec::ModelSpec::parse(
        r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
    )
    .unwrap()
    .build(&Channels::Rgb)
    .unwrap();
    for bad in [90.0, 120.0, -1.0, f64::NAN] {
        let opts = Options {
            pairs: 10,
            thetas_deg: vec![10.0, bad],
            ..Options::default()
        };
        match super::check(&*ward, &opts) {
            Err(Error::InvalidArgument { name, .. }) => assert_eq!(name, "thetas_deg"),
            other => panic!("{bad}: {other:?}"),
        }
    }
    let edge = Options {
        pairs: 10,
        thetas_deg: vec![0.0, 89.9],
        ..Options::default()
    };
    assert!(super::check(&*ward, &edge).unwrap().max_albedo.is_finite());
}

#[test]
fn lambert_is_plausible_below_one_over_pi_and_not_above() {
    let ok = Lambert::new(Value::Grey(0.3), &Channels::Rgb).unwrap();
    let r = check(&ok, &quick());
    assert!(r.plausible(), "{r}");
    assert_eq!(r.min_value, 0.3f32 as f64);
    assert_eq!(r.max_reciprocity_error, 0.0);
    let bright = Lambert::new(Value::Grey(0.5), &Channels::Rgb).unwrap();
    let r = check(&bright, &quick());
    assert!(r.positive && r.reciprocal && !r.energy_conserving, "{r}");
    assert!((r.max_albedo - 0.5 * std::f64::consts::PI).abs() < 1e-6);
}

#[test]
fn original_phong_is_not_reciprocal() {
    let r = check(&OriginalPhong, &quick());
    assert!(r.positive, "{r}");
    assert!(!r.reciprocal && r.max_reciprocity_error > 0.5, "{r}");
    assert!(r.max_reciprocity_at.is_some());
    assert!(!r.declared.reciprocal);
}

#[test]
fn cook_torrance_albedo_grows_at_grazing_angles() {
    // The lecture's "cheat": 1/(N·L) lets the albedo climb towards grazing incidence (with
    // the V-cavity G and F = 1 it tends to 1 instead of falling off like a real rough surface).
    let r = check(&CookTorrance { m: 0.6 }, &quick());
    assert!(r.positive && r.reciprocal, "{r}");
    let a: Vec<f64> = r.albedo_curve.iter().map(|p| p.albedo[0]).collect();
    assert!(a.windows(2).all(|w| w[1] > w[0]), "{a:?}");
    assert!(a[4] > 1.2 * a[0], "{r}");
    assert_eq!(r.max_albedo_theta_deg, 89.0);
}

#[test]
fn albedos_that_pass_1_only_past_89_degrees_fail_energy_conservation() {
    // The exact albedos (`brdftab albedo`): original Phong k_s = 0.5, n = 20: 0.794 at 89°,
    // 7.28 at 89.9°; Ward k_s = 1, α = 0.5: 0.498 at 89°, 1.48 at 89.9°, 4.66 at 89.99°.
    let o = Options {
        pairs: 200,
        ..Options::default()
    };
    for (spec, at_89) in [
        (r#"{"model": "phong", "ks": 0.5, "n": 20}"#, 0.794),
        (
            r#"{"model": "ward", "ks": 1, "alpha_x": 0.5, "alpha_y": 0.5}"#,
            0.498,
        ),
    ] {
        let r = check(&*model(spec), &o);
        let a89 = r
            .albedo_curve
            .iter()
            .find(|p| p.theta_deg == 89.0)
            .unwrap()
            .albedo[0];
        assert!((a89 - at_89).abs() < 2e-3, "{spec}: {a89}");
        assert!(!r.energy_conserving && r.max_albedo > 4.0, "{spec}: {r}");
        assert_eq!(r.max_albedo_theta_deg, 89.99, "{spec}");
    }
    // Bounded albedos keep their verdicts: reciprocal Phong peaks at normal incidence.
    let r = check(
        &*model(r#"{"model": "reciprocal_phong", "ks": 1, "n": 20}"#),
        &o,
    );
    assert!(r.energy_conserving && r.max_albedo_theta_deg == 0.0, "{r}");
}

fn model(spec: &str) -> Box<dyn Brdf + Send + Sync> {
    crate::spec::ModelSpec::parse(spec)
        .unwrap()
        .build(&Channels::Rgb)
        .unwrap()
}

#[test]
fn real_lecture_models() {
    let o = quick();
    let r = check(&*model(r#"{"model": "phong", "ks": 0.5, "n": 20}"#), &o);
    assert!(r.positive && !r.reciprocal && !r.declared.reciprocal, "{r}");
    for spec in [
        r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 20}"#,
        r#"{"model": "max_phong", "ks": 0.5, "n": 20}"#,
        r#"{"model": "pumped_phong", "ks": 0.5, "n": 20, "x": "product"}"#,
    ] {
        let r = check(&*model(spec), &o);
        assert!(r.positive && r.reciprocal, "{spec}: {r}");
    }
    // Reciprocal Phong loses energy at grazing incidence, X = cos θ cos θ′ pumps it up
    // without bound.
    let r = check(
        &*model(r#"{"model": "reciprocal_phong", "ks": 1, "n": 20}"#),
        &o,
    );
    assert!(r.energy_conserving && r.max_albedo_theta_deg == 0.0, "{r}");
    let r = check(
        &*model(r#"{"model": "pumped_phong", "ks": 1, "n": 20, "x": "product"}"#),
        &o,
    );
    assert!(
        !r.energy_conserving && r.max_albedo_theta_deg == 89.0,
        "{r}"
    );
    // Cook-Torrance with gold: the albedo climbs towards grazing incidence.
    let r = check(
        &*model(r#"{"model": "cook_torrance", "m": 0.6, "fresnel": {"conductor": "Au"}}"#),
        &o,
    );
    assert!(r.positive && r.reciprocal, "{r}");
    let a: Vec<f64> = r.albedo_curve.iter().map(|p| p.albedo[2]).collect();
    assert!(a[4] > 1.2 * a[0], "{r}");
    assert_eq!(r.max_albedo_theta_deg, 89.0);
}

#[test]
fn negative_values_are_found() {
    let r = check(&Negative, &quick());
    assert!(!r.positive && r.min_value < -0.5, "{r}");
}

#[test]
fn report_is_deterministic_and_serializes() {
    let a = check(&OriginalPhong, &quick());
    let b = check(&OriginalPhong, &quick());
    assert_eq!(a, b);
    let json = serde_json::to_value(&a).unwrap();
    for key in [
        "positive",
        "min_value",
        "reciprocal",
        "max_reciprocity_error",
        "energy_conserving",
        "max_albedo",
        "max_albedo_theta_deg",
        "declared",
        "albedo_curve",
    ] {
        assert!(json.get(key).is_some(), "{key} missing in {json}");
    }
}
