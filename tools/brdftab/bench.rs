//! `bench`: lookups of a SOURCE timed on random pairs, single-threaded and in batches.

use std::fmt::Write as _;
use std::time::Instant;

use brdftab::rng::Pcg32;
use brdftab::table::Interp;
use brdftab::{Error, Result, geometry};
use clap::Args;
use glam::DVec3;
use serde_json::json;

use crate::source;
use crate::table::print_out;

/// Arguments of `brdftab bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// The source: a table file or a model spec.
    source: String,
    /// Number of random pairs.
    #[arg(long, default_value_t = 1_000_000)]
    pairs: usize,
    /// Interpolation for tables: nearest or linear.
    #[arg(long, default_value = "linear")]
    interp: String,
    /// Wavelengths (model specs only).
    #[arg(long)]
    wavelengths: Option<String>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// `brdftab bench`.
pub fn bench(a: BenchArgs) -> Result<()> {
    if a.pairs == 0 {
        return Err(Error::arg("--pairs", "must be positive"));
    }
    let interp = Interp::parse(&a.interp)?;
    let channels = source::channels(a.wavelengths.as_deref())?;
    let src = source::open_with(&a.source, &channels, interp)?;
    let c = src.channels().len();
    let mut rng = Pcg32::new(2024);
    let (wi, wo): (Vec<DVec3>, Vec<DVec3>) = (0..a.pairs)
        .map(|_| {
            (
                geometry::uniform_hemisphere(rng.next_dvec2()),
                geometry::uniform_hemisphere(rng.next_dvec2()),
            )
        })
        .unzip();
    let mut out = vec![0.0f32; a.pairs * c];
    // Warm up (loads lazy chunks, faults pages).
    src.eval_batch(&wi, &wo, &mut out);
    let repeats = 5;
    let n = a.pairs as f64;
    let threads = rayon::current_num_threads();
    let mut o = String::new();
    let (mut single, mut single_cpu) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        let (t, cpu) = (Instant::now(), thread_cpu_ns());
        for (k, o) in out.chunks_exact_mut(c).enumerate() {
            src.eval(wi[k], wo[k], o);
        }
        single.push(t.elapsed().as_secs_f64() * 1e9 / n);
        if let (Some(a0), Some(a1)) = (cpu, thread_cpu_ns()) {
            single_cpu.push((a1 - a0) as f64 / n);
        }
        std::hint::black_box(&out);
    }
    let (mut batch, mut batch_cpu) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        let (t, cpu) = (Instant::now(), process_cpu_ns());
        src.eval_batch(&wi, &wo, &mut out);
        batch.push(n / t.elapsed().as_secs_f64());
        if let (Some(a0), Some(a1)) = (cpu, process_cpu_ns()) {
            // Per core of CPU time: independent of how busy the machine is and of how many
            // threads `eval_batch` used.
            batch_cpu.push(n / ((a1 - a0) as f64 * 1e-9));
        }
        std::hint::black_box(&out);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(|x, y| x.total_cmp(y));
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    let ns = median(&mut single);
    let per_s = median(&mut batch);
    let ns_cpu = median(&mut single_cpu);
    let per_s_cpu = median(&mut batch_cpu);
    if a.json {
        let v = json!({
            "source": src.describe(),
            "pairs": a.pairs,
            "channels": c,
            "interp": interp,
            "ns_per_lookup_single_thread": ns,
            "cpu_ns_per_lookup_single_thread": ns_cpu,
            "lookups_per_s_batch": per_s,
            "lookups_per_s_batch_per_core_cpu_time": per_s_cpu,
            "threads": threads,
        });
        let _ = writeln!(
            o,
            "{}",
            serde_json::to_string_pretty(&v).unwrap_or_default()
        );
    } else {
        let _ = writeln!(o, "source:  {}", src.describe());
        let _ = writeln!(o, "pairs:   {} ({c} channels, {interp:?})", a.pairs);
        let _ = writeln!(
            o,
            "single:  {ns:.1} ns per lookup wall, {ns_cpu:.1} ns CPU time (median of {repeats}, one thread)"
        );
        let _ = writeln!(
            o,
            "batch:   {:.2} M lookups/s wall (eval_batch, up to {threads} threads), {:.2} M/s per core of CPU time (median of {repeats})",
            per_s / 1e6,
            per_s_cpu / 1e6
        );
    }
    print_out(&o)
}

/// CPU time of the calling thread in ns (Linux `/proc/thread-self/schedstat`); the machine may be
/// shared, so wall-clock figures alone mislead.
pub fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

/// CPU time of every thread of the process in ns.
pub fn process_cpu_ns() -> Option<u64> {
    let mut total = 0;
    for e in std::fs::read_dir("/proc/self/task").ok()? {
        let p = e.ok()?.path().join("schedstat");
        if let Ok(s) = std::fs::read_to_string(p) {
            total += s.split_whitespace().next()?.parse::<u64>().ok()?;
        }
    }
    Some(total)
}
