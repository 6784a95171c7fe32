//! Tests of the spec schema: every listed example round-trips, the declaration and the enum
//! agree, and a bad spec's error names its field and path.

use super::json::SERIALIZED;
use super::*;

#[test]
fn every_listed_example_parses_and_round_trips() {
    for m in MODELS {
        let s = ModelSpec::parse(m.example).unwrap_or_else(|e| panic!("{}: {e}", m.name));
        assert_eq!(s.name(), m.name);
        assert_eq!(
            s.tagged().0.as_deref(),
            Some(m.name),
            "name() and serde disagree"
        );
        let back = ModelSpec::parse(&s.to_json()).unwrap();
        assert_eq!(back, s);
    }
}

#[test]
fn nested_sums_parse_in_polynomial_work() {
    // Issue #23: `name()` serialized the whole spec and the serializer asks every nested
    // spec its name, so each level of nested sums doubled the work (a 1 KB spec nesting 20
    // sums took 29 s to parse). Now parsing and validating a chain of depth d serializes
    // each spec once per validation of each enclosing level: about d² in all (depth 12:
    // 312, before 73,614).
    let leaf = r#"{"model": "ggx", "alpha": 0.2}"#;
    let mut chain = leaf.to_string();
    let depth = 12;
    for _ in 0..depth {
        chain = format!(r#"{{"model": "sum", "terms": [{leaf}, {chain}]}}"#);
    }
    SERIALIZED.with(|n| n.set(0));
    let spec = ModelSpec::parse(&chain).unwrap();
    assert_eq!(spec.name(), "sum");
    spec.validate().unwrap();
    let n = SERIALIZED.with(|n| n.get());
    let bound = 2 * (2 * depth + 1) * (2 * depth + 1);
    assert!(
        n <= bound,
        "{n} serializations for depth {depth} (bound {bound})"
    );
}

#[test]
fn the_declaration_and_the_enum_agree() {
    for m in MODELS {
        let s = ModelSpec::parse(m.example).unwrap();
        // Every field the enum writes is declared ...
        for (k, _) in s.tagged().1 {
            assert!(m.params.iter().any(|p| p.name == k), "{}.{k}", m.name);
        }
        // ... and a declared parameter that is not in the enum is rejected by serde.
        for p in m.params {
            let mut j: serde_json::Value = serde_json::from_str(m.example).unwrap();
            if j.get(p.name).is_none() {
                continue;
            }
            j[p.name] = serde_json::json!(-1);
            let e = ModelSpec::parse(&j.to_string());
            if p.bound != Bound::None {
                let e = e.unwrap_err().to_string();
                assert!(e.contains(p.name), "{}.{}: {e}", m.name, p.name);
            }
        }
    }
    assert_eq!(MODELS.len(), 13, "one entry per ModelSpec variant");
}

#[test]
fn bounds_come_from_the_declaration() {
    let e = ModelSpec::parse(r#"{"model": "cook_torrance", "m": 0}"#).unwrap_err();
    assert!(e.to_string().contains("> 0"), "{e}");
    let e = ModelSpec::parse(r#"{"model": "refractor", "eta": 0}"#).unwrap_err();
    assert!(e.to_string().contains("eta"), "{e}");
    let e = ModelSpec::parse(
        r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.1}], "weights": [-1]}"#,
    )
    .unwrap_err();
    assert!(e.to_string().contains("weights[0]"), "{e}");
    let e = ModelSpec::parse(r#"{"model": "ggx", "alpha": 0.1, "alpha_x": 0.2}"#).unwrap_err();
    assert!(e.to_string().contains("alpha"), "{e}");
    assert!(MODELS[9].params_line().contains("alpha_x: number > 0"));
    // The rule follows the parameters after a semicolon (it was ", (rule)").
    let sum = MODELS
        .iter()
        .find(|m| m.name == "sum")
        .unwrap()
        .params_line();
    assert!(
        sum.ends_with("= all 1; at least one term; one weight per term"),
        "{sum}"
    );
}

/// Every number at either end of [`crate::spectrum::NUMBER_RANGE`] evaluates to finite
/// values (the range is safe), and just beyond it is an error naming the field.
#[test]
fn numbers_at_the_range_ends_evaluate_finite_and_beyond_are_errors() {
    use crate::geometry::spherical;
    use std::f64::consts::{FRAC_PI_2, PI};
    let (lo, hi) = (
        *crate::spectrum::NUMBER_RANGE.start(),
        *crate::spectrum::NUMBER_RANGE.end(),
    );
    // Normal, oblique, mirror, retro and grazing pairs.
    let pairs = [
        (glam::DVec3::Z, glam::DVec3::Z),
        (spherical(0.4, 0.0), spherical(0.4, PI)),
        (spherical(0.7, 1.0), spherical(0.2, 2.0)),
        (spherical(1.2, 0.3), spherical(1.2, 0.3)),
        (
            spherical(FRAC_PI_2 - 1e-4, 0.0),
            spherical(FRAC_PI_2 - 1e-4, PI),
        ),
        (spherical(FRAC_PI_2 - 1e-4, 0.0), spherical(0.01, 1.0)),
    ];
    let mut checked = 0;
    for m in MODELS {
        for p in m.params {
            let numeric = matches!(p.kind, Kind::Number | Kind::Radians | Kind::Value);
            if !numeric {
                continue;
            }
            for (x, ok) in [
                (lo, true),
                (hi, true),
                (lo / 10.0, false),
                (hi * 10.0, false),
            ] {
                let mut j: serde_json::Value = serde_json::from_str(m.example).unwrap();
                if p.name == "alpha" || p.name == "alpha_x" || p.name == "alpha_y" {
                    // Keep the example's own choice of isotropic or anisotropic α.
                    if j.get(p.name).is_none() {
                        continue;
                    }
                }
                j[p.name] = serde_json::json!(x);
                let parsed = ModelSpec::parse(&j.to_string());
                if !ok {
                    let e = parsed.expect_err(&j.to_string()).to_string();
                    assert!(e.contains(p.name) && e.contains("out of range"), "{e}");
                    continue;
                }
                // Rules between parameters (Schlick F0 ≤ 1, ...) may refuse an end.
                let Ok(spec) = parsed else { continue };
                let b = build(&spec, &Channels::Rgb).unwrap();
                let mut f = [0.0f32; 3];
                for (wi, wo) in pairs {
                    b.eval(wi, wo, &mut f);
                    assert!(f.iter().all(|v| v.is_finite()), "{j}: {f:?} at {wi} {wo}");
                }
                checked += 1;
            }
        }
    }
    assert!(checked >= 20, "{checked} specs evaluated");
}

#[test]
fn unknown_field_is_named() {
    let e = ModelSpec::parse(r#"{"model": "lambert", "kd": 0.3, "kx": 1}"#).unwrap_err();
    assert!(e.to_string().contains("kx"), "{e}");
}

#[test]
fn unknown_model_is_an_error() {
    let e = ModelSpec::parse(r#"{"model": "bogus"}"#).unwrap_err();
    assert!(e.to_string().contains("bogus"), "{e}");
}

#[test]
fn negative_parameter_is_named_with_path() {
    let e = ModelSpec::parse(
        r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.1}, {"model": "reciprocal_phong", "ks": -1, "n": 3}]}"#,
    )
    .unwrap_err();
    assert!(e.to_string().contains("terms[1].ks"), "{e}");
    let e = ModelSpec::parse(r#"{"model": "phong", "ks": 1, "n": -3}"#).unwrap_err();
    assert!(e.to_string().contains("`n`"), "{e}");
}

#[test]
fn wrong_type_names_the_field() {
    let e = ModelSpec::parse(r#"{"model": "lambert", "kd": "red"}"#).unwrap_err();
    assert!(e.to_string().contains("kd"), "{e}");
    let e = ModelSpec::parse(r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"eta": [1, 2]}}"#)
        .unwrap_err();
    assert!(e.to_string().contains("fresnel"), "{e}");
}

#[test]
fn missing_field_and_bad_json() {
    assert!(ModelSpec::parse(r#"{"model": "lambert"}"#).is_err());
    assert!(matches!(ModelSpec::parse("{"), Err(Error::Json { .. })));
}
