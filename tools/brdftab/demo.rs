//! `demo`: the README's main job in one command.
//!
//! 1. The plausibility table of the lecture's models (`--plausibility` prints only this).
//! 2. Bakes the lecture's tabulatable models and the RGL-EPFL materials into one database
//!    (`demo-out/demo.btdb`) through the library's `BakeRequest`, reads every table back from it
//!    and prints one row per source: grid, stored bytes, size relative to the same values as
//!    plain f32, and the accuracy suite's metrics ([`suite::metrics`]) of the table against its
//!    source, plausibility of the stored table.
//! 3. Preview renders (source | table | difference) as PNGs.
//! 4. A rate–distortion sweep (presets × codecs) of Cook-Torrance gold through the accuracy
//!    suite: `rd.csv` and its plot `rd.png`.
//!
//! Everything here is library calls; this file only chooses sources and prints.

use std::path::PathBuf;
use std::time::Instant;

use brdftab::analysis::{fidelity, plausibility};
use brdftab::bake::{BakeRequest, BakeTarget, SymmetryChoice};
use brdftab::store;
use brdftab::table::TabulatedBrdf;
use brdftab::table::presets::Preset;
use brdftab::{Brdf, Channels, Error, Result};
use brdftab_tools::report::suite::{self, MetricOptions};
use clap::Args;

use crate::bake::flag_named;
use crate::demo_extra::{BAKED_MODELS, plausibility_table, preview_renders, rate_distortion};
use brdftab_tools::text::print_out;

/// Arguments of `brdftab demo`.
#[derive(Args)]
pub struct DemoArgs {
    /// Print only the plausibility table of the lecture's models.
    #[arg(long, conflicts_with_all = ["out", "preset", "rgl", "quick"])]
    plausibility: bool,
    /// Output directory (created).
    #[arg(long, default_value = "demo-out")]
    out: PathBuf,
    /// Grid preset of every table: small, medium, large (default: what `brdftab bake` does with
    /// no options — the medium preset for models, or their adaptive table or the preset's
    /// calibrated where the preset's albedo is off by over 1 %, the adaptive default grid for
    /// RGL files).
    #[arg(long)]
    preset: Option<String>,
    /// Directory of RGL-EPFL `.bsdf` files (default: $BRDFTAB_RGL_DIR, else the shipped
    /// data/rgl, else ../shared/data/measured/rgl).
    #[arg(long)]
    rgl: Option<PathBuf>,
    /// Skip the preview renders and the rate–distortion sweep.
    #[arg(long)]
    quick: bool,
}

/// Pairs of the accuracy comparison (per source).
const ACCURACY_PAIRS: usize = 50_000;

/// A source of the demo: table name, SOURCE string, whether it is measured, the opened BRDF.
struct Source {
    name: String,
    source: std::ffi::OsString,
    measured: bool,
    brdf: Box<dyn Brdf + Send + Sync>,
}

