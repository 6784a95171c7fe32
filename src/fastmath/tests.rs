//! The fast functions' unit tests: the documented examples, and floor, ln, sin_cos and atan2
//! against libm within their stated error bounds.

#[test]
fn the_documented_examples_hold() {
    assert_eq!((floor(2.7), floor(-2.5), floor(-3.0)), (2.0, -3.0, -3.0));
    let (sn, cs) = sin_cos_2pi(0.125);
    assert!((sn - 0.5f64.sqrt()).abs() < 1e-15 && (cs - 0.5f64.sqrt()).abs() < 1e-15);
    assert!((ln(0.3) - 0.3f64.ln()).abs() < 1e-15);
    assert!((atan2(1.0, -1.0) - 0.75 * std::f64::consts::PI).abs() < 1e-15);
}

#[test]
fn atan2_matches_libm_within_its_error_bound() {
    // The documented bound, plus libm's own half ulp.
    let bound = |a: f64| 1e-15 + 5e-16 * a.abs();
    let mut rng = crate::rng::Pcg32::new(12);
    let check = |y: f64, x: f64| {
        let (a, b) = (atan2(y, x), y.atan2(x));
        assert!(
            (a - b).abs() <= bound(b),
            "atan2({y:e}, {x:e}) = {a:e}, libm {b:e}"
        );
    };
    for _ in 0..400_000 {
        let (s, c) = sin_cos_2pi(rng.next_f64());
        let r = (40.0 * rng.next_f64() - 20.0).exp();
        check(r * s, r * c);
        // Near the axes and the diagonals (the reduction's seams).
        let e = 1e-9 * (rng.next_f64() - 0.5);
        check(1.0 + e, 1.0);
        check(TAN_SEAM + e, 1.0);
        check(e, -1.0);
        check(-1.0, e);
    }
    for (y, x) in [
        (0.0, 1.0),
        (0.0, -1.0),
        (1.0, 0.0),
        (-1.0, 0.0),
        (1e-300, 1.0),
        (1.0, 1e-300),
    ] {
        check(y, x);
    }
    assert_eq!(atan2(0.0, 0.0), 0.0);
    assert!(atan2(f64::NAN, 1.0).is_nan() && atan2(1.0, f64::NAN).is_nan());
}

const TAN_SEAM: f64 = 0.414_213_562_373_095_03;

use super::*;
use std::f64::consts::{FRAC_PI_4, PI};

#[test]
fn floor_matches_libm_on_finite_input() {
    let mut x = -1000.0f64;
    while x < 1000.0 {
        assert_eq!(floor(x), x.floor(), "{x}");
        x += 0.173;
    }
    for x in [
        0.0,
        -0.0,
        0.5,
        -0.5,
        1.0 - 1e-16,
        -1e-300,
        4503599627370497.0,
    ] {
        assert_eq!(floor(x), x.floor(), "{x}");
    }
    assert_eq!(floor(f64::NAN), 0.0);
}

#[test]
fn ln_matches_libm_within_its_error_bound() {
    // The bound of `ln`: one rounding in r (≤ 1.1e-16 absolute), in ln c (≤ 2.8e-17), in the
    // polynomial (≤ 1e-18 for |r| ≤ 0.0078) and in the two final sums (≤ 1.1e-16 |ln x|
    // each), plus libm's own half ulp (1.1e-16 |ln x|): 2e-16 + 3.4e-16 |ln x|.
    let bound = |y: f64| 2e-16 + 3.4e-16 * y.abs();
    let mut rng = crate::rng::Pcg32::new(3);
    let check = |x: f64| {
        let (a, b) = (ln(x), x.ln());
        assert!((a - b).abs() <= bound(b), "ln({x:e}) = {a:e}, libm {b:e}");
    };
    for _ in 0..200_000 {
        let u = rng.next_f64();
        check(u.max(f64::MIN_POSITIVE));
        check(1.0 - u);
        check(0.5 + u);
        // Any positive finite double (sign bit cleared; NaN and infinity skipped).
        let bits = ((rng.next_u32() as u64) << 32 | rng.next_u32() as u64) >> 1;
        let x = f64::from_bits(bits);
        if x.is_finite() {
            check(x);
        }
    }
    for x in [
        f64::MIN_POSITIVE,
        f64::EPSILON,
        0.6875,
        1.0,
        1.375,
        2.0,
        f64::MAX,
    ] {
        check(x);
    }
    // Edges go to libm.
    assert_eq!(ln(0.0), f64::NEG_INFINITY);
    assert!(ln(-1.0).is_nan() && ln(f64::NAN).is_nan());
    assert_eq!(ln(f64::INFINITY), f64::INFINITY);
    assert_eq!(ln(5e-324), (5e-324f64).ln());
    assert_eq!(ln(1.0), 0.0);
}

#[test]
fn quarter_range_matches_libm_to_two_ulps_of_one() {
    let n = 200_001;
    let mut worst = 0.0f64;
    for i in 0..n {
        let x = -FRAC_PI_4 + 2.0 * FRAC_PI_4 * i as f64 / (n - 1) as f64;
        let (s, c) = sin_cos_quarter(x);
        let (s0, c0) = x.sin_cos();
        worst = worst.max((s - s0).abs()).max((c - c0).abs());
    }
    assert!(worst <= 2.5e-16, "worst abs error {worst:e}");
}

#[test]
fn full_turn_matches_libm_and_is_periodic() {
    let n = 400_000;
    let mut worst = 0.0f64;
    for i in 0..=n {
        let u = i as f64 / n as f64;
        let (s, c) = sin_cos_2pi(u);
        let (s0, c0) = (2.0 * PI * u).sin_cos();
        // libm's own argument 2πu carries a rounding error of up to ~4.4e-16 · 2π.
        worst = worst.max((s - s0).abs()).max((c - c0).abs());
        assert!((s * s + c * c - 1.0).abs() < 1e-15);
    }
    assert!(worst <= 2e-15, "worst abs error {worst:e}");
    // Exact quadrant points, negative and large arguments.
    assert_eq!(sin_cos_2pi(0.0), (0.0, 1.0));
    assert_eq!(sin_cos_2pi(0.25), (1.0, 0.0));
    assert_eq!(sin_cos_2pi(0.5), (-0.0, -1.0));
    assert_eq!(sin_cos_2pi(-0.25), (-1.0, 0.0));
    let (s, c) = sin_cos_2pi(1e6 + 0.1);
    let (s0, c0) = (2.0 * PI * 0.1).sin_cos();
    assert!((s - s0).abs() < 1e-9 && (c - c0).abs() < 1e-9);
    assert!(sin_cos_2pi(f64::NAN).0.is_nan());
}
