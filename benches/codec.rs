//! Codec benchmark: compressed size, ratio vs f32, compress/decompress MB/s (of f32 input) on a
//! Cook-Torrance isotropic halfdiff table at the medium (default) preset (90 × – × 180 × 360
//! full with sqrt θh and uniform-in-cos θd, stored 90 × 1 × 180 × 90 × RGB with reciprocity and
//! bilateral symmetry), side by side with plain zstd
//! on the raw f32 bytes and with OpenEXR ZIP / PIZ (exr crate) on the same values. Then the time
//! to open a 100-table database and do a first lookup.
//!
//! `cargo bench --bench codec` (set `BRDFTAB_BENCH_REPS` to change repetitions, default 5).

#[allow(dead_code)] // only its clock: this bench times by hand, not through criterion
mod common;

use std::io::Cursor;
use std::time::{Duration, Instant};

use brdftab::codec::{self, Codec, Quant};
use brdftab::store::{Source, Store, tables};
use brdftab::table::presets::Preset;
use brdftab::table::{Grid, Mapping, Param, Symmetry, Table, pair_of};
use brdftab::{Channels, ModelSpec};
use rayon::prelude::*;

fn reps() -> usize {
    std::env::var("BRDFTAB_BENCH_REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5)
}

/// Best-of-N wall time.
fn time<T>(mut f: impl FnMut() -> T) -> (Duration, T) {
    let mut best = Duration::MAX;
    let mut out = None;
    for _ in 0..reps() {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed());
        out = Some(r);
    }
    (best, out.expect("at least one rep"))
}

/// The bench table: Cook-Torrance on the grid `brdftab bake` uses by default for an isotropic
/// source (the medium preset: halfdiff, sqrt θh, uniform-in-cos θd, reciprocity + bilateral
/// symmetry), or on a uniform-θd grid of the given full sizes.
fn cook_torrance_table(sizes: Option<[usize; 4]>) -> Table {
    let spec =
        ModelSpec::parse(r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#)
            .unwrap();
    let brdf = spec.build(&Channels::Rgb).unwrap();
    let sym = Symmetry {
        isotropic: true,
        reciprocal: true,
        bilateral: true,
    };
    let g = match sizes {
        None => Preset::Medium
            .grid(Some(Param::HalfDiff), sym, Channels::Rgb)
            .unwrap(),
        Some(sizes) => Grid::with_sizes(
            Param::HalfDiff,
            sizes,
            [Mapping::Sqrt, Mapping::Uniform],
            Channels::Rgb,
            sym,
        )
        .unwrap(),
    };
    Table::from_fn(g, brdf.describe(), |_, a, out| {
        let (wi, wo) = pair_of(Param::HalfDiff, a);
        brdf.eval(wi, wo, out);
    })
}

/// CPU time of the calling thread ([`common::thread_cpu_ns`]), for throughput figures that do
/// not depend on how busy the shared machine is. (Not `/proc/thread-self/schedstat`: the
/// running thread's runtime there advances only at scheduler ticks, so a decompression of a
/// few milliseconds read as 1, 2 or 3 ticks and its MB/s landed on a few values.)
fn thread_cpu() -> Option<Duration> {
    Some(Duration::from_nanos(common::thread_cpu_ns()))
}

/// Best-of-N single-threaded CPU time of `f`.
fn cpu_time<T>(mut f: impl FnMut() -> T) -> Duration {
    let mut best = Duration::MAX;
    for _ in 0..reps() {
        let (Some(a), _, Some(b)) = (thread_cpu(), f(), thread_cpu()) else {
            return Duration::ZERO;
        };
        best = best.min(b - a);
    }
    best
}

fn row(
    name: &str,
    raw: usize,
    bytes: usize,
    c: Duration,
    d: Duration,
    cpu: Option<(Duration, Duration)>,
) {
    let mb = raw as f64 / 1e6;
    let per_core = cpu.map_or(String::new(), |(c1, d1)| {
        format!(
            "   | 1 core CPU: {:>5.0} / {:>5.0} MB/s",
            mb / c1.as_secs_f64(),
            mb / d1.as_secs_f64()
        )
    });
    println!(
        "{name:<24} {bytes:>9} B {:>6.1}x {:>6.0} MB/s {:>6.0} MB/s{per_core}",
        raw as f64 / bytes as f64,
        mb / c.as_secs_f64(),
        mb / d.as_secs_f64()
    );
}

fn exr_bytes(v: &[f32], w: usize, h: usize, compression: exr::prelude::Compression) -> Vec<u8> {
    use exr::prelude::*;
    let ch = |k: usize| {
        AnyChannel::new(
            ["R", "G", "B"][k],
            FlatSamples::F32(v.iter().skip(k).step_by(3).copied().collect()),
        )
    };
    let enc = Encoding {
        compression,
        ..Encoding::FAST_LOSSLESS
    };
    let layer = Layer::new(
        (w, h),
        LayerAttributes::named("t"),
        enc,
        AnyChannels::sort(vec![ch(0), ch(1), ch(2)].into()),
    );
    let mut out = Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut out)
        .unwrap();
    out.into_inner()
}

