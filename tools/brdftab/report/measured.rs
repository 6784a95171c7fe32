//! The measured-table benchmark: for each RGL file, the default bake against the file's own
//! (native) evaluation, in the same run — error, file size, resident memory, single-lookup
//! time and batch rate, and the ratios the goals are stated in.
//!
//! What a renderer writer asks before choosing a table over the measurement's own reader: is
//! it as accurate (relative RMSE of f_r cos θi cos θo, both directions within 80°), no larger
//! than the file, small in memory (a scene holds hundreds of materials) and faster? The two
//! timings of a row are taken back to back in one process, so their ratio holds on a machine
//! whose absolute speed varies.

use std::path::{Path, PathBuf};

use serde::Serialize;

use brdftab::analysis::accuracy::{Weight, compare_weighted};
use brdftab::analysis::fidelity::{self, Fidelity, FidelityOptions};
use brdftab::analysis::timing;
use std::time::Instant;

use glam::DVec3;

use crate::rng::Rng;
use brdftab::bake::{BakeRequest, BakeTarget};
use brdftab::brdf::Brdf;
use brdftab::error::{Error, Result};
use brdftab::geometry;
use brdftab::progress::{Progress, Stage};
use brdftab::source::{self, OpenOptions};

/// How [`run`] measures.
#[derive(Debug, Clone)]
pub struct MeasuredOptions {
    /// Random pairs of the error (both directions within 80°; 100 000 by default: on a
    /// near-mirror film 20 000 pairs give a heavy-tailed estimate, 0.2–1.0 % on one table).
    pub error_pairs: usize,
    /// Random pairs of each of the fidelity figures (whole hemisphere, grazing band).
    pub fidelity_pairs: usize,
    /// Random pairs of the timings.
    pub timing_pairs: usize,
    /// Timing repeats (medians are reported).
    pub repeats: usize,
    /// Where the baked tables are written (removed afterwards unless `keep`).
    pub dir: PathBuf,
    /// Keep the baked tables.
    pub keep: bool,
}

impl Default for MeasuredOptions {
    fn default() -> Self {
        MeasuredOptions {
            error_pairs: 100_000,
            fidelity_pairs: 100_000,
            timing_pairs: 1_000_000,
            repeats: 5,
            dir: std::env::temp_dir().join(format!("brdftab-measured-{}", std::process::id())),
            keep: false,
        }
    }
}

/// One RGL file against its default table.
#[derive(Debug, Clone, Serialize)]
pub struct MeasuredRow {
    /// The file's name.
    pub file: String,
    /// The table's grid, in one line.
    pub grid: String,
    /// The stored node counts, `θh×θd×φd`.
    pub nodes: String,
    /// Relative RMSE of f_r cos θi cos θo within 80° (seed 1).
    pub rel_rmse_80: f64,
    /// The same with seed 2 (the spread of the estimate: near-mirror peaks make it noisy).
    pub rel_rmse_80_seed2: f64,
    /// The figures over the whole domain ([`fidelity::measure`]: whole hemisphere, grazing band,
    /// worst directional albedo over θ′ = 1–89°, and the three relative RMSEs on the
    /// mirror-centred rule).
    pub fidelity: Fidelity,
    /// Bytes of the RGL file.
    pub rgl_bytes: u64,
    /// Bytes of the table file.
    pub table_bytes: u64,
    /// Bytes of decoded values the open table holds while evaluating.
    pub resident_bytes: u64,
    /// ns per native evaluation (one thread, median over rounds).
    pub native_ns: f64,
    /// ns per table lookup (one thread, median over rounds); each round times the native
    /// evaluation and then the table on the same pairs.
    pub table_ns: f64,
    /// Median over rounds of native ns / table ns within the round (paired, so the machine's
    /// changing speed cancels).
    pub speedup: f64,
    /// ns per table lookup on the same pairs rounded to f32 (as renderers pass them; one
    /// thread, median over rounds of [`timing::lookups`]).
    pub table_ns_f32: f64,
    /// Native batch rate, lookups per second per core of CPU time.
    pub native_batch_per_core: f64,
    /// Table batch rate, lookups per second per core of CPU time.
    pub table_batch_per_core: f64,
    /// Seconds the bake took.
    pub bake_seconds: f64,
}