/// Runs the demo.
pub fn demo(a: DemoArgs) -> Result<()> {
    let t0 = Instant::now();
    let preset = a.preset.as_deref().map(str::parse::<Preset>).transpose();
    let preset = preset.map_err(|e| flag_named(e, "--preset"))?;
    plausibility_table()?;
    eprintln!("[{:.1} s] plausibility table", t0.elapsed().as_secs_f64());
    if a.plausibility {
        return Ok(());
    }
    std::fs::create_dir_all(&a.out).map_err(|e| Error::io(&a.out, e))?;
    let out = a.out.canonicalize().map_err(|e| Error::io(&a.out, e))?;
    let db = out.join("demo.btdb");
    if db.exists() {
        std::fs::remove_file(&db).map_err(|e| Error::io(&db, e))?;
    }
    let sources = sources(a.rgl.as_deref())?;

    // Bake every source into the database.
    print_out(&format!(
        "\nBaking {} sources (grids: {}) into {}\n",
        sources.len(),
        a.preset.as_deref().unwrap_or(
            "the defaults: medium preset for models (adaptive or calibrated where its albedo \
                 is off by over 1 %), adaptive for RGL files",
        ),
        db.display()
    ))?;
    let bar = brdftab_tools::progress::Bar::values();
    let target = |name: &str| BakeTarget::db(&db, name);
    let mut seconds = Vec::new();
    for s in &sources {
        let req = BakeRequest::new(&s.source).channels(Channels::Rgb);
        let req = match preset {
            // The library's defaults: what a user gets from `brdftab bake SOURCE`.
            None => req,
            // What each source declares (measured data meets it only up to noise).
            Some(p) => req.preset(p).symmetry(SymmetryChoice::Declared),
        };
        bar.prefix(&s.name);
        seconds.push(req.run_with(&target(&s.name), &bar)?.seconds);
    }

    // Read every table back from the database and measure it against its source.
    eprintln!("[{:.1} s] baked", t0.elapsed().as_secs_f64());
    let st = store::Store::open(&db)?;
    print_out(&format!(
        "\n{:<24} {:<30} {:>9} {:>7} {:>9} {:>8} {:<13} {:>6}\n",
        "source",
        "grid (stored)",
        "bytes",
        "vs f32",
        "rel RMSE",
        "albedo",
        "pos/rec/energy",
        "bake s"
    ))?;
    let thetas: Vec<f64> = [0.0f64, 30.0, 60.0, 80.0].map(f64::to_radians).to_vec();
    // The native RGL reader is discontinuous at normal incidence (it turns each measurement
    // into the frame of φi, undefined at θi = 0: up to 25 % between θi = 0 and ±0.2° on
    // cc_iris_purple_gem), so measured rows start at 2°.
    let measured_thetas: Vec<f64> = [2.0f64, 30.0, 60.0, 80.0].map(f64::to_radians).to_vec();
    let mut previews: Vec<(String, &dyn Brdf, TabulatedBrdf)> = Vec::new();
    let mut fidelity_rows = Vec::new();
    for (s, bake_s) in sources.iter().zip(seconds) {
        let stored = st.table(&s.name)?;
        let bytes = stored.compressed_bytes();
        let tab = TabulatedBrdf::from_table(stored.to_table()?);
        let f32_bytes = tab.grid().stored_values() as f64 * 4.0;
        // Weighted by cos θi cos θo, measured data within 80° of the normal, as the accuracy
        // suite's rows (`suite::rmse_weighting`).
        let (cap, weight) = suite::rmse_weighting(s.measured);
        let opts = MetricOptions {
            pairs: ACCURACY_PAIRS,
            seed: 1,
            albedo_thetas: if s.measured {
                measured_thetas.clone()
            } else {
                thetas.clone()
            },
            cap,
            weight,
        };
        let src_albedo = suite::albedos(s.brdf.as_ref(), &opts.albedo_thetas);
        let m = suite::metrics(&tab, s.brdf.as_ref(), &src_albedo, &opts)?;
        let r = plausibility::check(&tab, &fast_plausibility())?;
        let yn = |b: bool| if b { "y" } else { "N" };
        let shape = tab.grid().stored_shape().map(|x| x.to_string()).join("×");
        print_out(&format!(
            "{:<24} {:<30} {:>9} {:>6.2}% {:>8.3}% {:>7.3}% {:<13} {:>6.2}\n",
            s.name,
            format!("{} {shape}", tab.grid().param()),
            bytes,
            100.0 * bytes as f64 / f32_bytes,
            100.0 * m.rel_rmse,
            100.0 * m.albedo_err,
            format!(
                "{}/{}/{}",
                yn(r.positive),
                yn(r.reciprocal),
                yn(r.energy_conserving)
            ),
            bake_s
        ))?;
        let f = fidelity::measure(&tab, s.brdf.as_ref(), &fidelity_options())?;
        fidelity_rows.push((s.name.clone(), f));
        if matches!(
            s.name.as_str(),
            "cook_torrance_gold" | "ward_aniso" | "rgl_satin_rosaline"
        ) {
            previews.push((s.name.clone(), s.brdf.as_ref(), tab));
        }
    }
    print_out(
        "\nbytes: compressed size in the database (log16 ≤ 1e-3 relative + predictor + zstd); vs f32: that size \
         relative to the stored values as plain f32;\nrel RMSE: relative RMSE of f_r cos θi cos θo of \
         the table read back from the database vs its source (50k random pairs over the whole hemisphere;\nmeasured rows (rgl_*): with both directions within 80° of the normal, as `brdftab bench --measured`, since their f_r grows like 1/cos θo at grazing — see BENCHMARKS.md;\nweighted by cos θi alone the RMS is infinite for measured data, Ward and Cook-Torrance);\nalbedo: max \
         relative albedo error at θ′ = 0, 30, 60, 80° (measured rows: 2°, not 0°, where their reader is discontinuous; the accuracy suite's, floored at 1e-3 of the largest albedo); pos/rec/energy: plausibility of the stored \
         table (y = yes, N = no;\nmeasured data is not reciprocal, satin_rosaline's own file \
         reflects more than it receives past 75° (`brdftab check` on it: albedo up to 1.16), and \
         the lecture's Lambert kd = 0.5 is not energy conserving).\n",
    )?;

    if !fidelity_rows.is_empty() {
        print_out(&format!(
            "\nEvery table over the whole domain (relative RMSE of f_r cos θi cos θo on a mirror-centred rule; albedo: worst over θ′ = 1..89°):\n{:<24} {:>9} {:>9} {:>9} {:>20}\n",
            "source", "≤ 80°", "whole", "grazing", "albedo"
        ))?;
        for (name, f) in &fidelity_rows {
            print_out(&format!(
                "{:<24} {:>8.2}% {:>8.2}% {:>8.2}% {:>8.2}% at {:>2}° {}\n",
                name,
                100.0 * f.rule.cap,
                100.0 * f.rule.whole,
                100.0 * f.rule.grazing,
                100.0 * f.albedo.worst,
                f.albedo.theta_deg,
                ["R", "G", "B"]
                    .get(f.albedo.channel)
                    .copied()
                    .unwrap_or("?"),
            ))?;
        }
        print_out(
            "(the measured tables' bars: 1 % within 80°, 1.5 % whole, 3 % grazing, 1 % albedo; `brdftab bench --measured` adds random-pair figures, sizes and speed. Ward's f_r grows like 1/√(cos θi cos θo): its table stores f_r cos θi cos θo, and its f_r nearest the horizon grows like 1/cos θo instead — see BENCHMARKS.md)\n",
        )?;
    }
    eprintln!("[{:.1} s] tables measured", t0.elapsed().as_secs_f64());
    let mut outputs = vec![db.clone()];
    if !a.quick {
        outputs.extend(preview_renders(&out, &previews)?);
        eprintln!("[{:.1} s] renders done", t0.elapsed().as_secs_f64());
        outputs.extend(rate_distortion(&out)?);
    }
    let mut text = format!("\nDone in {:.1} s. Outputs:\n", t0.elapsed().as_secs_f64());
    for p in outputs {
        text += &format!("  {}\n", p.display());
    }
    print_out(&text)
}

