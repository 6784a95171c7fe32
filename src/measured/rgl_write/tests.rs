//! Writer tests: round trips through brdftab's reader, the issue's error bars, bad input.

use super::*;
use crate::measured::RglBrdf;
use crate::measured::tensor::TensorFile;
use crate::spec::ModelSpec;
use crate::spectrum::Channels;

pub(crate) const CT_GOLD: &str =
    r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#;
pub(crate) const GGX_COPPER: &str = r#"{"model": "sum", "terms": [{"model": "lambert", "kd": [0.12, 0.06, 0.04]}, {"model": "ggx", "alpha": 0.2, "fresnel": {"conductor": "Cu"}}]}"#;

fn model(spec: &str, ch: &Channels) -> Box<dyn Brdf> {
    ModelSpec::parse(spec).unwrap().build(ch).unwrap()
}

/// Encodes, reads back from bytes, reports.
fn roundtrip(src: &dyn Brdf, opts: &Options, pairs: usize) -> (Fields, RglBrdf, Report) {
    let f = encode(src, opts, None).unwrap();
    let t = TensorFile::from_bytes("mem.bsdf", f.to_bytes()).unwrap();
    let r = RglBrdf::from_tensor(&t, None).unwrap();
    let rep = report(&r, src, pairs, 7).unwrap();
    (f, r, rep)
}

#[test]
fn explore() {
    for spec in [CT_GOLD, GGX_COPPER] {
        let b = model(spec, &Channels::Rgb);
        let t = std::time::Instant::now();
        let env = |k: &str, d: usize| {
            std::env::var(k)
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(d)
        };
        let o = Options {
            resolution: Some(env("BT_N", 64)),
            theta_i: Some(env("BT_T", 16)),
            ndf_resolution: Some(env("BT_V", 128)),
            ..Options::default()
        };
        let (_, _, rep) = roundtrip(&*b, &o, 20_000);
        eprintln!(
            "{spec}: {:.4e} max {:.3e} ({:.2}s)",
            rep.rel_rmse,
            rep.max_rel,
            t.elapsed().as_secs_f64()
        );
    }
}

/// The shipped RGL files: `data/rgl` under the crate, else `../shared/data/measured/rgl`.
/// Panics (fails the test) when neither exists.
pub(crate) fn rgl_dir() -> std::path::PathBuf {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    [
        root.join("data/rgl"),
        root.join("../shared/data/measured/rgl"),
    ]
    .into_iter()
    .find(|d| d.is_dir())
    .expect("no RGL data: neither data/rgl nor ../shared/data/measured/rgl exists")
}

pub(crate) fn rgl_files() -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(rgl_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "bsdf"))
        .collect();
    v.sort();
    assert!(!v.is_empty(), "no .bsdf files in {}", rgl_dir().display());
    v
}

#[test]
fn explore_measured() {
    let env = |k: &str, d: usize| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let o = Options {
        resolution: Some(env("BT_N", 64)),
        theta_i: Some(env("BT_T", 16)),
        ndf_resolution: Some(env("BT_V", 128)),
        ..Options::default()
    };
    let ct = model(CT_GOLD, &Channels::Rgb);
    let m = crate::measured::MerlBrdf::from_bytes(
        "ct.binary",
        &crate::measured::MerlBrdf::from_brdf(&*ct).to_bytes(),
    )
    .unwrap();
    let (_, _, rep) = roundtrip(&m, &o, 20_000);
    eprintln!("MERL ct: {:.4e} max {:.3e}", rep.rel_rmse, rep.max_rel);
    let (_, w, _) = roundtrip(&m, &o, 1000);
    eprintln!(
        "MERL vs CT {:.4e}; written(MERL) vs CT {:.4e}",
        report(&m, &*ct, 20_000, 7).unwrap().rel_rmse,
        report(&w, &*ct, 20_000, 7).unwrap().rel_rmse
    );
    for spec in [
        r#"{"model": "cook_torrance", "m": 0.5, "fresnel": {"conductor": "Au"}}"#,
        r#"{"model": "oren_nayar", "kd": 0.25, "sigma": 0.3}"#,
        r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2}, {"model": "cook_torrance", "m": 0.4, "ks": 0.5}]}"#,
    ] {
        let b = model(spec, &Channels::Rgb);
        let m = crate::measured::MerlBrdf::from_bytes(
            "x.binary",
            &crate::measured::MerlBrdf::from_brdf(&*b).to_bytes(),
        )
        .unwrap();
        let (_, _, rep) = roundtrip(&m, &o, 20_000);
        eprintln!(
            "MERL {spec}: {:.4e}; MERL vs model {:.4e}",
            rep.rel_rmse,
            report(&m, &*b, 20_000, 7).unwrap().rel_rmse
        );
    }
    for p in rgl_files() {
        let src = RglBrdf::open(&p).unwrap();
        let o = Options {
            parameterization: Some(Parameterization::from_file(&p).unwrap()),
            ..Options::default()
        };
        let (_, _, rep) = roundtrip(&src, &o, 20_000);
        eprintln!(
            "{}: {:.4e} max {:.3e}",
            p.display(),
            rep.rel_rmse,
            rep.max_rel
        );
    }
}

#[test]
fn explore_worst() {
    let env = |k: &str, d: usize| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let o = Options {
        resolution: Some(env("BT_N", 64)),
        theta_i: Some(env("BT_T", 16)),
        ndf_resolution: Some(env("BT_V", 128)),
        ..Options::default()
    };
    let b = model(CT_GOLD, &Channels::Rgb);
    let (_, r, _) = roundtrip(&*b, &o, 20_000);
    let mut rng = crate::rng::Pcg32::with_stream(3, 0);
    let mut worst = vec![];
    for _ in 0..20000 {
        let cap = |u: glam::DVec2| {
            crate::geometry::uniform_hemisphere(glam::DVec2::new(
                1.0 - (1.0 - 80f64.to_radians().cos()) * u.x,
                u.y,
            ))
        };
        let wi = cap(rng.next_dvec2());
        let wo = cap(rng.next_dvec2());
        let (mut a, mut s) = ([0f32; 3], [0f32; 3]);
        r.eval(wi, wo, &mut a);
        b.eval(wi, wo, &mut s);
        let w = wi.z * wo.z;
        worst.push((((a[1] - s[1]) as f64 * w).abs(), wi, wo, a[1], s[1]));
    }
    worst.sort_by(|x, y| y.0.partial_cmp(&x.0).unwrap());
    for (e, wi, wo, a, s) in &worst[..12] {
        let h = (*wi + *wo).normalize();
        eprintln!(
            "err {e:.3e} θi {:.1} θo {:.1} φo-φi {:.1} θh {:.1} written {a:.4} src {s:.4}",
            wi.z.acos().to_degrees(),
            wo.z.acos().to_degrees(),
            (wo.y.atan2(wo.x) - wi.y.atan2(wi.x)).to_degrees(),
            h.z.acos().to_degrees()
        );
    }
}
