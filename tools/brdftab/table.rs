//! `bake`, `info` and `bench`: dense tables from the command line.

use std::fmt::Write as _;
use std::io::IsTerminal;
use std::time::Instant;

use brdftab::codec::Codec;
use brdftab::rng::Pcg32;
use brdftab::store::{Source, TableHeader, Writer, db, tables};
use brdftab::table::presets::Preset;
use brdftab::table::{
    BakeOptions, Grid, Interp, Mapping, Param, Symmetry, Table, bake_chunks, symmetry,
};
use brdftab::{Brdf, Error, Result, geometry};
use clap::Args;
use glam::DVec3;
use serde_json::json;

use crate::source;

/// Writes `text` to stdout; a closed pipe (`| head`) is not an error.
fn print_out(text: &str) -> Result<()> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(Error::io("stdout", e)),
        _ => Ok(()),
    }
}

/// Arguments of `brdftab bake`.
#[derive(Args)]
pub struct BakeArgs {
    /// The source: a model spec (inline JSON or .json), a table, a MERL or RGL file.
    pub source: String,
    /// Output table file (`.btdb`).
    #[arg(short, long)]
    pub output: Option<String>,
    /// Codec: f32 (lossless), f16 (fails above ±65504), or log16 (relative error bound at any
    /// magnitude, default 1e-3; `log16:1e-2` sets it). The default is log16: analytic lobes such as
    /// Cook-Torrance reach 1e5 at grazing angles, beyond f16.
    #[arg(long, default_value = "log16")]
    pub codec: String,
    /// log16 relative tolerance (default 1e-3). Named so as not to clash with the symmetry
    /// `--tolerance`.
    #[arg(long)]
    pub codec_tolerance: Option<f64>,
    /// log16 absolute floor (default: 1e-7 of each chunk's largest value).
    #[arg(long)]
    pub floor: Option<f64>,
    /// zstd level (1..=22; default 3 for f32/f16, 6 for log16).
    #[arg(long)]
    pub level: Option<i32>,
    /// Try every filter through zstd per chunk and keep the smallest (slower).
    #[arg(long)]
    pub exhaustive: bool,
    /// Table name inside the file (default: the output file's stem).
    #[arg(long)]
    pub name: Option<String>,
    /// Grid size preset: small, medium (default) or large.
    #[arg(long, default_value = "medium")]
    preset: String,
    /// Parameterization: halfdiff (default) or inout.
    #[arg(long)]
    param: Option<String>,
    /// Full grid sizes θ1xφ1xθ2xφ2 (e.g. 90x360x90x360), or `merl`; overrides --preset.
    #[arg(long)]
    grid: Option<String>,
    /// Wavelengths in nm (comma separated) instead of RGB (model specs only).
    #[arg(long)]
    wavelengths: Option<String>,
    /// Symmetry reduction: auto (detect), none, or a list of isotropic,reciprocal,bilateral.
    #[arg(long, default_value = "auto")]
    symmetry: String,
    /// Bake even if the source breaks a declared symmetry.
    #[arg(long)]
    force: bool,
    /// Relative tolerance of symmetry detection and verification.
    #[arg(long, default_value_t = symmetry::DEFAULT_TOLERANCE)]
    tolerance: f64,
    /// Samples per axis and cell (box prefilter for very sharp lobes).
    #[arg(long, default_value_t = 1)]
    supersample: usize,
}

