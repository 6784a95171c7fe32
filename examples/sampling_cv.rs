//! The coefficient of variation of sample weights w = f_r cos θi / pdf (issue #24): for each
//! SOURCE, natively (RGL files: the native reader) and as the default table that
//! `brdftab bake SOURCE` makes, at views θo = 3, 15, 30, 45, 60, 75, 85°. Each figure is the
//! largest CV over four view azimuths (0.3, 1.9, 3.4, 5.0 rad), 40 000 samples each; a draw
//! without a direction counts as weight 0.
//!
//! `cargo run --release --example sampling_cv -- data/rgl/*.bsdf`
//! (`--samples N` per view; `--native-only`, `--table-only`; SOURCE may be a model spec, e.g.
//! `'{"model": "ggx", "alpha": 0.1, "fresnel": {"conductor": "Cu"}}'`; `--grid G` bakes on grid
//! G instead of the default, e.g. `medium`.)

use std::time::Instant;

use brdftab::Brdf;
use brdftab::analysis::weights::weight_stats;
use brdftab::bake::{BakeRequest, BakeTarget, GridChoice};
use brdftab::geometry;
use brdftab::source;

const VIEWS: [f64; 7] = [3.0, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0];
const PHIS: [f64; 4] = [0.3, 1.9, 3.4, 5.0];

fn row(label: &str, b: &dyn Brdf, samples: usize) {
    let t = Instant::now();
    // Build any lazy structure before timing the rows.
    let _ = b.pdf(glam::DVec3::Z, glam::DVec3::Z);
    let build = t.elapsed().as_secs_f64();
    let mut cells = Vec::new();
    let mut worst_max = 0.0f64;
    for &v in &VIEWS {
        let mut cv = 0.0f64;
        for (k, &phi) in PHIS.iter().enumerate() {
            let wo = geometry::spherical(v.to_radians(), phi);
            let s = weight_stats(b, wo, samples, 1000 + k as u64);
            cv = if s.cv.is_nan() { f64::NAN } else { cv.max(s.cv) };
            worst_max = worst_max.max(s.max_over_mean);
        }
        cells.push(format!("{cv:6.3}"));
    }
    println!(
        "| {label:<34} | {} | {worst_max:7.1} | {build:5.2} |",
        cells.join(" | ")
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut samples = 40_000;
    let (mut native, mut table) = (true, true);
    let mut grid: Option<GridChoice> = None;
    let mut sources = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--samples" => samples = args.next().and_then(|s| s.parse().ok()).unwrap_or(samples),
            "--native-only" => table = false,
            "--table-only" => native = false,
            "--grid" => grid = args.next().map(|g| g.parse()).transpose()?,
            _ => sources.push(a),
        }
    }
    println!(
        "| source | {} | max w/mean | build s |",
        VIEWS.map(|v| format!("{v}°")).join(" | ")
    );
    println!("|---|{}---|---|", "---|".repeat(VIEWS.len()));
    let dir = std::env::temp_dir().join(format!("brdftab-sampling-cv-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    for (i, s) in sources.iter().enumerate() {
        let name = std::path::Path::new(s)
            .file_stem()
            .map(|f| f.to_string_lossy().replace("_rgb", ""))
            .filter(|n| !s.trim_start().starts_with('{') && !n.is_empty())
            .unwrap_or_else(|| format!("source {i}"));
        if native {
            let b = source::open(s)?;
            row(&format!("{name} native"), b.as_ref(), samples);
        }
        if table {
            let out = dir.join(format!("{i}.btdb"));
            let mut req = BakeRequest::new(s.as_str());
            if let Some(g) = grid {
                req = req.grid(g);
            }
            req.run(&BakeTarget::file(out.to_string_lossy()))?;
            let b = source::open(&out.to_string_lossy())?;
            row(&format!("{name} table"), b.as_ref(), samples);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
