//! Accuracy of baked tables against their analytic models, per preset.
//!
//! `cargo run --release --example table_accuracy [small|medium|large ...] [--pairs N]`
//!
//! For each model: detect the symmetry, bake the preset grid (default parameterization), and
//! compare the linear (and nearest) table with the model over N random pairs: cosine-weighted
//! relative RMSE and max relative error (see `brdftab::analysis::accuracy`).

use brdftab::analysis::accuracy;
use brdftab::table::presets::Preset;
use brdftab::table::{BakeOptions, Interp, TabulatedBrdf, bake, symmetry};
use brdftab::{Channels, ModelSpec};

const MODELS: &[(&str, &str)] = &[
    ("lambert", r#"{"model": "lambert", "kd": [0.1, 0.2, 0.3]}"#),
    (
        "cook_torrance m=0.3 n=0.2 k=3",
        r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"n": 0.2, "k": 3}}"#,
    ),
    (
        "reciprocal_phong n=50",
        r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 50}"#,
    ),
    ("ggx alpha=0.1", r#"{"model": "ggx", "alpha": 0.1}"#),
    (
        "reciprocal_phong n=1000",
        r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 1000}"#,
    ),
    (
        "phong n=1000 (original)",
        r#"{"model": "phong", "ks": 0.5, "n": 1000}"#,
    ),
    (
        "ward ax=0.1 ay=0.3",
        r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
    ),
];

fn main() -> brdftab::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut presets = Vec::new();
    let mut pairs = 100_000;
    let mut only: Option<String> = None;
    let mut seeds = 1u64;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--pairs" => {
                pairs = it.next().and_then(|s| s.parse().ok()).unwrap_or_else(|| {
                    eprintln!("error: --pairs takes a whole number");
                    std::process::exit(1)
                })
            }
            "--only" => only = it.next().cloned(),
            "--seeds" => {
                seeds = it.next().and_then(|s| s.parse().ok()).unwrap_or_else(|| {
                    eprintln!("error: --seeds takes a whole number");
                    std::process::exit(1)
                })
            }
            p => presets.push(p.parse::<Preset>()?),
        }
    }
    if presets.is_empty() {
        presets.push(Preset::Medium);
    }
    println!(
        "{:<32} {:<7} {:<46} {:>10} {:>11} {:>11} {:>8}",
        "model", "preset", "grid (stored)", "values", "rmse lin", "rmse near", "max lin"
    );
    for (name, spec) in MODELS {
        if only.as_deref().is_some_and(|o| !name.contains(o)) {
            continue;
        }
        let model = match ModelSpec::parse(spec).and_then(|s| s.build(&Channels::Rgb)) {
            Ok(m) => m,
            Err(e) => {
                println!("{name:<32} skipped: {e}");
                continue;
            }
        };
        let sym = symmetry::detect(model.as_ref(), symmetry::DEFAULT_TOLERANCE);
        for &p in &presets {
            let grid = p.grid(None, sym, Channels::Rgb)?;
            let t0 = std::time::Instant::now();
            let (table, _) = bake(model.as_ref(), &grid, &BakeOptions::default())?;
            let secs = t0.elapsed().as_secs_f64();
            let lin = TabulatedBrdf::from_table(table);
            let a = accuracy::compare(&lin, model.as_ref(), pairs, 12345)?;
            let near = lin.with_interp(Interp::Nearest);
            let b = accuracy::compare(&near, model.as_ref(), pairs, 12345)?;
            let lin = near.with_interp(Interp::Linear);
            let mut spread: Vec<f64> = (1..seeds)
                .map(|s| {
                    accuracy::compare(&lin, model.as_ref(), pairs, 12345 + s)
                        .map(|a| a.rel_rmse * 100.0)
                })
                .collect::<brdftab::Result<_>>()?;
            spread.push(a.rel_rmse * 100.0);
            spread.sort_by(f64::total_cmp);
            let s = grid.stored_shape();
            println!(
                "{name:<32} {:<7} {:<46} {:>10} {:>10.3}% {:>10.3}% {:>8.3}  ({sym}, bake {secs:.1}s{})",
                format!("{p:?}").to_lowercase(),
                format!("{:?} {}x{}x{}x{}", grid.param(), s[0], s[1], s[2], s[3]),
                grid.stored_values(),
                a.rel_rmse * 100.0,
                b.rel_rmse * 100.0,
                a.max_rel,
                if seeds > 1 {
                    format!(
                        ", linear rmse over {seeds} seeds: min {:.3}% median {:.3}% max {:.3}%",
                        spread[0],
                        spread[spread.len() / 2],
                        spread[spread.len() - 1]
                    )
                } else {
                    String::new()
                }
            );
        }
    }
    Ok(())
}