/// Arguments of `brdftab info`.
#[derive(Args)]
pub struct InfoArgs {
    /// A table file.
    file: String,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

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

fn parse_grid(s: &str) -> Result<[usize; 4]> {
    let v: Vec<usize> = s
        .split(['x', 'X', '×'])
        .map(|t| {
            t.trim()
                .parse::<usize>()
                .map_err(|_| Error::arg("--grid", format!("`{t}` is not a size")))
        })
        .collect::<Result<_>>()?;
    v.try_into()
        .map_err(|_| Error::arg("--grid", "expected four sizes θ1xφ1xθ2xφ2"))
}

/// The codec the bake options ask for.
pub fn codec(a: &BakeArgs) -> Result<Codec> {
    let (name, tol) = match a.codec.split_once(':') {
        Some((n, t)) => (
            n,
            Some(
                t.parse::<f64>()
                    .map_err(|_| Error::arg("--codec", format!("`{t}` is not a tolerance")))?,
            ),
        ),
        None => (a.codec.as_str(), None),
    };
    let quant = brdftab::codec::Quant::parse(name.trim(), a.codec_tolerance.or(tol), a.floor)?;
    let level = a.level.unwrap_or(quant.default_level());
    if !(1..=22).contains(&level) {
        return Err(Error::arg("--level", format!("{level} is outside 1..=22")));
    }
    Ok(Codec {
        quant,
        level,
        exhaustive: a.exhaustive,
        ..Codec::default()
    })
}

/// Where a bake goes.
pub enum Target<'a> {
    /// A single-table file (replaced atomically).
    File(&'a str),
    /// A table in a database.
    Db {
        /// The database file.
        path: &'a str,
        /// The table's name.
        name: &'a str,
        /// Replace an existing table of that name.
        replace: bool,
    },
}

/// `brdftab bake`.
pub fn bake(a: BakeArgs) -> Result<()> {
    let out = a
        .output
        .clone()
        .ok_or_else(|| Error::arg("--output", "an output file is required"))?;
    bake_to(a, Target::File(&out))
}

/// Bakes SOURCE as the options say and streams the chunks into `target`.
pub fn bake_to(a: BakeArgs, target: Target<'_>) -> Result<()> {
    let codec = codec(&a)?;
    let channels = source::channels(a.wavelengths.as_deref())?;
    let src = source::open(&a.source, &channels)?;
    let channels = src.channels().clone();
    let sym = match a.symmetry.trim() {
        "auto" => {
            let d = symmetry::detect(src.as_ref(), a.tolerance);
            let declared = Symmetry::from_flags(src.flags());
            if d != declared {
                eprintln!("note: the source declares {declared}, detected {d}; using {d}");
            }
            d
        }
        s => Symmetry::parse(s)?,
    };
    let param = a.param.as_deref().map(Param::parse).transpose()?;
    let grid = match a.grid.as_deref() {
        Some("merl") => Grid::merl(channels.clone()).with_symmetry(sym)?,
        Some(g) => {
            let p = param.unwrap_or(Param::HalfDiff);
            let m = match p {
                Param::HalfDiff => [Mapping::Sqrt, Mapping::Uniform],
                Param::InOut => [Mapping::Uniform, Mapping::Uniform],
            };
            Grid::with_sizes(p, parse_grid(g)?, m, channels.clone(), sym)?
        }
        None => Preset::parse(&a.preset)?.grid(param, sym, channels.clone())?,
    };
    eprintln!(
        "baking {}\n  grid: {}\n  {} stored values ({} unreduced, {:.1}x reduction)",
        src.describe(),
        grid.summary(),
        grid.stored_values(),
        grid.full_values(),
        grid.full_values() as f64 / grid.stored_values() as f64
    );
    let bar = if std::io::stderr().is_terminal() {
        let b = indicatif::ProgressBar::new(grid.stored_values() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40} {percent:>3}% {human_pos}/{human_len} values, eta {eta}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Some(b)
    } else {
        None
    };
    let progress = |done: u64, _total: u64| {
        if let Some(b) = &bar {
            b.set_position(done);
        }
    };
    let opts = BakeOptions {
        supersample: a.supersample,
        force: a.force,
        tolerance: a.tolerance,
        progress: Some(&progress),
        ..Default::default()
    };
    let src_info = match source::kind(&a.source) {
        source::Kind::Spec => Source::model(&source::spec(&a.source)?),
        source::Kind::Merl | source::Kind::Rgl => Source::measured(&a.source)?,
        source::Kind::Table => Source::Other {
            description: format!("{}: {}", a.source, src.describe()),
        },
    };
    let (out, default_name) = match &target {
        Target::File(p) => (
            *p,
            std::path::Path::new(p)
                .file_stem()
                .map_or("table".into(), |s| s.to_string_lossy().into_owned()),
        ),
        Target::Db { path, name, .. } => (*path, name.to_string()),
    };
    let name = a.name.clone().unwrap_or(default_name);
    let header = TableHeader::for_grid(name, src_info, &grid, codec);
    let mut report = None;
    let mut stream = |w: &mut Writer| -> Result<()> {
        report = Some(bake_chunks(src.as_ref(), &grid, &opts, |i, v| {
            w.chunk_with(v, tables::chunk_layout(&grid, i))
        })?);
        Ok(())
    };
    match target {
        Target::File(p) => {
            let mut w = Writer::create(p)?;
            w.begin_table(header)?;
            stream(&mut w)?;
            w.end_table()?;
            w.finish()?;
        }
        Target::Db { path, replace, .. } => db::put(path, header, replace, stream)?,
    }
    let report = report.ok_or_else(|| Error::arg("bake", "nothing baked"))?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    if let Some(f) = &report.forced {
        eprintln!("warning: forced past a symmetry violation: {f}");
    }
    eprintln!(
        "wrote {} ({} values in {:.2} s, {:.1} M values/s, codec {})",
        out,
        report.values,
        report.seconds,
        report.values as f64 / report.seconds.max(1e-9) / 1e6,
        codec.quant.name()
    );
    Ok(())
}

/// `brdftab info`.
pub fn info(a: InfoArgs) -> Result<()> {
    if matches!(
        source::kind(&a.file),
        source::Kind::Merl | source::Kind::Rgl
    ) {
        return crate::measured::info_source(&a.file);
    }
    if tables::is_store_file(db::split_source(&a.file).0) {
        return crate::db::info(&a.file, a.json);
    }
    let t = Table::open_raw(&a.file)?;
    let g = t.grid();
    let bytes = std::fs::metadata(&a.file)
        .map_err(|e| Error::io(&a.file, e))?
        .len();
    let mut o = String::new();
    let v = json!({
        "file": a.file,
        "format": "raw",
        "description": t.description(),
        "grid": g,
        "parameterization": g.param(),
        "symmetry": g.symmetry().to_string(),
        "channels": g.channels().names(),
        "stored_shape": g.stored_shape(),
        "chunks": g.layout().chunk_count(),
        "stored_values": g.stored_values(),
        "full_values": g.full_values(),
        "bytes": bytes,
    });
    if a.json {
        let _ = writeln!(
            o,
            "{}",
            serde_json::to_string_pretty(&v).unwrap_or_default()
        );
    } else {
        let _ = writeln!(o, "file:          {}", a.file);
        let _ = writeln!(o, "source:        {}", t.description());
        let _ = writeln!(o, "grid:          {}", g.summary());
        let _ = writeln!(o, "symmetry:      {}", g.symmetry());
        let _ = writeln!(o, "channels:      {}", g.channels().names().join(" "));
        let _ = writeln!(o, "chunks:        {}", g.layout().chunk_count());
        let _ = writeln!(o, "stored_values: {}", g.stored_values());
        let _ = writeln!(o, "full_values:   {}", g.full_values());
        let _ = writeln!(o, "bytes:         {bytes}");
    }
    print_out(&o)
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
