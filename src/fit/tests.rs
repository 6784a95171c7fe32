//! Tests of the fit: known parameters recovered (per channel, grey, in log space), bounds
//! kept, and bad options and pair counts refused as errors.

use super::*;
use crate::spectrum::Channels;

fn build(json: &str) -> Box<dyn Brdf + Send + Sync> {
    ModelSpec::parse(json)
        .unwrap()
        .build(&Channels::Rgb)
        .unwrap()
}

fn quick() -> FitOptions {
    FitOptions {
        pairs: 400,
        starts: 3,
        ..Default::default()
    }
}

#[test]
fn a_pair_count_beyond_the_bound_is_an_argument_error_not_an_abort() {
    // 10^10 pairs allocated 240 GB (an abort); usize::MAX overflowed (a panic).
    let src = build(r#"{"model": "lambert", "kd": 0.5}"#);
    for pairs in [10_000_000_000, usize::MAX, MAX_RESIDUALS / 3 + 1] {
        let opts = FitOptions { pairs, ..quick() };
        let e = fit(src.as_ref(), &preset("lambert").unwrap(), &opts).unwrap_err();
        assert!(
            matches!(e, Error::InvalidArgument { ref name, .. } if name == "pairs"),
            "{pairs}: {e}"
        );
    }
}

#[test]
fn lambert_recovers_kd_per_channel() {
    let src = build(r#"{"model": "lambert", "kd": [0.1, 0.2, 0.05]}"#);
    let r = fit(src.as_ref(), &preset("lambert").unwrap(), &quick()).unwrap();
    let ModelSpec::Lambert { kd } = &r.spec else {
        panic!("{:?}", r.spec)
    };
    let v = kd.resolve(&Channels::Rgb);
    for (a, b) in v.iter().zip([0.1, 0.2, 0.05]) {
        assert!((a - b).abs() < 1e-4 * b, "{v:?}");
    }
    assert!(r.rmse < 1e-4, "{}", r.rmse);
    assert_eq!(r.starts.len(), 3);
    // The fitted spec is valid JSON that parses back and builds.
    let back = ModelSpec::parse(&r.spec.to_json()).unwrap();
    back.build(&Channels::Rgb).unwrap();
}

#[test]
fn grey_mode_fits_the_mean() {
    let src = build(r#"{"model": "lambert", "kd": [0.1, 0.2, 0.3]}"#);
    let opts = FitOptions {
        color: ColorMode::Grey,
        ..quick()
    };
    let r = fit(src.as_ref(), &preset("lambert").unwrap(), &opts).unwrap();
    assert!(
        matches!(r.spec, ModelSpec::Lambert { kd: crate::Value::Grey(k) } if (k - 0.2).abs() < 1e-4)
    );
}

/// A term the source does not have heads for its lower bound of 0; on the way its value
/// passed below 1e-12, which a spec refuses, and the start was dropped (every start of
/// Lambert fitted with lambert+ggx failed). Now such a value is 0 and every start ends.
#[test]
fn a_term_heading_for_zero_does_not_lose_its_start() {
    let src = build(r#"{"model": "lambert", "kd": 0.2}"#);
    let r = fit(src.as_ref(), &preset("lambert+ggx").unwrap(), &quick()).unwrap();
    for s in &r.starts {
        assert!(s.objective.is_finite(), "{s:?}");
    }
    assert!(r.rmse < 1e-3, "{}", r.rmse);
    let b = Bounds::linear(0.0, 1.0);
    assert_eq!(b.from_unit(1e-14), 0.0);
    assert_eq!(b.from_unit(1e-11), 1e-11);
    assert_eq!(Bounds::linear(-1.0, 1.0).from_unit(0.5 + 1e-14), 0.0);
}

#[test]
fn bounds_are_respected() {
    let src = build(r#"{"model": "lambert", "kd": 0.25}"#);
    let opts = FitOptions {
        params: vec!["kd=0.01:0.05".parse::<ParamRequest>().unwrap()],
        ..quick()
    };
    let r = fit(src.as_ref(), &preset("lambert").unwrap(), &opts).unwrap();
    let v = &r.params[0].value;
    assert!(v.iter().all(|&k| (0.01..=0.05).contains(&k)), "{v:?}");
    assert!(v.iter().all(|&k| k > 0.049), "{v:?}");
    assert!(r.params[0].at_bound);
    for s in &r.starts {
        assert!(s.fitted.iter().all(|&k| (0.01..=0.05).contains(&k)));
        assert!(s.initial.iter().all(|&k| (0.01..=0.05).contains(&k)));
    }
}

#[test]
fn log_space_fit_recovers_kd() {
    let src = build(r#"{"model": "lambert", "kd": 0.3}"#);
    let opts = FitOptions {
        log: true,
        ..quick()
    };
    let r = fit(src.as_ref(), &preset("lambert").unwrap(), &opts).unwrap();
    assert!(r.log);
    assert!(
        r.params[0].value.iter().all(|k| (k - 0.3).abs() < 1e-4),
        "{:?}",
        r.params
    );
}

#[test]
fn presets_parse_and_unknown_names_fail() {
    for name in [
        "lambert+cook_torrance",
        "lambert+ggx",
        "lambert+blinn_phong",
        "lambert+ward",
        "ggx",
        "reciprocal_phong",
    ] {
        let s = preset(name).unwrap();
        assert_eq!(s.name(), if name.contains('+') { "sum" } else { name });
    }
    assert!(preset("mirror").is_err());
    assert!(preset("lambert+bogus").is_err());
    assert_eq!(
        preset(r#"{"model": "lambert", "kd": 0.2}"#).unwrap().name(),
        "lambert"
    );
}

#[test]
fn bad_options_are_errors() {
    let src = build(r#"{"model": "lambert", "kd": 0.25}"#);
    let l = preset("lambert").unwrap();
    assert!(
        fit(
            src.as_ref(),
            &l,
            &FitOptions {
                pairs: 0,
                ..quick()
            }
        )
        .is_err()
    );
    assert!(
        fit(
            src.as_ref(),
            &l,
            &FitOptions {
                starts: 0,
                ..quick()
            }
        )
        .is_err()
    );
    let o = FitOptions {
        params: vec![ParamRequest::new("terms[1].m")],
        ..quick()
    };
    assert!(fit(src.as_ref(), &l, &o).is_err());
}
