//! The spectrum module's unit tests: values on channel sets, the colour-preserving mix, parsing
//! and the checks of wavelengths and magnitudes.

use super::*;

#[test]
fn rgb_value_on_rgb_channels_is_exact() {
    let v = Value::Rgb([0.1, 0.2, 0.3]);
    assert_eq!(v.resolve(&Channels::Rgb), vec![0.1, 0.2, 0.3]);
}

#[test]
fn grey_stays_grey_in_every_mode() {
    let v = Value::Grey(0.25);
    let ch = Channels::linspace(400.0, 700.0, 7).unwrap();
    assert!(v.resolve(&ch).iter().all(|&x| x == 0.25));
}

#[test]
fn spectral_interpolates_linearly_and_clamps() {
    let v = Value::Spectral {
        wavelengths: vec![400.0, 500.0],
        values: vec![1.0, 3.0],
    };
    assert_eq!(v.at(450.0), 2.0);
    assert_eq!(v.at(300.0), 1.0);
    assert_eq!(v.at(900.0), 3.0);
}

#[test]
fn an_rgb_value_as_a_spectrum_keeps_its_colour() {
    // What a spectral renderer shows of the parameter (its CIE projection) is the RGB given.
    let v = Value::Rgb([1.0, 2.0, 3.0]);
    let back = crate::colour::srgb_of(|nm| v.at(nm));
    for (i, c) in back.iter().enumerate() {
        assert!((c - (i as f64 + 1.0)).abs() < 1e-11, "{back:?}");
    }
    // On spectral channels it is that spectrum at each wavelength.
    let ch = Channels::linspace(400.0, 700.0, 4).unwrap();
    let r = v.resolve(&ch);
    for (i, x) in r.iter().enumerate() {
        assert_eq!(*x, v.at(ch.wavelength(i)));
    }
}

#[test]
fn wavelength_mixes_interpolate_between_neighbours() {
    let ch = Channels::wavelengths(vec![400.0, 500.0, 600.0]).unwrap();
    let m = ch.mix_at(450.0);
    assert_eq!(m.apply(|i| [1.0, 3.0, 100.0][i]), 2.0);
    assert_eq!(ch.mix_at(300.0).apply(|i| [1.0, 3.0, 5.0][i]), 1.0);
    assert_eq!(
        ch.mix_at(900.0).apply(|i| [1.0, 3.0, f64::INFINITY][i]),
        f64::INFINITY
    );
    assert_eq!(
        ch.mix_at(500.0).apply(|i| [f64::INFINITY, 3.0, 5.0][i]),
        3.0
    );
}

#[test]
fn a_non_wavelength_has_no_value() {
    // NaN, ±∞, 0 and negative nm are not wavelengths: NaN, never an end channel's value.
    let ch = Channels::wavelengths(vec![400.0, 500.0]).unwrap();
    let spectral = Value::Spectral {
        wavelengths: vec![400.0, 500.0],
        values: vec![1.0, 3.0],
    };
    for nm in [
        f64::NAN,
        0.0,
        -0.0,
        -450.0,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ] {
        assert!(ch.mix_at(nm).apply(|i| [1.0, 3.0][i]).is_nan(), "{nm}");
        assert!(
            Channels::Rgb.mix_at(nm).apply(|i| [0.2; 3][i]).is_nan(),
            "{nm}"
        );
        for v in [
            Value::Grey(0.5),
            Value::Rgb([0.1, 0.2, 0.3]),
            spectral.clone(),
        ] {
            assert!(v.at(nm).is_nan(), "{v:?} at {nm}");
        }
    }
    // The ends of real wavelengths are held, as before.
    assert_eq!(ch.mix_at(1e-300).apply(|i| [1.0, 3.0][i]), 1.0);
    assert_eq!(ch.mix_at(1e300).apply(|i| [1.0, 3.0][i]), 3.0);
    assert_eq!(Value::Grey(0.5).at(1e-300), 0.5);
}

#[test]
fn json_forms_parse_and_bad_forms_fail() {
    let a: Value = serde_json::from_str("0.5").unwrap();
    assert_eq!(a, Value::Grey(0.5));
    let b: Value = serde_json::from_str("[1,2,3]").unwrap();
    assert_eq!(b, Value::Rgb([1.0, 2.0, 3.0]));
    let c: Value = serde_json::from_str(r#"{"wavelengths":[400,500],"values":[1,2]}"#).unwrap();
    assert!(matches!(c, Value::Spectral { .. }));
    assert!(serde_json::from_str::<Value>("[1,2]").is_err());
    assert!(serde_json::from_str::<Value>("\"x\"").is_err());
    assert!(serde_json::from_str::<Value>(r#"{"wavelengths":[1],"values":[1],"z":1}"#).is_err());
}

#[test]
fn validation_names_the_field() {
    let e = Value::Grey(-1.0).validate("kd", 0.0).unwrap_err();
    assert!(e.to_string().contains("kd"), "{e}");
    assert!(Value::Grey(f64::NAN).validate("kd", 0.0).is_err());
    let bad = Value::Spectral {
        wavelengths: vec![500.0, 400.0],
        values: vec![1.0, 1.0],
    };
    assert!(bad.validate("k", 0.0).is_err());
}
