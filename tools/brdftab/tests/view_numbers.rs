//! `brdftab view`'s numbers where they went wrong: measured data near the horizon, a table's
//! difference to its source, albedos with delta lobes, and which measured file is a table's
//! source.

mod common;

use brdftab::testkit::TempDir;
use common::brdftab;
use common::viewer::{enc, get, get_json, start};
use serde_json::Value;

/// The numbers of `v[key]`.
fn nums(v: &Value, key: &str) -> Vec<f64> {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("no {key} in {v}"))
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn max(x: &[f64]) -> f64 {
    x.iter().fold(0.0f64, |m, &v| m.max(v.abs()))
}

/// An RGL file of the shipped data copied to `d` under `name`.
fn rgl(d: &TempDir, file: &str, name: &str) -> String {
    let dir = brdftab::measured::data::rgl_dir().expect("data/rgl ships with brdftab");
    let to = d.file(name);
    std::fs::copy(dir.join(file), &to).unwrap();
    to
}

#[test]
fn a_measured_table_is_paired_with_its_file_beside_the_database() {
    let d = TempDir::new("view-measured");
    let bsdf = rgl(&d, "paper_white_rgb.bsdf", "paper_white_rgb.bsdf");
    let db = d.file("m.btdb");
    let r = brdftab(&[
        "db", "add", &db, &bsdf, "--name", "paper", "--preset", "small",
    ]);
    assert!(r.ok, "{}", r.stderr);
    {
        let v = start(&[&db, &bsdf]);
        let list = get_json(&v, "/api/materials");
        assert_eq!(
            (list[0]["kind"].as_str(), list[1]["kind"].as_str()),
            (Some("table"), Some("rgl"))
        );
        assert_eq!(list[0]["provenance"]["kind"], "measured");
        assert_eq!(list[0]["has_source"], true);
        let c = get_json(&v, "/api/compare?m=0");
        assert!(c["weight"].as_str().unwrap().contains("80°"), "{c}");
        assert!(c["rel_rmse"].as_f64().unwrap() < 0.2, "{c}");
        get_json(&v, "/api/polar?m=0&of=source&n=5");
    }
    // Another measurement under the same name is not the table's source: its hash differs from
    // the provenance's, and comparing would report the difference of two materials.
    std::fs::remove_file(&bsdf).unwrap();
    rgl(&d, "cg_sunflower_rgb.bsdf", "paper_white_rgb.bsdf");
    {
        let v = start(&[&db]);
        let m = &get_json(&v, "/api/materials")[0];
        assert_eq!(m["has_source"], false, "{m}");
        assert!(m["source_note"].as_str().unwrap().contains("sha256"), "{m}");
        assert_eq!(get(&v, "/api/compare?m=0").0, 404);
    }
    // Without the file beside it, the table is shown alone.
    std::fs::remove_file(&bsdf).unwrap();
    let v = start(&[&db]);
    assert_eq!(get_json(&v, "/api/materials")[0]["has_source"], false);
    assert_eq!(get(&v, "/api/compare?m=0").0, 404);
    assert_eq!(get(&v, "/api/polar?m=0&of=source").0, 404);
}

#[test]
fn measured_views_sample_no_direction_at_the_horizon() {
    // A measured file's f_r is its stored f_r cos θo over cos θo: 1e14 at the horizon, where
    // cos(π/2) is 6e-17. The views sample cell centres, as tables and `brdftab slice` do.
    let d = TempDir::new("view-horizon");
    let bsdf = rgl(&d, "paper_white_rgb.bsdf", "paper_white_rgb.bsdf");
    let v = start(&[&bsdf]);
    for n in [7, 180, 181] {
        let p = get_json(&v, &format!("/api/polar?m=0&theta_i=30&n={n}"));
        let t = nums(&p, "theta_o");
        assert!(t.iter().all(|t| t.abs() < 90.0), "{t:?}");
        let y = nums(&p, "y");
        assert!(max(&y) < 5.0, "n = {n}: max {}", max(&y));
    }
    // The lobe's top row no longer towers over the rest (it was 1.77 at 89.5°, the others
    // at most 0.31).
    let l = get_json(&v, "/api/lobe?m=0&theta_i=30&nt=19&np=36");
    let (rows, y) = (nums(&l, "theta_o"), nums(&l, "y"));
    assert_eq!(rows.len(), 19);
    assert!(rows.iter().all(|&t| t > 0.0 && t < 90.0), "{rows:?}");
    let inner = max(&y[..18 * 36]);
    assert!(max(&y) < 1.5 * inner, "{} vs {inner}", max(&y));
    // The slice's largest value was 5.9e15.
    let s = get_json(&v, "/api/slice?m=0&n=64");
    assert!(nums(&s, "theta").iter().all(|&t| t > 0.0 && t < 90.0));
    let y = nums(&s, "y");
    assert!(max(&y) < 1e3, "slice max {}", max(&y));
}

