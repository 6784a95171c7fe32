//! The Fresnel formulas' unit tests: the scaled and lane forms against the scalar one, closed
//! forms, Brewster, total internal reflection, grazing and index-matched cases, the spec's JSON.

use super::*;

#[test]
fn scaled_conductor_matches_the_normalized_formula() {
    // Au-like and Cu-like indices, random cosines and normal lengths: the scaled formula is
    // the normalized one with every term multiplied by a power of gg, so they agree to
    // rounding (a few ulps, amplified by the conditioning of the differences t1 − t2).
    let n = [0.18, 0.42, 1.37, 0.27];
    let k = [3.4, 2.35, 1.77, 2.8];
    let mut rng = crate::rng::Pcg32::new(11);
    for _ in 0..20_000 {
        let cos = rng.next_f64().max(1e-6);
        let len = 0.01 + 10.0 * rng.next_f64();
        let (x, gg) = (cos * len, len * len);
        let f = conductor_lanes_scaled(x, gg, n, k);
        for i in 0..4 {
            let expect = conductor(cos, n[i], k[i]);
            assert!(
                (f[i] - expect).abs() <= 1e-12 * expect,
                "{cos} {len}: {} vs {expect}",
                f[i]
            );
        }
    }
    assert_eq!(conductor_lanes_scaled(0.0, 1.0, n, k), [1.0; 4]);
    assert_eq!(conductor_lanes_scaled(-0.5, 1.0, n, k), [1.0; 4]);
    assert_eq!(conductor_lanes_scaled(f64::NAN, 1.0, n, k), [1.0; 4]);
}

#[test]
fn lanes_are_bit_identical_to_the_scalar_formula() {
    let n = [0.2, 1.5, 0.05, 3.0];
    let k = [3.0, 0.0, 4.2, 0.1];
    for i in 0..=1000 {
        let c = i as f64 / 1000.0;
        let f = conductor_lanes(c, n, k);
        for l in 0..4 {
            assert_eq!(
                f[l].to_bits(),
                conductor(c, n[l], k[l]).to_bits(),
                "c={c} lane {l}"
            );
        }
    }
    assert_eq!(conductor_lanes(f64::NAN, n, k), [1.0; 4]);
    assert_eq!(conductor_lanes(-0.5, n, k), [1.0; 4]);
}

#[test]
fn normal_incidence_closed_form() {
    for &(n, k) in &[(1.5, 0.0), (0.2, 3.0), (0.15, 3.6), (1.1, 7.0), (2.5, 0.3)] {
        let expect = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
        let got = conductor(1.0, n, k);
        assert!(
            (got - expect).abs() < 1e-14,
            "n={n} k={k}: {got} vs {expect}"
        );
    }
    let expect = (0.5f64 / 2.5).powi(2);
    assert!((dielectric(1.0, 1.5) - expect).abs() < 1e-14);
}

#[test]
fn real_closed_form_equals_complex_form() {
    for &(n, k) in &[
        (1.5, 0.0),
        (0.2, 3.0),
        (0.14, 3.697),
        (1.1, 7.0),
        (2.5, 0.3),
        (0.65, 0.0),
    ] {
        for i in 1..=200 {
            let c = i as f64 / 200.0;
            let (a, b) = conductor_polarized(c, n, k);
            let complex = 0.5 * (a + b);
            let real = conductor(c, n, k);
            assert!(
                (real - complex).abs() < 1e-12,
                "n={n} k={k} cos={c}: {real} vs {complex}"
            );
        }
    }
}

#[test]
fn brewster_angle_zeroes_parallel() {
    for &eta in &[1.33, 1.5, 2.4] {
        let theta_b = f64::atan(eta);
        let (f_par, f_perp) = conductor_polarized(theta_b.cos(), eta, 0.0);
        assert!(f_par < 1e-15, "eta={eta}: F∥ = {f_par}");
        assert!(f_perp > 0.01);
    }
}

#[test]
fn dielectric_matches_conductor_with_k_zero() {
    for i in 0..=100 {
        let c = i as f64 / 100.0;
        assert!((dielectric(c, 1.5) - conductor(c, 1.5, 0.0)).abs() < 1e-12);
    }
}