pub use brdftab::measured::data::rgl_files;

/// Bakes every file with the defaults and measures it against its native evaluation.
///
/// The tables go to `opts.dir`, which is removed afterwards unless `opts.keep` — also when a
/// file fails.
pub fn run(
    files: &[PathBuf],
    opts: &MeasuredOptions,
    progress: &dyn Progress,
) -> Result<Vec<MeasuredRow>> {
    std::fs::create_dir_all(&opts.dir).map_err(|e| Error::io(&opts.dir, e))?;
    let rows = rows(files, opts, progress);
    if !opts.keep {
        let _ = std::fs::remove_dir_all(&opts.dir);
    }
    rows
}

fn rows(
    files: &[PathBuf],
    opts: &MeasuredOptions,
    progress: &dyn Progress,
) -> Result<Vec<MeasuredRow>> {
    let _stage = Stage::begin(progress, "measuring", files.len() as u64);
    let mut rows = Vec::with_capacity(files.len());
    for (k, f) in files.iter().enumerate() {
        let r = row(f, opts);
        progress.set(k as u64 + 1);
        rows.push(r?);
    }
    Ok(rows)
}

fn row(f: &Path, opts: &MeasuredOptions) -> Result<MeasuredRow> {
    let file = f
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    // By their paths, not as text: a directory whose name is not UTF-8 would not be found.
    let out = opts.dir.join(format!("{file}.btdb"));
    let report = BakeRequest::new(f).run(&BakeTarget::File(out.clone()))?;
    let native = source::open(f)?;
    let table = source::open_table(&out, &OpenOptions::default())?;
    let cap = 80f64.to_radians();
    let w = Weight::CosInCosOut;
    let e1 = compare_weighted(&table, native.as_ref(), opts.error_pairs, 1, cap, w)?;
    let e2 = compare_weighted(&table, native.as_ref(), opts.error_pairs, 2, cap, w)?;
    let fidelity = fidelity::measure(
        &table,
        native.as_ref(),
        &FidelityOptions {
            pairs: opts.fidelity_pairs,
            ..Default::default()
        },
    )?;
    let single = paired(native.as_ref(), &table, opts.timing_pairs, opts.repeats);
    let tn = timing::lookups(native.as_ref(), opts.timing_pairs / 4, opts.repeats)?;
    let tt = timing::lookups(&table, opts.timing_pairs, opts.repeats)?;
    let bytes = |p: &Path| {
        std::fs::metadata(p)
            .map(|m| m.len())
            .map_err(|e| Error::io(p, e))
    };
    Ok(MeasuredRow {
        file,
        grid: report.grid.summary(),
        nodes: {
            let [h, _, d, p] = report.grid.stored_shape();
            format!("{h}×{d}×{p}")
        },
        rel_rmse_80: e1.rel_rmse,
        rel_rmse_80_seed2: e2.rel_rmse,
        fidelity,
        rgl_bytes: bytes(f)?,
        table_bytes: bytes(&out)?,
        resident_bytes: table.resident_bytes() as u64,
        native_ns: single.0,
        table_ns: single.1,
        speedup: single.2,
        table_ns_f32: tt.ns_per_lookup_f32_directions,
        native_batch_per_core: tn.lookups_per_s_batch_per_core_cpu_time,
        table_batch_per_core: tt.lookups_per_s_batch_per_core_cpu_time,
        bake_seconds: report.seconds,
    })
}

