//! The fit parameters' unit tests: paths, default bounds, the reparameterization and the colour
//! modes.

use super::*;

#[test]
fn reparameterization_stays_in_bounds_and_round_trips() {
    for b in [Bounds::linear(0.0, 0.4), Bounds::log(1.0, 1e4)] {
        for t in [-1e3, -30.0, -1.0, 0.0, 2.0, 40.0, 1e3] {
            let x = b.from_free(t);
            assert!(x >= b.lo && x <= b.hi, "{x}");
        }
        let x = b.from_unit(0.3);
        assert!((b.from_free(b.to_free(x)) - x).abs() < 1e-9 * x.max(1.0));
    }
}

#[test]
fn default_paths_walk_sums_and_skip_fresnel() {
    let j = serde_json::json!({"model": "sum", "terms": [
        {"model": "lambert", "kd": 0.1},
        {"model": "cook_torrance", "m": 0.3, "ks": 1.0, "fresnel": {"conductor": "Au"}}
    ]});
    assert_eq!(
        default_paths(&j),
        ["terms[0].kd", "terms[1].ks", "terms[1].m"]
    );
}

#[test]
fn fresnel_f0_and_eta_are_found() {
    let j = serde_json::json!({"model": "sum", "terms": [
        {"model": "ggx", "alpha": 0.3, "ks": 1.0, "fresnel": {"schlick": 0.04}},
        {"model": "cook_torrance", "m": 0.3, "ks": 1.0, "fresnel": {"eta": 1.5}}
    ]});
    assert_eq!(
        default_paths(&j),
        [
            "terms[0].alpha",
            "terms[0].fresnel.schlick",
            "terms[0].ks",
            "terms[1].fresnel.eta",
            "terms[1].ks",
            "terms[1].m"
        ]
    );
}

#[test]
fn paths_and_bounds_parse() {
    let r = "terms[1].m=0.05:0.5".parse::<ParamRequest>().unwrap();
    assert_eq!(r.path, "terms[1].m");
    assert_eq!(r.bounds, Some(Bounds::linear(0.05, 0.5)));
    let r = "n=2:100:log".parse::<ParamRequest>().unwrap();
    assert_eq!(r.bounds.unwrap().scale, Scale::Log);
    assert!("n=100:2".parse::<ParamRequest>().is_err());
    assert!("n=0:2:log".parse::<ParamRequest>().is_err());
    assert!("terms[x].m".parse::<ParamRequest>().is_err());
    assert!("".parse::<ParamRequest>().is_err());
}

#[test]
fn unknown_path_is_an_error_naming_it() {
    let mut j = serde_json::json!({"model": "lambert", "kd": 0.1});
    let e = resolve(
        &mut j,
        &[ParamRequest::new("ks")],
        &Channels::Rgb,
        ColorMode::Grey,
    )
    .unwrap_err();
    assert!(e.to_string().contains("ks"), "{e}");
    let e = resolve(
        &mut j,
        &[ParamRequest::new("terms[0].kd")],
        &Channels::Rgb,
        ColorMode::Grey,
    )
    .unwrap_err();
    assert!(e.to_string().contains("terms"), "{e}");
}

#[test]
fn per_channel_values_write_rgb_and_spectra() {
    let mut j = serde_json::json!({"model": "lambert", "kd": 0.1});
    let p = resolve(&mut j, &[], &Channels::Rgb, ColorMode::PerChannel).unwrap();
    assert_eq!(p[0].width, 3);
    write(&mut j, &p[0], &[0.1, 0.2, 0.3], &Channels::Rgb).unwrap();
    assert_eq!(j["kd"], serde_json::json!([0.1, 0.2, 0.3]));
    let ch = Channels::wavelengths(vec![450.0, 550.0]).unwrap();
    let p = resolve(&mut j, &[], &ch, ColorMode::PerChannel).unwrap();
    write(&mut j, &p[0], &[0.1, 0.2], &ch).unwrap();
    assert_eq!(read(&mut j, &p[0], &ch).unwrap(), vec![0.1, 0.2]);
}