fn exr_read(b: &[u8]) -> usize {
    use exr::prelude::*;
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(Cursor::new(b))
        .unwrap();
    img.layer_data.len()
}

/// Sizes, ratios and speeds of every codec on one table.
fn compare(label: &str, sizes: Option<[usize; 4]>) {
    let t0 = Instant::now();
    let table = cook_torrance_table(sizes);
    let grid = table.grid().clone();
    let l = grid.layout();
    let raw = table.values().len() * 4;
    let max = table.values().iter().fold(0.0f32, |m, v| m.max(v.abs()));
    println!(
        "\nCook-Torrance (m 0.3, Au) halfdiff, {label}: stored {:?} x {} ch = {} values ({:.1} MB f32), max {:.4e}, {} chunks; baked in {:.2?}; {} threads",
        l.shape,
        l.channels,
        table.values().len(),
        raw as f64 / 1e6,
        max,
        l.chunk_count(),
        t0.elapsed(),
        rayon::current_num_threads()
    );
    println!("wall time on all threads of the (shared) machine, then single-thread CPU time");
    println!(
        "{:<24} {:>11} {:>7} {:>11} {:>11}",
        "codec", "size", "ratio", "compress", "decompress"
    );

    let chunks: Vec<(&[f32], codec::Layout)> = (0..l.chunk_count())
        .map(|a| (table.chunk(a), tables::chunk_layout(&grid, a)))
        .collect();

    // Plain zstd on the raw f32 bytes (per chunk, in parallel, same as ours).
    let (c, z): (_, Vec<Vec<u8>>) = time(|| {
        chunks
            .par_iter()
            .map(|(v, _)| zstd::bulk::compress(bytemuck(v), 3).unwrap())
            .collect()
    });
    let (d, _) = time(|| {
        z.par_iter()
            .zip(&chunks)
            .map(|(b, (v, _))| zstd::bulk::decompress(b, v.len() * 4).unwrap().len())
            .sum::<usize>()
    });
    let c1 = cpu_time(|| {
        chunks
            .iter()
            .map(|(v, _)| zstd::bulk::compress(bytemuck(v), 3).unwrap().len())
            .sum::<usize>()
    });
    let d1 = cpu_time(|| {
        z.iter()
            .zip(&chunks)
            .map(|(b, (v, _))| zstd::bulk::decompress(b, v.len() * 4).unwrap().len())
            .sum::<usize>()
    });
    row(
        "zstd-3 raw f32",
        raw,
        z.iter().map(Vec::len).sum(),
        c,
        d,
        Some((c1, d1)),
    );

    for (name, quant, level) in [
        ("f32 + filters, zstd-3", Quant::F32, 3),
        ("f16 + filters, zstd-1", Quant::F16, 1),
        ("f16 + filters, zstd-3", Quant::F16, 3),
        ("f16 + filters, zstd-9", Quant::F16, 9),
        (
            "log16 1e-3, zstd-3",
            Quant::Log16 {
                tolerance: 1e-3,
                floor: None,
            },
            3,
        ),
        (
            "log16 1e-3, zstd-6",
            Quant::Log16 {
                tolerance: 1e-3,
                floor: None,
            },
            6,
        ),
        (
            "log16 1e-3, zstd-9",
            Quant::Log16 {
                tolerance: 1e-3,
                floor: None,
            },
            9,
        ),
        (
            "log16 1e-2, zstd-3",
            Quant::Log16 {
                tolerance: 1e-2,
                floor: None,
            },
            3,
        ),
    ] {
        if quant == Quant::F16 && max > 65504.0 {
            println!("{name:<24} n/a: values up to {max:.4e} exceed the f16 range (±65504)");
            continue;
        }
        let codec = Codec {
            quant,
            level,
            ..Codec::default()
        };
        let (c, enc): (_, Vec<Vec<u8>>) = time(|| {
            chunks
                .par_iter()
                .map(|(v, lay)| codec::encode(v, *lay, &codec).unwrap())
                .collect()
        });
        let (d, _) = time(|| {
            enc.par_iter()
                .zip(&chunks)
                .map(|(b, (v, _))| codec::decode(b, v.len()).unwrap().len())
                .sum::<usize>()
        });
        let c1 = cpu_time(|| {
            chunks
                .iter()
                .map(|(v, lay)| codec::encode(v, *lay, &codec).unwrap().len())
                .sum::<usize>()
        });
        let d1 = cpu_time(|| {
            enc.iter()
                .zip(&chunks)
                .map(|(b, (v, _))| codec::decode(b, v.len()).unwrap().len())
                .sum::<usize>()
        });
        row(
            name,
            raw,
            enc.iter().map(Vec::len).sum(),
            c,
            d,
            Some((c1, d1)),
        );
        let mut filters = std::collections::BTreeMap::new();
        let esc: usize = enc
            .iter()
            .map(|b| codec::chunk_info(b).unwrap().escapes)
            .sum();
        if esc > 0 {
            println!("{:<24}   exactly stored (escapes): {esc}", "");
        }
        for b in &enc {
            *filters
                .entry(format!("{:?}", codec::chunk_info(b).unwrap().filter))
                .or_insert(0) += 1;
        }
        println!("{:<24}   filters chosen: {filters:?}", "");
    }

    // OpenEXR: the table as an image of width = stored φd × rows = θh·θd, RGB channels.
    let (w, h) = (l.shape[3], table.values().len() / 3 / l.shape[3]);
    for (name, comp) in [
        ("exr ZIP (f32)", exr::prelude::Compression::ZIP16),
        ("exr PIZ (f32)", exr::prelude::Compression::PIZ),
    ] {
        let (c, b) = time(|| exr_bytes(table.values(), w, h, comp));
        let (d, _) = time(|| exr_read(&b));
        row(name, raw, b.len(), c, d, None);
    }
}

