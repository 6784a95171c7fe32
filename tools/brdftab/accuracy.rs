//! `accuracy`: the accuracy suite (tables vs sources per grid and codec), CSV + Markdown + plots.

use std::path::PathBuf;

use brdftab::table::Param;
use brdftab::table::presets::Preset;
use brdftab::{Error, Result};
use brdftab_tools::report::suite::{self, SuiteConfig};
use clap::Args;

use crate::bake::flag_named;

/// Arguments of `brdftab accuracy`.
#[derive(Args)]
pub struct AccuracyArgs {
    /// Output directory (accuracy.csv, accuracy.md, rd_<source>.png).
    #[arg(long)]
    out: PathBuf,
    /// The quick suite: 11 sources, small preset, fewer pairs, tiny renders (about 1 min).
    #[arg(long)]
    quick: bool,
    /// Directory of RGL `.bsdf` files (default: $BRDFTAB_RGL_DIR, else the shipped data/rgl,
    /// else ../shared/data/measured/rgl; none → models only).
    #[arg(long)]
    rgl: Option<PathBuf>,
    /// Grid presets, comma separated (default: small for --quick, else small,medium,large).
    #[arg(long, value_name = "P[,P..]")]
    presets: Option<String>,
    /// Parameterizations, comma separated (default halfdiff,inout).
    #[arg(long, value_name = "P[,P..]")]
    params: Option<String>,
    /// Only sources whose name contains one of these comma-separated strings.
    #[arg(long, value_name = "S[,S..]")]
    only: Option<String>,
    /// Random direction pairs per row (default 20000 quick, 200000 full).
    #[arg(long)]
    pairs: Option<usize>,
    /// Skip the render metric.
    #[arg(long)]
    no_render: bool,
}

fn list(s: &str) -> impl Iterator<Item = &str> {
    s.split(',').map(str::trim).filter(|x| !x.is_empty())
}

/// Runs the suite and writes its files.
pub fn accuracy(a: AccuracyArgs) -> Result<()> {
    let rgl = crate::source::rgl_dir(a.rgl.as_deref());
    if let Some(d) = &rgl {
        if !d.is_dir() {
            return Err(Error::NotFound(format!(
                "--rgl {}: not a directory",
                d.display()
            )));
        }
    } else {
        eprintln!(
            "note: no RGL directory (--rgl DIR, $BRDFTAB_RGL_DIR, data/rgl or ../shared/data/measured/rgl): analytic models only"
        );
    }
    let mut cfg = if a.quick {
        SuiteConfig::quick(rgl.as_deref())?
    } else {
        SuiteConfig::full(rgl.as_deref())?
    };
    if let Some(p) = &a.presets {
        cfg.presets = list(p)
            .map(|p| p.parse::<Preset>().map_err(|e| flag_named(e, "--presets")))
            .collect::<Result<_>>()?;
    }
    if let Some(p) = &a.params {
        cfg.params = list(p)
            .map(|p| p.parse::<Param>().map_err(|e| flag_named(e, "--params")))
            .collect::<Result<_>>()?;
    }
    if let Some(o) = &a.only {
        let keys: Vec<&str> = list(o).collect();
        cfg.sources
            .retain(|s| keys.iter().any(|k| s.name.contains(k)));
    }
    if let Some(n) = a.pairs {
        cfg.pairs = n;
    }
    if a.no_render {
        cfg.render = None;
    }
    if cfg.sources.is_empty() || cfg.presets.is_empty() || cfg.params.is_empty() {
        return Err(Error::arg(
            "accuracy",
            "nothing to run (no sources, presets or params)",
        ));
    }
    let bar = brdftab_tools::progress::Bar::new("[{bar:30}] {pos}/{len} rows {elapsed} {msg}");
    let report = suite::run(&cfg, &bar)?;
    let files = report.write_all(&a.out)?;
    eprintln!(
        "{} rows in {:.1} s; wrote {} files to {}",
        report.rows.len(),
        report.seconds,
        files.len(),
        a.out.display()
    );
    Ok(())
}