#[test]
fn a_tables_difference_slice_is_not_ruled_by_the_horizon() {
    // A GGX table against its spec: at the horizon the spec gave 2.6e14 and the relative
    // difference of 66 edge cells was > 0.5, pinning the map's 99th percentile at 1.
    let d = TempDir::new("view-diff");
    let t = d.file("g.btdb");
    let spec = r#"{"model":"ggx","alpha":0.2}"#;
    let r = brdftab(&["bake", spec, "-o", &t, "--preset", "small"]);
    assert!(r.ok, "{}", r.stderr);
    let v = start(&[&t]);
    let table = nums(&get_json(&v, "/api/slice?m=0&n=64"), "y");
    let source = nums(&get_json(&v, "/api/slice?m=0&of=source&n=64"), "y");
    assert!(max(&source) < 1e4, "source max {}", max(&source));
    // The page scales the map by the 99th percentile of the cells whose directions lie within
    // 80° of the normal (at φd = 90° both have cos θ = cos θh cos θd): a few percent there, not
    // the grazing row where the small grid's table is 75 % off.
    let theta = nums(&get_json(&v, "/api/slice?m=0&n=4"), "theta");
    assert_eq!(theta, [11.25, 33.75, 56.25, 78.75]);
    let cos = |k: usize| ((k as f64 + 0.5) * 90.0 / 64.0).to_radians().cos();
    let mut rel: Vec<f64> = (0..64 * 64)
        .filter(|k| cos(k % 64) * cos(k / 64) >= 80f64.to_radians().cos())
        .map(|k| ((table[k] - source[k]) / source[k].abs().max(1e-5)).abs())
        .collect();
    rel.sort_by(f64::total_cmp);
    let p99 = rel[(0.99 * (rel.len() - 1) as f64) as usize];
    assert!(p99 < 0.2, "99th percentile {p99}");
}

#[test]
fn albedos_count_delta_lobes_as_brdftab_albedo_does() {
    let v = start(&[r#"{"model":"lambert","kd":0.5}"#]);
    let mirror = r#"{"model":"mirror"}"#;
    let sum = r#"{"model":"sum","terms":[{"model":"lambert","kd":0.1},{"model":"mirror"}]}"#;
    for (spec, want) in [(mirror, 1.0), (sum, 1.0 + 0.1 * std::f64::consts::PI)] {
        let a = get_json(&v, &format!("/api/albedo?spec={}", enc(spec)));
        for y in nums(&a, "y") {
            assert!((y - want).abs() < 1e-3, "{spec}: {a}");
        }
        let p = get_json(&v, &format!("/api/plausibility?spec={}", enc(spec)));
        let top = p["max_albedo"].as_f64().unwrap();
        assert!((top - want).abs() < 1e-3, "{spec}: {p}");
        assert_eq!(p["energy_conserving"], want <= 1.0 + 1e-3, "{spec}: {p}");
    }
}

#[test]
fn a_spectral_table_is_compared_with_its_spec_at_its_own_wavelengths() {
    // A spec baked at 7 wavelengths: its source opened in RGB beside it made the error figures
    // "7 vs 3 channels" (the page showed "–") and the source's curves another colour's.
    let d = TempDir::new("view-spectral");
    let db = d.file("s.btdb");
    let gold = r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#;
    let r = brdftab(&[
        "db",
        "add",
        &db,
        gold,
        "--name",
        "gold",
        "--preset",
        "small",
        "--wavelengths",
        "400,450,500,550,600,650,700",
    ]);
    assert!(r.ok, "{}", r.stderr);
    let v = start(&[&db]);
    let c = get_json(&v, "/api/compare?m=0");
    assert!(c["error"].is_null(), "{c}");
    // The small preset's table of this model is within 2 % (`brdftab demo --preset small`).
    assert!(c["rel_rmse"].as_f64().unwrap() < 0.05, "{c}");
    let (table, source) = (
        get_json(&v, "/api/polar?m=0&n=8"),
        get_json(&v, "/api/polar?m=0&of=source&n=8"),
    );
    assert_eq!(source["f"].as_array().unwrap().len(), 7, "{source}");
    // The same luminance, up to the table's error near the peak.
    let (a, b) = (nums(&table, "y"), nums(&source, "y"));
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= 0.05 * max(&b), "{a:?} {b:?}");
    }
}

#[test]
fn a_view_shows_the_channel_asked_for() {
    // The views drew the luminance only: gold's red and blue Fresnel, a blue plastic's colour
    // could not be seen one by one. `ch=r|g|b` shows a linear sRGB component (an RGB
    // material's own channel), `ch=y` (the default) the luminance.
    let spec = r#"{"model": "lambert", "kd": [0.1, 0.2, 0.4]}"#;
    let v = start(&[spec]);
    let f = get_json(&v, "/api/polar?m=0&n=4");
    for (k, ch) in ["r", "g", "b"].iter().enumerate() {
        let one: Vec<f64> = f["f"][k]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        for view in [
            format!("/api/polar?m=0&n=4&ch={ch}"),
            format!("/api/lobe?m=0&nt=2&np=3&ch={ch}"),
            format!("/api/slice?m=0&n=2&ch={ch}"),
        ] {
            let y = nums(&get_json(&v, &view), "y");
            assert!(
                y.iter().all(|&x| (x - one[0]).abs() < 1e-7),
                "{view}: {y:?}"
            );
        }
        let a = get_json(&v, &format!("/api/albedo?m=0&ch={ch}"));
        let (y, kd) = (nums(&a, "y"), [0.1, 0.2, 0.4][k]);
        // The lecture's Lambert: f_r = kd, albedo π kd at every angle.
        assert!(
            y.iter()
                .all(|&x| (x - std::f64::consts::PI * kd).abs() < 1e-4),
            "{ch}: {y:?}"
        );
    }
    let y = nums(&get_json(&v, "/api/polar?m=0&n=4&ch=y"), "y");
    let lum = 0.2126 * 0.1 + 0.7152 * 0.2 + 0.0722 * 0.4;
    assert!(y.iter().all(|&x| (x - lum).abs() < 1e-7), "{y:?}");
    assert_eq!(nums(&get_json(&v, "/api/polar?m=0&n=4"), "y"), y);
    let (status, body) = common::viewer::get(&v, "/api/albedo?m=0&ch=x");
    assert!(status == 400 && body.contains("ch:"), "{status} {body}");
}
