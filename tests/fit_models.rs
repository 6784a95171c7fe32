//! Fitting a model to itself recovers its parameters; fits through other kinds of sources.

use brdftab::fit::{self, ColorMode, FitOptions, ParamRequest};
use brdftab::spec::ModelSpec;
use brdftab::{Brdf, Channels};

fn build(json: &str) -> Box<dyn Brdf + Send + Sync> {
    ModelSpec::parse(json)
        .unwrap()
        .build(&Channels::Rgb)
        .unwrap()
}

fn grey(starts: usize) -> FitOptions {
    FitOptions {
        pairs: 1500,
        starts,
        color: ColorMode::Grey,
        ..Default::default()
    }
}

fn value(r: &fit::FitResult, path: &str) -> f64 {
    let p = r.params.iter().find(|p| p.path == path).unwrap();
    p.value.iter().sum::<f64>() / p.value.len() as f64
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

#[test]
fn reciprocal_phong_recovers_ks_and_n() {
    let src = build(r#"{"model": "reciprocal_phong", "ks": 2.0, "n": 40}"#);
    let r = fit::fit(
        src.as_ref(),
        &fit::preset("reciprocal_phong").unwrap(),
        &grey(4),
    )
    .unwrap();
    let (ks, n) = (value(&r, "ks"), value(&r, "n"));
    assert!(
        close(ks, 2.0, 0.02) && close(n, 40.0, 0.02),
        "ks {ks} n {n}"
    );
    assert!(r.rmse < 1e-3, "{}", r.rmse);
}

#[test]
fn cook_torrance_recovers_m_and_ks() {
    let src = build(r#"{"model": "cook_torrance", "m": 0.25, "ks": 0.8, "fresnel": "none"}"#);
    let r = fit::fit(
        src.as_ref(),
        &fit::preset("cook_torrance").unwrap(),
        &grey(4),
    )
    .unwrap();
    let (m, ks) = (value(&r, "m"), value(&r, "ks"));
    assert!(
        close(m, 0.25, 0.02) && close(ks, 0.8, 0.02),
        "m {m} ks {ks}"
    );
    // Also in log space.
    let opts = FitOptions {
        log: true,
        ..grey(4)
    };
    let r = fit::fit(src.as_ref(), &fit::preset("cook_torrance").unwrap(), &opts).unwrap();
    let (m, ks) = (value(&r, "m"), value(&r, "ks"));
    assert!(
        close(m, 0.25, 0.02) && close(ks, 0.8, 0.02),
        "log: m {m} ks {ks}"
    );
}

#[test]
fn diffuse_plus_specular_sum_recovers_both_terms() {
    let src = build(
        r#"{"model": "sum", "terms": [{"model": "lambert", "kd": [0.2, 0.1, 0.05]},
            {"model": "ggx", "alpha": 0.15, "ks": 0.6}]}"#,
    );
    let opts = FitOptions {
        pairs: 1500,
        starts: 4,
        ..Default::default()
    };
    let r = fit::fit(src.as_ref(), &fit::preset("lambert+ggx").unwrap(), &opts).unwrap();
    let kd = &r
        .params
        .iter()
        .find(|p| p.path == "terms[0].kd")
        .unwrap()
        .value;
    for (a, b) in kd.iter().zip([0.2, 0.1, 0.05]) {
        assert!(close(*a, b, 0.02), "kd {kd:?}");
    }
    assert!(
        close(value(&r, "terms[1].alpha"), 0.15, 0.02),
        "{:?}",
        r.params
    );
    assert!(close(value(&r, "terms[1].ks"), 0.6, 0.02), "{:?}", r.params);
    // The fitted spec round-trips through JSON and builds.
    ModelSpec::parse(&r.spec.to_json())
        .unwrap()
        .build(&Channels::Rgb)
        .unwrap();
}

#[test]
fn a_subset_of_parameters_keeps_the_others_fixed() {
    let src = build(r#"{"model": "cook_torrance", "m": 0.25, "ks": 0.8}"#);
    let init = ModelSpec::parse(r#"{"model": "cook_torrance", "m": 0.5, "ks": 0.8}"#).unwrap();
    let opts = FitOptions {
        params: vec!["m=0.1:0.2".parse::<ParamRequest>().unwrap()],
        ..grey(2)
    };
    let r = fit::fit(src.as_ref(), &init, &opts).unwrap();
    let ModelSpec::CookTorrance { m, ks, .. } = &r.spec else {
        panic!("{:?}", r.spec)
    };
    assert!(
        (0.1..=0.2).contains(m) && *m > 0.19,
        "m {m} stays inside its bounds"
    );
    assert_eq!(ks, &brdftab::Value::Grey(0.8));
}

#[test]
fn cook_torrance_recovered_through_a_baked_table() {
    use brdftab::table::{BakeOptions, Grid, Mapping, Param, Symmetry, TabulatedBrdf, bake};
    let src = build(r#"{"model": "cook_torrance", "m": 0.25, "ks": 0.8, "fresnel": "none"}"#);
    let grid = Grid::with_sizes(
        Param::HalfDiff,
        [64, 1, 32, 32],
        [Mapping::Sqrt, Mapping::Uniform],
        Channels::Rgb,
        Symmetry::ALL,
    )
    .unwrap();
    let (table, _) = bake(src.as_ref(), &grid, &BakeOptions::default()).unwrap();
    let tab = TabulatedBrdf::from_table(table);
    let r = fit::fit(&tab, &fit::preset("cook_torrance").unwrap(), &grey(3)).unwrap();
    let (m, ks) = (value(&r, "m"), value(&r, "ks"));
    assert!(
        close(m, 0.25, 0.02) && close(ks, 0.8, 0.02),
        "m {m} ks {ks}"
    );
    // The table itself is least accurate at grazing angles, which `rmse_uniform` includes.
    assert!(r.rmse < 0.02, "{}", r.rmse);
}

/// A source with a delta lobe cannot be fitted: eval is 0 for a mirror, and a sum's mirror term
/// is invisible to it, so a fit would silently match the other terms only.
#[test]
fn sources_with_a_delta_lobe_are_refused() {
    for src in [
        r#"{"model": "mirror"}"#,
        r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2}, {"model": "mirror"}]}"#,
    ] {
        let r = fit::fit(build(src).as_ref(), &fit::preset("ggx").unwrap(), &grey(1));
        assert!(
            matches!(r, Err(brdftab::Error::Unsupported(ref m)) if m.contains("delta")),
            "{src}: {r:?}"
        );
    }
}
