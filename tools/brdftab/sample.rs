//! `sample` and `pdf`: the importance sampler of any SOURCE, from the command line.
//!
//! `sample` prints one line per drawn direction: `wix wiy wiz pdf w_1 .. w_c` where `w` is the
//! per-channel weight f_r cos θi / pdf. Numbers are printed in Rust's shortest round-trip form,
//! so `wi` can be fed back to `pdf` or `eval` exactly. Delta samples (mirror, refractor) print
//! pdf 1 (the library's convention; a sum's mirror term: the probability of choosing it) and
//! the lobe's reflectance (over that probability) as weight; `--delta` adds a last column, 1
//! for such a draw and 0 for a smooth one.
//! Draws for which the sampler returns no direction (e.g. `wo` below the horizon) print nothing, so
//! fewer than `--count` lines may appear.

use std::io::Write;

use brdftab::{Error, Result};
use brdftab_tools::rng::Rng;
use clap::Args;

/// Arguments of `brdftab sample`.
#[derive(Args)]
pub struct SampleArgs {
    /// A spec, table, MERL or RGL SOURCE.
    source: std::ffi::OsString,
    /// The outgoing direction (towards the viewer) `X,Y,Z`; need not be normalized.
    #[arg(long, allow_hyphen_values = true)]
    wo: String,
    /// Number of draws.
    #[arg(long, default_value_t = 16)]
    count: usize,
    /// Seed of the uniform numbers (PCG32).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Append a column: 1 where the draw is a delta lobe's (a mirror, or a sum's mirror term,
    /// which `pdf` does not contain), 0 elsewhere.
    #[arg(long)]
    delta: bool,
    #[command(flatten)]
    open: brdftab::request::OpenSettings,
}

/// Arguments of `brdftab pdf`.
#[derive(Args)]
pub struct PdfArgs {
    /// A spec, table, MERL or RGL SOURCE.
    source: std::ffi::OsString,
    #[command(flatten)]
    open: brdftab::request::OpenSettings,
}

fn out_err(e: std::io::Error) -> Error {
    Error::io("stdout", e)
}

/// Draws `count` directions for `wo` and prints `wix wiy wiz pdf w_1 .. w_c`.
pub fn sample(a: SampleArgs) -> Result<()> {
    let wo = brdftab_tools::text::parse_direction(&a.wo, "--wo")?;
    let brdf = brdftab::request::open(&a.source, &a.open)?;
    let c = brdf.channels().len();
    let mut w = vec![0.0f32; c];
    let mut rng = Rng::new(a.seed);
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    for _ in 0..a.count {
        let u = rng.next_dvec2();
        let s = brdf.sample(wo, u, &mut w);
        brdf.health()?; // a corrupt table chunk: its error, not zeros
        let Some(s) = s else {
            continue;
        };
        write!(out, "{} {} {} {}", s.wi.x, s.wi.y, s.wi.z, s.pdf).map_err(out_err)?;
        for x in &w {
            write!(out, " {x}").map_err(out_err)?;
        }
        if a.delta {
            write!(out, " {}", u8::from(s.delta)).map_err(out_err)?;
        }
        writeln!(out).map_err(out_err)?;
    }
    out.flush().map_err(out_err)
}

/// Reads `wix wiy wiz wox woy woz` lines from stdin, prints pdf(wi | wo) per line.
pub fn pdf(a: PdfArgs) -> Result<()> {
    let brdf = brdftab::request::open(&a.source, &a.open)?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    brdftab_tools::text::for_each_pair(std::io::stdin().lock(), "stdin", |wi, wo| {
        let p = brdf.pdf(wi, wo);
        brdf.health()?;
        writeln!(out, "{p}").map_err(out_err)
    })?;
    out.flush().map_err(out_err)
}
