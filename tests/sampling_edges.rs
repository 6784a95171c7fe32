//! Sampling densities at the domain's edges: a view a hair above the horizon, where the pdf of
//! a direction near the mirror direction hangs on wo·h, which is then ~1e-8 while the terms of
//! `wo.dot(h)` are ~0.1.

use brdftab::request::{self, BakeSettings, OpenSettings};
use brdftab::testkit::{Pcg32, TempDir};
use brdftab::{Brdf, geometry, progress::Silent};
use glam::DVec3;
use std::f64::consts::FRAC_PI_2;

fn open(source: &str) -> Box<dyn Brdf + Send + Sync> {
    let eager = OpenSettings {
        eager: Some(true),
        ..Default::default()
    };
    request::open(source, &eager).unwrap_or_else(|e| panic!("{source}: {e}"))
}

/// Models whose sampler reflects about a half vector (Ward, Blinn-Phong, Cook-Torrance's
/// visible normals, GGX), a sum, a table (halfdiff and inout grids: the table sampler) and a
/// shipped RGL file (the same sampler on the file's data).
fn sources(dir: &TempDir) -> Vec<(String, Box<dyn Brdf + Send + Sync>)> {
    let mut v: Vec<(String, Box<dyn Brdf + Send + Sync>)> = [
        r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
        r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.2, "alpha_y": 0.2}"#,
        r#"{"model": "blinn_phong", "ks": 0.5, "n": 100}"#,
        r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#,
        r#"{"model": "ggx", "alpha_x": 0.1, "alpha_y": 0.4}"#,
        r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2}, {"model": "cook_torrance", "m": 0.2}]}"#,
    ]
    .iter()
    .map(|s| (s.to_string(), open(s)))
    .collect();
    let phong = r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 50}"#;
    for (i, settings) in [
        r#"{"preset": "small"}"#,
        r#"{"preset": "small", "param": "inout"}"#,
    ]
    .iter()
    .enumerate()
    {
        let out = dir.file(&format!("t{i}.btdb"));
        let s: BakeSettings = request::from_json(settings).unwrap();
        request::bake(phong, &out, &s, &Silent).unwrap();
        v.push((format!("table {settings} of {phong}"), open(&out)));
    }
    let rgl = brdftab::measured::data::rgl_file("cc_ibiza_sunset_rgb.bsdf").unwrap();
    v.push(("RGL file".into(), open(rgl.to_str().unwrap())));
    v
}

/// `pdf(wi, wo)` at views within 1e-15 and 1e-9 rad of the horizon, for `wi` the reflection
/// of `wo` about half vectors h at 0.01–0.3 rad from the normal turned nearly 90° from wo's
/// azimuth (wo·h ~ 1e-8), against `pdf` at `wi` moved by rounding (≤ 2⁻⁵¹ per component).
/// The true density moves with h, which turns by at most |δwi| / |wi + wo| ≈ 3e-16 / 2e-8 =
/// 1.5e-8 rad; no source here has a density whose logarithm changes by more than 1e3 per
/// radian of h (the steepest: a table's bilinear density near the pole, where φh turns by
/// 1.5e-8 / θh), so 1e-4 bounds the change with room. `wo.dot(h)` gave ~1e-8 with an
/// absolute error ~1e-16 / 1e-8 · 0.1: every source here but GGX (whose density already read
/// |wi + wo| / 2) was off by 94–100 %, pdf 0 for the moved direction included; Cook-Torrance's
/// cavity partner ⟨V,H′⟩ alone, as a dot product, left 30 %.
#[test]
fn pdf_near_the_grazing_mirror_direction_is_well_conditioned() {
    let dir = TempDir::new("sampling-edges");
    let mut rng = Pcg32::new(5);
    let mut bad = Vec::new();
    for (name, b) in sources(&dir) {
        let mut worst = (0.0f64, String::new());
        let mut pairs = 0;
        for delta in [1e-15f64, 1e-9] {
            let wo = geometry::spherical(FRAC_PI_2 - delta, 0.3);
            for theta_h in [0.01f64, 0.06, 0.3] {
                for k in 1..=20 {
                    // wo·h = cos θh sin δ + sin θh cos δ cos Δφ ≈ k · 1e-8.
                    let dphi = FRAC_PI_2 - 1e-8 * k as f64 / theta_h.tan();
                    let h = geometry::spherical(theta_h, 0.3 + dphi);
                    let wi = 2.0 * wo.dot(h) * h - wo;
                    if wi.z <= 0.0 {
                        continue;
                    }
                    let p = b.pdf(wi, wo);
                    assert!(p > 0.0 && p.is_finite(), "{name}: pdf {p} at {wi}");
                    pairs += 1;
                    for _ in 0..4 {
                        let jitter = DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, 0.0);
                        let moved = (wi + jitter * 4e-16).normalize();
                        let q = b.pdf(moved, wo);
                        let rel = (q - p).abs() / p.max(q);
                        if rel.is_nan() || rel > worst.0 {
                            worst = (rel, format!("δ {delta}, θh {theta_h}: {p} vs {q}"));
                        }
                    }
                }
            }
        }
        assert!(pairs > 60, "{name}: only {pairs} pairs above the horizon");
        if worst.0.is_nan() || worst.0 > 1e-4 {
            bad.push(format!("{name}: {:.3e} ({})", worst.0, worst.1));
        }
    }
    assert!(
        bad.is_empty(),
        "ill-conditioned densities:\n{}",
        bad.join("\n")
    );
}
