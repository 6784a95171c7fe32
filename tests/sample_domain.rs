//! `Brdf::sample` on any `u`: a `u` outside [0, 1)² — beyond the edges, infinite or NaN — has
//! no sample (as in `sample_batch`), and a `u` inside it, edges included, gives either no sample
//! or a unit direction above the horizon whose density `pdf` reproduces, with finite positive
//! weights. Over every model of the catalogue, anisotropic and summed lobes, a table and a
//! measured file.

use std::sync::OnceLock;

use brdftab::request::{self, BakeSettings};
use brdftab::spec::MODELS;
use brdftab::testkit::TempDir;
use brdftab::{Brdf, geometry, progress::Silent};
use glam::{DVec2, DVec3};
use proptest::prelude::*;

/// A source, the relative tolerance between a sample's pdf and `pdf(wi, wo)` — 1e-7 where both
/// are f64 arithmetic, 1e-6 for an RGL file's sampler, whose warps are the file's f32 data (the
/// contract's `pdf_tolerance` and its reasons) — and whether it is data. A model with positive
/// parameters is positive wherever its sampler draws; data may hold 0 (a channel a measurement
/// did not see, a table's nodes beyond a lobe), so its weights need only be ≥ 0.
struct Source {
    name: String,
    brdf: Box<dyn Brdf + Send + Sync>,
    pdf_tolerance: f64,
    data: bool,
}

impl Source {
    fn new(name: &str, brdf: Box<dyn Brdf + Send + Sync>, pdf_tolerance: f64, data: bool) -> Self {
        let name = name.to_owned();
        Source {
            name,
            brdf,
            pdf_tolerance,
            data,
        }
    }
}

fn sources() -> &'static [Source] {
    static SOURCES: OnceLock<Vec<Source>> = OnceLock::new();
    SOURCES.get_or_init(|| {
        let open = |s: &str| brdftab::open(s).unwrap_or_else(|e| panic!("{s}: {e}"));
        let mut v: Vec<Source> = MODELS
            .iter()
            .map(|m| Source::new(m.example, open(m.example), 1e-7, false))
            .collect();
        for spec in [
            r#"{"model": "phong", "ks": 0.5, "n": 1000}"#,
            r#"{"model": "ggx", "alpha_x": 0.1, "alpha_y": 0.4, "fresnel": {"conductor": "Cu"}}"#,
            r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2}, {"model": "phong", "ks": 0.4, "n": 30}, {"model": "ward", "ks": 0.2, "alpha_x": 0.1, "alpha_y": 0.3}]}"#,
        ] {
            v.push(Source::new(spec, open(spec), 1e-7, false));
        }
        let dir = TempDir::new("sample-domain");
        let table = dir.file("phong.btdb");
        let settings: BakeSettings = request::from_json(r#"{"preset": "small"}"#).unwrap();
        let phong = r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 50}"#;
        request::bake(phong, &table, &settings, &Silent).unwrap();
        // Read whole now: the temporary directory goes when this function returns.
        let eager = request::OpenSettings {
            eager: Some(true),
            ..Default::default()
        };
        let table = request::open(&table, &eager).unwrap();
        v.push(Source::new(&format!("table of {phong}"), table, 1e-7, true));
        let rgl = brdftab::measured::data::rgl_dir().expect("the RGL files ship in data/rgl");
        let rgl = rgl.join("cc_ibiza_sunset_rgb.bsdf");
        v.push(Source::new("RGL file", open(rgl.to_str().unwrap()), 1e-6, true));
        v
    })
}

/// One coordinate of `u`: on and beyond the unit interval's edges, far outside it, not finite,
/// anywhere in [−2, 0) or [1, 3), or inside from 1e-4 on. (Nearer u.x = 0 the folded samplers
/// — tables, measured files, Cook-Torrance — draw next to the mirror direction, where the
/// fold's density depends on the direction of approach, so a rounded direction's `pdf` parts
/// from the draw's: 2e-7 at u.x = 1e-6 for a table, all of it at 1e-12. That is the samplers'
/// conditioning, not the edge of the square this test is about; u.x = 0 itself is tested.)
fn coordinate() -> impl Strategy<Value = f64> {
    let below_one = 1.0 - f64::EPSILON / 2.0;
    prop_oneof![
        prop::sample::select(vec![
            0.0,
            -0.0,
            below_one,
            1.0,
            1.0 + f64::EPSILON,
            -f64::MIN_POSITIVE,
            -1e-300,
            1.5,
            -0.2,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ]),
        -2.0..0.0f64,
        1.0..3.0f64,
        1e-4..1.0f64,
    ]
}

/// A view above the horizon, from the normal to a hair above the horizon, not normalized.
fn view() -> impl Strategy<Value = DVec3> {
    (0.0..1.0f64, 0.0..std::f64::consts::TAU, 0.1..10.0f64).prop_map(|(t, phi, r)| {
        let theta = t * 89.9f64.to_radians();
        r * geometry::spherical(theta, phi)
    })
}

fn in_square(u: DVec2) -> bool {
    (0.0..1.0).contains(&u.x) && (0.0..1.0).contains(&u.y)
}

/// What is wrong with `sample(wo, u)` of `src`, if anything.
fn violation(src: &Source, wo: DVec3, u: DVec2) -> Option<String> {
    let b = src.brdf.as_ref();
    let c = b.channels().len();
    let mut w = vec![f32::NAN; c];
    let s = b.sample(wo, u, &mut w)?;
    if !in_square(u) {
        return Some(format!("u outside [0, 1)² gave {s:?}, weights {w:?}"));
    }
    let unit = s.wi.is_finite() && (s.wi.length() - 1.0).abs() <= 1e-9;
    let side_ok = if b.flags().transmission {
        s.wi.z != 0.0
    } else {
        s.wi.z > 0.0
    };
    if !(unit && side_ok) {
        return Some(format!("wi {} (length {})", s.wi, s.wi.length()));
    }
    let allowed = |x: f32| x.is_finite() && (x > 0.0 || src.data && x == 0.0);
    if !w.iter().all(|&x| allowed(x)) {
        return Some(format!("weights {w:?} for wi {}", s.wi));
    }
    if s.delta {
        // A delta lobe: pdf 1 by convention (a discrete choice of 1), pdf() 0.
        let ok = s.pdf == 1.0 && b.pdf(s.wi, wo) == 0.0;
        return (!ok).then(|| format!("delta sample {s:?}, pdf() {}", b.pdf(s.wi, wo)));
    }
    let p = b.pdf(s.wi, wo);
    let close = (s.pdf - p).abs() <= src.pdf_tolerance * s.pdf.abs().max(p.abs());
    if !(s.pdf.is_finite() && s.pdf > 0.0 && p > 0.0 && close) {
        return Some(format!("wi {}: sample's pdf {} vs pdf() {p}", s.wi, s.pdf));
    }
    None
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    #[test]
    fn a_sample_is_a_unit_direction_above_with_its_density_or_none(
        wo in view(),
        ux in coordinate(),
        uy in coordinate(),
    ) {
        let u = DVec2::new(ux, uy);
        let bad: Vec<String> = sources()
            .iter()
            .filter_map(|s| violation(s, wo, u).map(|v| format!("{}: {v}", s.name)))
            .collect();
        prop_assert!(bad.is_empty(), "wo {}, u {}:\n{}", wo, u, bad.join("\n"));
    }
}