#[test]
fn total_internal_reflection() {
    // From inside glass (cos_i < 0), beyond the critical angle asin(1/1.5) ≈ 41.8°.
    let theta = 50f64.to_radians();
    assert_eq!(dielectric(-theta.cos(), 1.5), 1.0);
    let theta = 30f64.to_radians();
    assert!(dielectric(-theta.cos(), 1.5) < 1.0);
}

#[test]
fn grazing_incidence_reflects_everything() {
    assert!((conductor(1e-9, 0.2, 3.0) - 1.0).abs() < 1e-6);
    assert!((dielectric(1e-9, 1.5) - 1.0).abs() < 1e-6);
}

#[test]
fn an_index_matched_interface_reflects_nothing_and_never_nan() {
    // n = 1 + 0j is no interface: F = 0 at every cosine whose fourth power is a normal
    // number (the closed form's t1 − t2 and the dielectric's cos θt cancelled to ±1e-17
    // there; below it (η² − sin²)² is subnormal and inexact), and a number in [0, 1] at any
    // cosine (where cos² underflowed it was 0/0 = NaN: a mirror's sample weight).
    let mut c = 1.0f64;
    while c > 1e-75 {
        assert_eq!(conductor(c, 1.0, 0.0), 0.0, "cos {c:e}");
        assert_eq!(
            conductor_lanes(c, [1.0; 4], [0.0; 4]),
            [0.0; 4],
            "cos {c:e}"
        );
        assert_eq!(conductor_lanes_scaled(c, 1.0, [1.0; 4], [0.0; 4]), [0.0; 4]);
        assert_eq!(dielectric(c, 1.0), 0.0, "cos {c:e}");
        c *= 0.37;
    }
    for c in [1e-80, 1e-160, 1e-170, 1e-300, f64::from_bits(1)] {
        for f in [conductor(c, 1.0, 0.0), dielectric(c, 1.0)]
            .into_iter()
            .chain(conductor_lanes(c, [1.0; 4], [0.0; 4]))
            .chain(conductor_lanes_scaled(c, 1.0, [1.0; 4], [0.0; 4]))
        {
            assert!((0.0..=1.0).contains(&f), "cos {c:e}: {f}");
        }
    }
    // Near 1 + 0j the closed form stays non-negative (it gave −1e-17 for n = 1 at some
    // cosines) and agrees with the complex form.
    let mut rng = crate::rng::Pcg32::new(11);
    for _ in 0..100_000 {
        let c = rng.next_f64();
        let n = 1.0 + (rng.next_f64() - 0.5) * 1e-6;
        let k = rng.next_f64() * 1e-6;
        let f = conductor(c, n, k);
        let (p, q) = conductor_polarized(c, n, k);
        // Both forms cancel near 1 + 0j (the complex one in 1 − sin²/η², to ~1e-9 of F).
        let want = 0.5 * (p + q);
        assert!(
            f >= 0.0 && (f - want).abs() <= 1e-6 * want + 1e-15,
            "{c} {n} {k}: {f}"
        );
    }
}

#[test]
fn spec_json_forms() {
    let a: FresnelSpec = serde_json::from_str("\"none\"").unwrap();
    assert_eq!(a, FresnelSpec::None);
    let b: FresnelSpec = serde_json::from_str(r#"{"n": 0.2, "k": 3}"#).unwrap();
    assert!(matches!(b, FresnelSpec::Complex { .. }));
    let c: FresnelSpec = serde_json::from_str(r#"{"eta": 1.5}"#).unwrap();
    assert!(matches!(c, FresnelSpec::Dielectric(_)));
    assert!(serde_json::from_str::<FresnelSpec>(r#"{"eta": 1.5, "n": 2}"#).is_err());
    assert!(serde_json::from_str::<FresnelSpec>(r#"{"bogus": 1}"#).is_err());
    assert!(serde_json::from_str::<FresnelSpec>("\"schlick\"").is_err());
    let back = serde_json::to_string(&b).unwrap();
    assert_eq!(serde_json::from_str::<FresnelSpec>(&back).unwrap(), b);
}