/// The models, then the RGL materials found on disk.
fn sources(rgl: Option<&std::path::Path>) -> Result<Vec<Source>> {
    let mut v = Vec::new();
    for (name, spec) in BAKED_MODELS {
        let brdf = brdftab::ModelSpec::parse(spec)?.build(&Channels::Rgb)?;
        let (name, source) = (name.to_string(), spec.into());
        v.push(Source {
            name,
            source,
            measured: false,
            brdf,
        });
    }
    let Some(dir) = crate::source::rgl_dir(rgl) else {
        eprintln!(
            "note: no RGL directory found (--rgl DIR or $BRDFTAB_RGL_DIR); baking the models only"
        );
        return Ok(v);
    };
    for sd in suite::rgl_sources(&dir)? {
        let name = format!("rgl_{}", sd.name.trim_end_matches("_rgb"));
        let (source, brdf) = (sd.source(), sd.open()?);
        v.push(Source {
            name,
            source,
            measured: true,
            brdf,
        });
    }
    Ok(v)
}

/// The demo's whole-domain figures of every table: the albedo at every degree on the rule
/// `bench --measured` uses, random pairs left to it (the rule's figures are printed).
fn fidelity_options() -> fidelity::FidelityOptions {
    // Fewer pairs than `bench --measured`, but its albedo quadrature: 64 azimuths of order 6
    // printed a third of the worst albedo error of two RGL tables (iris 0.11 % where the
    // library's albedo gives 0.30 % and `bench --measured` 0.43 %).
    fidelity::FidelityOptions {
        pairs: 1000,
        ..Default::default()
    }
}

/// The plausibility check of the stored tables: fewer pairs and angles, and the albedo with the
/// accuracy suite's bounded quadrature.
fn fast_plausibility() -> plausibility::Options {
    plausibility::Options {
        pairs: 4000,
        thetas_deg: vec![0.0, 30.0, 60.0, 85.0],
        albedo: Some(suite::ALBEDO_OPTIONS),
        ..Default::default()
    }
}
