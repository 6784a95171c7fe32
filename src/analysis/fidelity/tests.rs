//! The fidelity figures' unit tests: the albedo quadrature, azimuth means, the grazing band and
//! the checks of the options.

#[test]
fn albedo_angles_outside_the_upper_hemisphere_are_refused() {
    let l = crate::models::lambert::Lambert::new(
        crate::spectrum::Value::Grey(0.3),
        &crate::spectrum::Channels::Rgb,
    )
    .unwrap();
    for bad in [90.0, 95.0, -1.0, f64::NAN] {
        let opts = FidelityOptions {
            albedo_thetas_deg: vec![10.0, bad],
            ..Default::default()
        };
        match albedo_error(&l, &l, &opts) {
            Err(Error::InvalidArgument { name, .. }) => assert_eq!(name, "albedo_thetas_deg"),
            r => panic!("{bad}: {r:?}"),
        }
    }
}

use super::*;
use crate::error::Error;
use crate::models::lambert::Lambert;
use crate::spec::ModelSpec;
use crate::spectrum::{Channels, Value};

#[test]
fn the_quadrature_integrates_lambert_and_a_sharp_lobe() {
    // f = kd: ∫ kd cos θo dω = π kd at every θ′.
    let l = Lambert::new(Value::Rgb([0.1, 0.2, 0.3]), &Channels::Rgb).unwrap();
    let (a, b) = albedo_pair(&l, &l, &FidelityOptions::default()).unwrap();
    for (x, y) in a.iter().zip(&b) {
        for (ch, kd) in [0.1f32, 0.2, 0.3].iter().enumerate() {
            let want = std::f64::consts::PI * *kd as f64;
            // The product rule is exact for the cosine except on the segments the horizon
            // cuts, whose boundary is not polynomial (worst at θ′ = 89°): 1e-4 is 100×
            // below the 1 % the albedo is judged to, and the table and its source are
            // integrated by the same rule.
            assert!((x[ch] - want).abs() < 1e-4 * want, "{} {want}", x[ch]);
            assert_eq!(x[ch], y[ch]);
        }
    }
    // Reciprocal Phong n = 1000 (about 2° wide): 2π ks/(n + 2) at normal incidence.
    let p = ModelSpec::parse(r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 1000}"#)
        .unwrap()
        .build(&Channels::Rgb)
        .unwrap();
    let opts = FidelityOptions {
        albedo_thetas_deg: vec![0.0],
        ..Default::default()
    };
    let (a, _) = albedo_pair(p.as_ref(), p.as_ref(), &opts).unwrap();
    let want = std::f64::consts::TAU * 0.5 / 1002.0;
    assert!((a[0][0] - want).abs() < 1e-4 * want, "{} {want}", a[0][0]);
}

/// A diffuse lobe whose brightness follows the light's azimuth: (1 + ½ cos 2φ′)/π.
struct Azimuthal(Channels);

impl Brdf for Azimuthal {
    fn channels(&self) -> &Channels {
        &self.0
    }
    fn eval(&self, wi: glam::DVec3, wo: glam::DVec3, out: &mut [f32]) {
        let c2 = (wi.x * wi.x - wi.y * wi.y) / (wi.x * wi.x + wi.y * wi.y).max(1e-300);
        let f = if wi.z > 0.0 && wo.z > 0.0 {
            (1.0 + 0.5 * c2) / std::f64::consts::PI
        } else {
            0.0
        };
        out.iter_mut().for_each(|o| *o = f as f32);
    }
    fn flags(&self) -> crate::brdf::Flags {
        crate::brdf::Flags {
            isotropic: false,
            reciprocal: false,
            ..Lambert::new(Value::Rgb([0.5; 3]), &self.0).unwrap().flags()
        }
    }
    fn describe(&self) -> String {
        "azimuthal".into()
    }
}

#[test]
fn an_anisotropic_albedo_is_averaged_over_the_lights_azimuths() {
    // Its albedo is 1 + ½ cos 2φ′ at every θ′: 1.5 at φ′ = 0, and the mean over four or
    // more equally spaced azimuths is 1 (they sum cos 2φ′ to 0).
    let b = Azimuthal(Channels::Rgb);
    let l = Lambert::new(Value::Rgb([std::f64::consts::FRAC_1_PI; 3]), &Channels::Rgb).unwrap();
    for (n, want) in [(1, 1.5), (4, 1.0), (8, 1.0)] {
        let opts = FidelityOptions {
            albedo_thetas_deg: vec![10.0, 60.0, 89.0],
            albedo_azimuths: n,
            ..Default::default()
        };
        let curve = albedo_curve(&b, &opts).unwrap();
        let (a, _) = albedo_pair(&b, &l, &opts).unwrap();
        // The rule's own error on a cosine lobe (the Lambert test above): 1e-4.
        for (x, y) in curve.iter().zip(&a) {
            assert!((x[0] - want).abs() < 1e-4 * want, "{n}: {x:?}");
            assert_eq!(x, y);
        }
        // Against a Lambert lobe of albedo 1: the mean's error is the lobe's own.
        let e = albedo_error(&b, &l, &opts).unwrap();
        assert!((e.worst - (want - 1.0)).abs() < 2e-4, "{n}: {e:?}");
    }
    let none = FidelityOptions {
        albedo_azimuths: 0,
        ..Default::default()
    };
    assert!(albedo_curve(&b, &none).is_err());
}

#[test]
fn a_darker_table_shows_its_error_everywhere_and_dark_channels_are_floored() {
    let src = Lambert::new(Value::Rgb([0.5, 0.5, 0.005]), &Channels::Rgb).unwrap();
    let dim = Lambert::new(Value::Rgb([0.49, 0.5, 0.0025]), &Channels::Rgb).unwrap();
    // The default φ rule (128 nodes): it integrates Lambert within 1e-4 (above).
    let opts = FidelityOptions {
        pairs: 4096,
        ..Default::default()
    };
    let f = measure(&dim, &src, &opts).unwrap();
    // Red: 2 % low; blue: 0.0025π·… against the floor 0.02: |0.0025π − 0.005π| / 0.02.
    let blue = 0.0025 * std::f64::consts::PI / 0.02;
    // Both albedos within 1e-4 of their value (the rule's error, above).
    assert!((f.albedo.worst - blue).abs() < 2e-4 * blue, "{f:?}");
    assert_eq!(f.albedo.channel, 2);
    for e in [f.cap, f.whole, f.grazing] {
        // Relative RMSE of a per-channel scale error, weighted by the channels' energy.
        assert!(e > 0.01 && e < 0.02, "{f:?}");
    }
}