fn main() {
    compare("medium (default) preset", None);
    compare(
        "medium sizes with uniform θd (90 x 360 x 90 x 360; θd nodes end 0.5° from grazing, where f16 holds Cook-Torrance)",
        Some([90, 360, 90, 360]),
    );

    // Open a 100-table database and do a first lookup.
    let dir = brdftab::testkit::TempDir::new("bench-codec");
    let p = dir.join("db100.btdb");
    let small = cook_torrance_table(Some([32, 64, 32, 64]));
    let mut wtr = brdftab::store::Writer::create(&p).unwrap();
    let codec = Codec {
        quant: Quant::F16,
        level: 3,
        ..Codec::default()
    };
    for k in 0..100 {
        let hd = brdftab::store::TableHeader::for_grid(
            format!("t{k:03}"),
            Source::Other {
                description: "bench".into(),
            },
            small.grid(),
            codec,
        );
        wtr.begin_table(hd).unwrap();
        tables::write_table_chunks(&mut wtr, &small).unwrap();
        wtr.end_table().unwrap();
    }
    wtr.finish().unwrap();
    let size = std::fs::metadata(&p).unwrap().len();
    let (t, v) = time(|| {
        let s = Store::open(&p).unwrap();
        let t = s.table("t057").unwrap();
        let g = t.grid().unwrap();
        let off = g.layout().offset([10, 0, 5, 7]).unwrap();
        let (ci, o) = t.locate(off as u64).unwrap();
        t.chunk(ci).unwrap()[o]
    });
    println!(
        "open 100-table db ({:.1} MB) + header/index/grid + first value decode: {:.2?} (value {v})",
        size as f64 / 1e6,
        t
    );
    let src = format!("{}#t057", p.display());
    let (t, f) = time(|| {
        let b = tables::open_brdf(&src, false).unwrap();
        let mut f = [0.0f32; 3];
        brdftab::Brdf::eval(
            &b,
            glam::DVec3::new(0.3, 0.1, 0.9),
            glam::DVec3::new(-0.2, 0.3, 0.9),
            &mut f,
        );
        f
    });
    println!("open 100-table db + lazy TabulatedBrdf + first eval: {t:.2?} (f = {f:?})");
}

fn bytemuck(v: &[f32]) -> &[u8] {
    // SAFETY: f32 has no padding and any byte pattern is a valid u8.
    unsafe { std::slice::from_raw_parts(v.as_ptr().cast::<u8>(), v.len() * 4) }
}
