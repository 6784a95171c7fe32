//! `bench`: lookups of a SOURCE timed on random pairs ([`brdftab::analysis::timing`]).

use std::fmt::Write as _;

use brdftab::analysis::timing;
use brdftab::{Error, Result};
use clap::Args;

use brdftab_tools::text::{or_unknown, print_out};

/// Arguments of `brdftab bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// Any SOURCE: a spec, a table (`FILE.btdb`, `DB#NAME`), a MERL or RGL file (not with --measured).
    #[arg(required_unless_present = "measured", conflicts_with = "measured")]
    source: Option<brdftab_tools::args::PathArg>,
    /// Instead of one source: bake every RGL `.bsdf` file of DIR (default: $BRDFTAB_RGL_DIR,
    /// else the shipped data/rgl) with the defaults and compare each table with the file's own
    /// evaluation in the same run — error, bytes, resident memory, ns per lookup, batch rate.
    #[arg(long, value_name = "DIR", num_args = 0..=1, default_missing_value = "")]
    measured: Option<brdftab_tools::args::PathArg>,
    /// Number of random pairs.
    #[arg(long, default_value_t = 1_000_000)]
    pairs: usize,
    #[command(flatten)]
    open: brdftab::request::OpenSettings,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// `brdftab bench --measured`.
fn measured(dir: &std::path::Path, a: &BenchArgs) -> Result<()> {
    use brdftab_tools::report::measured;
    let dir = match dir.to_str() {
        Some("") => brdftab::measured::data::rgl_dir().ok_or_else(|| {
            Error::NotFound(format!(
                "no RGL directory (searched {:?})",
                brdftab::measured::data::rgl_dirs()
            ))
        })?,
        _ => dir.to_path_buf(),
    };
    // The native file is timed on a quarter of the pairs.
    if a.pairs < 4 {
        return Err(Error::arg("--pairs", "must be at least 4 with --measured"));
    }
    let files = measured::rgl_files(&dir)?;
    let opts = measured::MeasuredOptions {
        timing_pairs: a.pairs,
        ..Default::default()
    };
    let bar = brdftab_tools::progress::Bar::values();
    let rows = measured::run(&files, &opts, &bar)?;
    let mut o = String::new();
    if a.json {
        let _ = writeln!(
            o,
            "{}",
            serde_json::to_string_pretty(&rows).unwrap_or_default()
        );
    } else {
        let _ = writeln!(o, "{}", measured::markdown(&rows));
        let _ = writeln!(
            o,
            "columns: error is the relative RMSE of f_r cos θi cos θo, both directions within 80°, {} pairs; \
             ns: wall time per lookup on one thread, median of {} rounds each timing the native \
             evaluation then the table on the same pairs (speedup: median of the per-round \
             ratios); f32 pairs: the table on the same pairs rounded to f32 and normalized \
             there, as renderers pass them; batch: eval_batch lookups per second of CPU time",
            opts.error_pairs, opts.repeats
        );
        let _ = writeln!(o, "\n{}", measured::fidelity_markdown(&rows));
        let _ = writeln!(
            o,
            "over the whole domain: relative RMSE of f_r cos θi cos θo over {} random pairs and on \
             a mirror-centred product rule (no heavy tail on near-mirror films), within 80°, over \
             the whole hemisphere and in the grazing band (a direction beyond 80°); albedo: the \
             worst directional-albedo error over θ′ = 1..89° and the channels (a channel darker \
             than 0.02 judged against 0.02)",
            opts.fidelity_pairs
        );
    }
    print_out(&o)
}

/// `brdftab bench`.
pub fn bench(a: BenchArgs) -> Result<()> {
    // Before either road (the measured one times the native files on a quarter of the pairs).
    if a.pairs == 0 {
        return Err(Error::arg("--pairs", "must be at least 1"));
    }
    if let Some(d) = &a.measured {
        return measured(d, &a);
    }
    let interp = a.open.interp.as_deref().unwrap_or("auto");
    let src = brdftab::request::open(a.source.clone().unwrap_or_default(), &a.open)?;
    let t = timing::lookups(src.as_ref(), a.pairs, 5)?;
    let mut o = String::new();
    if a.json {
        let mut v = serde_json::to_value(&t).unwrap_or_default();
        v["interp"] = serde_json::json!(interp);
        let _ = writeln!(
            o,
            "{}",
            serde_json::to_string_pretty(&v).unwrap_or_default()
        );
    } else {
        let (ns, ns_cpu, r) = (
            t.ns_per_lookup_single_thread,
            t.cpu_ns_per_lookup_single_thread,
            t.repeats,
        );
        let _ = writeln!(o, "source:  {}", t.source);
        let _ = writeln!(
            o,
            "pairs:   {} ({} channels, interpolation {interp})",
            t.pairs, t.channels
        );
        let _ = writeln!(
            o,
            "single:  {ns:.1} ns per lookup wall, {} ns CPU time (median of {r}, one thread)",
            or_unknown(ns_cpu, 1)
        );
        let _ = writeln!(
            o,
            "batch:   {:.2} M lookups/s wall (eval_batch, up to {} threads), {} M/s per core of CPU time (median of {r})",
            t.lookups_per_s_batch / 1e6,
            t.threads,
            or_unknown(t.lookups_per_s_batch_per_core_cpu_time / 1e6, 2)
        );
        let _ = writeln!(
            o,
            "f32:     {:.1} ns per lookup wall, {} M/s per core batch: the same pairs rounded to f32 as renderers pass them (median of {r})",
            t.ns_per_lookup_f32_directions,
            or_unknown(
                t.lookups_per_s_batch_f32_directions_per_core_cpu_time / 1e6,
                2
            )
        );
        let _ = writeln!(
            o,
            "sample:  {:.1} ns per sample (direction, pdf and weight) = {:.2}× one lookup (median of {r} rounds timing both, one thread)",
            t.ns_per_sample_single_thread, t.sample_over_eval
        );
        let _ = writeln!(
            o,
            "pdf:     {:.1} ns per pdf (same pairs, one thread)",
            t.ns_per_pdf_single_thread
        );
        let _ = writeln!(
            o,
            "sample batch: {} M samples/s per core of CPU time (sample_batch on the same views, median of {r})",
            or_unknown(t.samples_per_s_batch_per_core_cpu_time / 1e6, 2)
        );
    }
    print_out(&o)
}