/// Single-thread ns per lookup of `a` and `b` over the same random pairs, in `rounds` rounds of
/// a then b (wall clock: CPU-time clocks tick too coarsely for ~70 ns lookups): medians of a,
/// b and of the per-round ratio a/b.
fn paired(a: &dyn Brdf, b: &dyn Brdf, pairs: usize, rounds: usize) -> (f64, f64, f64) {
    let mut rng = Rng::new(2024);
    let p: Vec<(DVec3, DVec3)> = (0..pairs.max(1))
        .map(|_| {
            (
                geometry::uniform_hemisphere(rng.next_dvec2()),
                geometry::uniform_hemisphere(rng.next_dvec2()),
            )
        })
        .collect();
    let c = a.channels().len();
    let mut out = vec![0f32; p.len() * c];
    let time = |s: &dyn Brdf, out: &mut [f32]| {
        let t = Instant::now();
        for ((wi, wo), o) in p.iter().zip(out.chunks_exact_mut(c)) {
            s.eval(*wi, *wo, o);
        }
        std::hint::black_box(&*out);
        t.elapsed().as_secs_f64() * 1e9 / p.len() as f64
    };
    // Warm up both (lazy chunks, page faults).
    time(a, &mut out);
    time(b, &mut out);
    let (mut ta, mut tb, mut r) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..rounds.max(1) {
        let x = time(a, &mut out);
        let y = time(b, &mut out);
        ta.push(x);
        tb.push(y);
        r.push(x / y);
    }
    (median(&mut ta), median(&mut tb), median(&mut r))
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|x, y| x.total_cmp(y));
    v[v.len() / 2]
}

/// The fidelity figures of the rows as a Markdown table: the 80° cap, the whole hemisphere and
/// the grazing band (random pairs, and on the mirror-centred rule), and the worst albedo error.
pub fn fidelity_markdown(rows: &[MeasuredRow]) -> String {
    let mut s = String::from(
        "| file | grid | within 80° | whole hemisphere | grazing band | rule: 80° / whole / grazing | worst albedo (θ′ = 1–89°) |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let f = &r.fidelity;
        let ch = ["R", "G", "B"]
            .get(f.albedo.channel)
            .copied()
            .unwrap_or("?");
        let [cap, whole, grazing, r_cap, r_whole, r_grazing, albedo] = f.percents();
        s += &format!(
            "| {} | {} | {cap:.2} % | {whole:.2} % | {grazing:.2} % | {r_cap:.2} / {r_whole:.2} / {r_grazing:.2} % | {albedo:.2} % at {}°, {ch} |\n",
            r.file, r.nodes, f.albedo.theta_deg,
        );
    }
    s
}

/// The rows as a Markdown table (the form BENCHMARKS.md quotes).
pub fn markdown(rows: &[MeasuredRow]) -> String {
    let mut s = String::from(
        "| file | error (seed 1 / 2) | RGL bytes | table bytes | resident | native ns | table ns | speedup | table ns, f32 pairs | batch M/s/core (table / native) |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {} | {:.2}% / {:.2}% | {} | {} ({:.2}×) | {:.2} MB | {:.0} | {:.1} | {:.1}× | {:.1} | {:.1} / {:.2} |\n",
            r.file,
            r.rel_rmse_80 * 100.0,
            r.rel_rmse_80_seed2 * 100.0,
            r.rgl_bytes,
            r.table_bytes,
            r.table_bytes as f64 / r.rgl_bytes as f64,
            r.resident_bytes as f64 / 1e6,
            r.native_ns,
            r.table_ns,
            r.speedup,
            r.table_ns_f32,
            r.table_batch_per_core / 1e6,
            r.native_batch_per_core / 1e6,
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_directory_without_rgl_files_is_an_error() {
        let d = brdftab::testkit::TempDir::new("empty");
        assert!(matches!(rgl_files(d.path()), Err(Error::NotFound(_))));
    }

    #[test]
    fn a_failed_run_removes_its_tables_directory() {
        let d = brdftab::testkit::TempDir::new("measured-fail");
        let junk = d.join("junk.bsdf");
        std::fs::write(&junk, b"not a tensor file").unwrap();
        let opts = MeasuredOptions {
            dir: d.join("tables"),
            ..MeasuredOptions::default()
        };
        assert!(run(&[junk], &opts, &brdftab::progress::Silent).is_err());
        assert!(!opts.dir.exists(), "{} left behind", opts.dir.display());
    }
}
