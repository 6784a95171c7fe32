//! `brdftab view`'s incident azimuth φi (`phi_i=DEG`): the polar curve in the plane of
//! incidence at φi, the lobe and the albedo curve with the light at φi + 180°, asked over HTTP
//! and checked against the library's own numbers for the same directions.

mod common;

use std::f64::consts::PI;

use brdftab::Brdf;
use brdftab::analysis::albedo::albedo_curve_at;
use brdftab::geometry::spherical;
use brdftab::spec::ModelSpec;
use brdftab::spectrum::Channels;
use common::viewer::{Viewer, enc, get, get_json, start};
use serde_json::Value;

const WARD: &str = r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.4}"#;
const GGX: &str = r#"{"model": "ggx", "alpha": 0.2}"#;

fn build(spec: &str) -> Box<dyn Brdf + Send + Sync> {
    ModelSpec::parse(spec)
        .unwrap()
        .build(&Channels::Rgb)
        .unwrap()
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("not an array: {v}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// The f32 values of a JSON array of f32s (each prints as its shortest decimal, which reads
/// back to the same f32).
fn f32s(v: &Value) -> Vec<f32> {
    nums(v).into_iter().map(|x| x as f32).collect()
}

/// `/api/{view}` of inline spec `spec` with `params`.
fn ask(v: &Viewer, view: &str, spec: &str, params: &str) -> Value {
    get_json(v, &format!("/api/{view}?spec={}&{params}", enc(spec)))
}

/// f_r of `brdf`'s channel `c` at each pair, as the library evaluates it.
fn eval(brdf: &dyn Brdf, pairs: &[(glam::DVec3, glam::DVec3)], c: usize) -> Vec<f32> {
    let mut out = [0f32; 3];
    pairs
        .iter()
        .map(|&(wi, wo)| {
            brdf.eval(wi, wo, &mut out);
            out[c]
        })
        .collect()
}

/// The polar curve's pairs at (θi, φi), written out: light at φi + 180°, the viewer in the plane
/// through φi (θo < 0 on the light's side).
fn polar_pairs(theta_i: f64, phi_i: f64, theta_o: &[f64]) -> Vec<(glam::DVec3, glam::DVec3)> {
    let phi = phi_i.to_radians();
    let wi = spherical(theta_i.to_radians(), phi + PI);
    let side = |t: f64| if t < 0.0 { PI } else { 0.0 };
    theta_o
        .iter()
        .map(|&t| (wi, spherical(t.abs().to_radians(), phi + side(t))))
        .collect()
}

/// The lobe's pairs at (θi, φi): rows `theta_o`, `np` columns from azimuth φi.
fn lobe_pairs(
    theta_i: f64,
    phi_i: f64,
    theta_o: &[f64],
    np: usize,
) -> Vec<(glam::DVec3, glam::DVec3)> {
    let phi = phi_i.to_radians();
    let wi = spherical(theta_i.to_radians(), phi + PI);
    let mut out = Vec::new();
    for &t in theta_o {
        for j in 0..np {
            let p = phi + std::f64::consts::TAU * j as f64 / np as f64;
            out.push((wi, spherical(t.to_radians(), p)));
        }
    }
    out
}

/// Whether positive f32s `a` and `b` are at most one rounding step apart.
fn one_step(a: f32, b: f32) -> bool {
    a.to_bits().abs_diff(b.to_bits()) <= 1
}

/// The largest |a − b| over the largest |a|.
fn rel_change(a: &[f32], b: &[f32]) -> f64 {
    let top = a.iter().fold(0f64, |m, &x| m.max(x.abs() as f64));
    let d = a
        .iter()
        .zip(b)
        .fold(0f64, |m, (&x, &y)| m.max((x as f64 - y as f64).abs()));
    d / top
}

/// The polar curve at φi is the library's f_r at the pairs of the plane of incidence at φi: for
/// an anisotropic Ward exactly (the same pairs), and unlike φi = 0 (it showed φi = 0 whatever
/// was asked). An isotropic GGX's curve is the same at φi = 90° as at 0 up to the rotation's
/// rounding: the directions move by a few f64 ulps (~1e-16), f_r by far less than one f32 step
/// (GGX's f_r changes by ≪ 1e8 of itself per radian), so each value is at most one f32 rounding
/// step from the other.
#[test]
fn the_polar_curve_lies_in_the_plane_of_incidence_at_phi_i() {
    let v = start(&[WARD]);
    let ward = build(WARD);
    let (p0, p90) = (
        ask(&v, "polar", WARD, "theta_i=30&n=61&phi_i=0"),
        ask(&v, "polar", WARD, "theta_i=30&n=61&phi_i=90"),
    );
    let theta_o = nums(&p90["theta_o"]);
    for c in 0..3 {
        let want = eval(ward.as_ref(), &polar_pairs(30.0, 90.0, &theta_o), c);
        assert_eq!(f32s(&p90["f"][c]), want, "channel {c}");
        // φi = 0 is the x–z plane with the light on the −x side, as before.
        let want0 = eval(ward.as_ref(), &polar_pairs(30.0, 0.0, &theta_o), c);
        assert_eq!(f32s(&p0["f"][c]), want0, "channel {c}");
    }
    let (a, b) = (f32s(&p0["f"][0]), f32s(&p90["f"][0]));
    assert!(
        rel_change(&a, &b) > 0.1,
        "Ward 0.1 × 0.4 looks the same across both planes"
    );
    assert_eq!(
        (&p90["phi_i"], &p90["isotropic"]),
        (&90.0.into(), &false.into())
    );

    let (g0, g90) = (
        ask(&v, "polar", GGX, "theta_i=30&n=61&phi_i=0"),
        ask(&v, "polar", GGX, "theta_i=30&n=61&phi_i=90"),
    );
    assert_eq!(g90["isotropic"], true);
    for c in 0..3 {
        let (a, b) = (f32s(&g0["f"][c]), f32s(&g90["f"][c]));
        assert!(a.iter().all(|&x| x > 0.0));
        for (k, (x, y)) in a.iter().zip(&b).enumerate() {
            assert!(
                one_step(*x, *y),
                "channel {c}, θo {}: {x} vs {y}",
                theta_o[k]
            );
        }
    }
}

/// The lobe's columns start at azimuth φi with the light at φi + 180°: the library's f_r at
/// those pairs exactly (channel R is f_r's own value), unlike φi = 0 for Ward; for an
/// isotropic GGX the same columns as at φi = 0 up to one f32 step (as the polar curve).
#[test]
fn the_lobe_turns_with_phi_i() {
    let v = start(&[GGX]);
    let ward = build(WARD);
    let q = |phi: f64| format!("theta_i=40&nt=7&np=12&ch=r&phi_i={phi}");
    let (l0, l90) = (
        ask(&v, "lobe", WARD, &q(0.0)),
        ask(&v, "lobe", WARD, &q(90.0)),
    );
    let rows = nums(&l90["theta_o"]);
    let want = eval(ward.as_ref(), &lobe_pairs(40.0, 90.0, &rows, 12), 0);
    assert_eq!(f32s(&l90["y"]), want);
    let want0 = eval(ward.as_ref(), &lobe_pairs(40.0, 0.0, &rows, 12), 0);
    assert_eq!(f32s(&l0["y"]), want0);
    assert!(rel_change(&want0, &want) > 0.1);
    assert_eq!(l90["phi_i"], 90.0);

    let (g0, g90) = (
        ask(&v, "lobe", GGX, &q(0.0)),
        ask(&v, "lobe", GGX, &q(90.0)),
    );
    let (a, b) = (f32s(&g0["y"]), f32s(&g90["y"]));
    assert_eq!(a.len(), 7 * 12);
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        assert!(*x > 0.0 && one_step(*x, *y), "{k}: {x} vs {y}");
    }
}

/// The albedo curve has its light where the polar curve and the lobe have it, at φi + 180°
/// (`albedo_curve_at` takes the light's own azimuth): exactly the library's curve there, and
/// for Ward unlike φi = 0 (the curve was at azimuth 0 whatever φi). A registered material's
/// curves are cached per φi; an isotropic one's is the same at every φi.
#[test]
fn the_albedo_curve_has_its_light_at_phi_i_plus_180() {
    let v = start(&[WARD, GGX]);
    let ward = build(WARD);
    for target in ["spec=".to_owned() + &enc(WARD), "m=0".to_owned()] {
        let a90 = get_json(&v, &format!("/api/albedo?{target}&phi_i=90"));
        let a0 = get_json(&v, &format!("/api/albedo?{target}&phi_i=0"));
        let theta: Vec<f64> = nums(&a90["theta"]).iter().map(|d| d.to_radians()).collect();
        for (phi, got) in [(90f64, &a90), (0.0, &a0)] {
            let want = albedo_curve_at(ward.as_ref(), &theta, phi.to_radians() + PI).unwrap();
            let got: Vec<Vec<f64>> = got["a"].as_array().unwrap().iter().map(nums).collect();
            // The server prints each f64 in its shortest exact decimal; serde_json's default
            // reader (no `float_roundtrip`) may land one ulp off it.
            assert_eq!(got.concat().len(), want.concat().len());
            for (g, w) in got.iter().flatten().zip(want.iter().flatten()) {
                assert!(
                    g.to_bits().abs_diff(w.to_bits()) <= 1,
                    "{target} at φi = {phi}: {g} vs {w}"
                );
            }
        }
        // At φi = 90° the lobe's wide axis (α_y) lies in the plane of incidence, reaching
        // towards the horizon where Ward's f_r grows like 1/√cos θo (0.137 against 0.123 at
        // 60°): a difference far above the quadrature's 1e-6, so not its noise.
        let (y0, y90) = (nums(&a0["y"]), nums(&a90["y"]));
        assert!((y0[12] - y90[12]).abs() > 1e-3 * y0[12], "{y0:?} {y90:?}");
    }
    let g90 = get_json(&v, "/api/albedo?m=1&phi_i=90");
    let g0 = get_json(&v, "/api/albedo?m=1&phi_i=0");
    assert_eq!(g90["a"], g0["a"]);
    // Azimuths are taken to 0.1° (so a client cannot fill the cache with curves): 45.04° is
    // the curve at 45°, 45.06° the one at 45.1° (where Ward's albedo turns fastest with φ).
    let near = get_json(&v, "/api/albedo?m=0&phi_i=45.04");
    assert_eq!(near["a"], get_json(&v, "/api/albedo?m=0&phi_i=45")["a"]);
    let next = get_json(&v, "/api/albedo?m=0&phi_i=45.06");
    assert_eq!(next["a"], get_json(&v, "/api/albedo?m=0&phi_i=45.1")["a"]);
    assert_ne!(next["a"], near["a"]);
}

/// `phi_i` is checked as `theta_i` is: a number in [−180, 180], else a 400 that says so.
#[test]
fn phi_i_outside_its_range_is_refused() {
    let v = start(&[GGX]);
    for view in ["polar", "lobe", "albedo"] {
        for bad in ["abc", "400", "-180.5", "NaN", "inf", ""] {
            let (status, body) = get(&v, &format!("/api/{view}?m=0&phi_i={bad}"));
            assert!(
                status == 400 && body.contains("phi_i") && body.contains("[-180, 180]"),
                "{view} phi_i={bad}: {status} {body}"
            );
        }
        for ok in ["-180", "180", "12.5"] {
            assert_eq!(get(&v, &format!("/api/{view}?m=0&phi_i={ok}")).0, 200);
        }
    }
}
