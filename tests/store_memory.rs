//! What reading a stored table costs in memory, measured by a counting allocator: listing a
//! database decodes nothing, and a table opened (lazily then looked up, or eagerly) is held
//! once, not two or three times over while it loads.
//!
//! The allocator counts every thread (an eager open decodes on the library's pool), so the
//! tests of this file take turns on one lock.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

use brdftab::codec::{Codec, Quant};
use brdftab::store::{Source, info, tables};
use brdftab::table::{Grid, Mapping, Param, Symmetry, Table};
use brdftab::testkit::TempDir;
use brdftab::{Brdf, Channels};
use glam::DVec3;

/// The system allocator, counting live bytes, their peak and every byte ever allocated.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);
static TOTAL: AtomicUsize = AtomicUsize::new(0);

fn added(n: usize) {
    let live = LIVE.fetch_add(n, Relaxed) + n;
    PEAK.fetch_max(live, Relaxed);
    TOTAL.fetch_add(n, Relaxed);
}

// SAFETY: every call is forwarded to `System` unchanged; only counters are added.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        added(l.size());
        unsafe { System.alloc(l) }
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        added(l.size());
        unsafe { System.alloc_zeroed(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        LIVE.fetch_sub(l.size(), Relaxed);
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
        // Counted as the old block and the new one alive together, as a copy would hold them.
        added(new);
        LIVE.fetch_sub(l.size(), Relaxed);
        unsafe { System.realloc(p, l, new) }
    }
}

#[global_allocator]
static A: Counting = Counting;

static TURN: Mutex<()> = Mutex::new(());

/// The bytes `f` allocated in all (`TOTAL`) and its peak of live bytes above those live before.
fn measure<T>(f: impl FnOnce() -> T) -> (T, usize, usize) {
    let base = LIVE.load(Relaxed);
    PEAK.store(base, Relaxed);
    let total = TOTAL.load(Relaxed);
    let out = f();
    let peak = PEAK.load(Relaxed) - base;
    (out, TOTAL.load(Relaxed) - total, peak)
}

/// A database `db.btdb` holding table `t`: 64×128×91 stored nodes × 3 channels (2.2 M values,
/// 8.9 MB as f32) on a grid the one-array kernel reads exact (sqrt θh, cos θd: the presets'
/// mappings), f32 codec. Returns the path and the number of values.
fn database(d: &TempDir) -> (String, usize) {
    let g = Grid::with_sizes(
        Param::HalfDiff,
        [64, 360, 128, 360],
        [Mapping::Sqrt, Mapping::Cos],
        Channels::Rgb,
        Symmetry {
            isotropic: true,
            reciprocal: true,
            bilateral: true,
        },
    )
    .unwrap();
    assert!(
        brdftab::table::kernel::Kernel::new(&g).is_some_and(|k| k.exact_values()),
        "the grid of this test is one the exact kernel reads"
    );
    let t = Table::from_fn(g, "test", |_, a, out| {
        for (c, o) in out.iter_mut().enumerate() {
            *o = (1.0 + a[0].cos() * 3.0 + a[2].sin() + a[3].cos()) as f32 * (1.0 + c as f32);
        }
    });
    let n = t.values().len();
    let p = d.file("db.btdb");
    let codec = Codec {
        quant: Quant::F32,
        level: 1,
        ..Codec::default()
    };
    let src = Source::Other {
        description: "fn".into(),
    };
    tables::save(&p, "t", src, &t, codec, false).unwrap();
    (p, n)
}

#[test]
fn listing_a_database_decodes_no_chunk() {
    let _turn = TURN.lock().unwrap_or_else(|p| p.into_inner());
    let d = TempDir::new("mem-list");
    let (p, n) = database(&d);
    let (rows, total, _) = measure(|| info::list(&p).unwrap());
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0]["values"].as_u64(), Some(n as u64));
    // The header, index and axes are a few kB; the table is 4n bytes, and sizing its sampler
    // (what the rows held before) decoded all of it and built a sampler of 1 MB.
    assert!(
        total < n,
        "db list allocated {total} bytes for a table of {} bytes",
        4 * n
    );
    // `info` of the table still sizes the sampler.
    let one = info::table_info(&p, "t").unwrap();
    assert!(
        one["sampling_bytes"].as_u64().is_some_and(|b| b > 0),
        "{one}"
    );
}

/// `info` of a whole database (`brdftab info DB`, Python `Database.info()`) reads headers and
/// indexes only, as `db list` does: sizing every table's sampler decoded every chunk and built
/// a sampler per table (session 39: 94 s for 1,000 small tables). The sampler's size is
/// reported for one table (`DB#NAME`) or a file of one table.
#[test]
fn info_of_a_whole_database_decodes_no_chunk() {
    let _turn = TURN.lock().unwrap_or_else(|p| p.into_inner());
    let d = TempDir::new("mem-info");
    let (p, n) = database(&d);
    let t = tables::open_brdf(format!("{p}#t"), true)
        .unwrap()
        .to_table()
        .unwrap();
    let src = Source::Other {
        description: "fn".into(),
    };
    tables::save(&p, "u", src, &t, Codec::default(), false).unwrap();
    let (v, total, _) = measure(|| info::file_info(&p).unwrap());
    let rows = v["tables"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    assert!(
        total < n,
        "info of the database allocated {total} bytes for two tables of {} bytes",
        4 * n
    );
    assert!(
        rows.iter().all(|r| r.get("sampling_bytes").is_none()),
        "{v}"
    );
    // One table of it is sized, as a file holding one table is.
    let one = info::file_info(format!("{p}#u")).unwrap();
    assert!(
        one["tables"][0]["sampling_bytes"]
            .as_u64()
            .is_some_and(|b| b > 0),
        "{one}"
    );
}

#[test]
fn an_opened_table_is_held_once_while_it_loads() {
    let _turn = TURN.lock().unwrap_or_else(|p| p.into_inner());
    let d = TempDir::new("mem-open");
    let (p, n) = database(&d);
    let bytes = 4 * n;
    let source = format!("{p}#t");
    let (wi, wo) = (DVec3::new(0.3, 0.1, 0.9), DVec3::new(-0.2, 0.4, 0.8));
    // The table, one array of it, plus a chunk being decoded (1/64 of it) and small things.
    let bound = bytes + bytes / 8;
    let (mut peaks, mut values) = (Vec::new(), Vec::new());
    for eager in [false, true] {
        let (v, _, peak) = measure(|| {
            let b = tables::open_brdf(&source, eager).unwrap();
            let mut out = [0f32; 3];
            b.eval(wi, wo, &mut out);
            b.health().unwrap();
            (b, out)
        });
        assert!(v.1[0] > 0.0, "{:?}", v.1);
        peaks.push((eager, peak));
        values.push(v.1);
        drop(v);
    }
    // The lazy table's 64 chunks are decoded side by side, a window at a time: the same
    // values as the eager read's.
    assert_eq!(values[0], values[1]);
    // Before: 2.0× the table lazily (the chunks gathered, then copied into the kernel's
    // array), 3× eagerly (the chunks decoded apart, concatenated, then copied).
    assert!(
        peaks.iter().all(|&(_, p)| p < bound),
        "(eager, peak bytes) {peaks:?} for a table of {bytes} bytes (bound {bound})"
    );
}

/// A raw table file (`table::raw`) of `lambert.raw`'s header with the θh axis given `size`,
/// followed by `values` f32 zeros. Found by fuzzing (session 40, `raw` target): the reader
/// built the grid of the header's word before checking it against the values that follow.
fn raw_with_theta_size(size: &str, values: usize) -> Vec<u8> {
    let header = format!(
        r#"{{"format":1,"grid":{{"param":"halfdiff","theta1":{{"size":{size},"mapping":"sqrt","nodes":"centers"}},"phi1":{{"size":1,"mapping":"uniform","nodes":"edges"}},"theta2":{{"size":2,"mapping":"uniform","nodes":"centers"}},"phi2":{{"size":4,"mapping":"uniform","nodes":"edges"}},"channels":"rgb","symmetry":{{"isotropic":true,"reciprocal":true,"bilateral":true}}}},"description":"lambert kd=0.5","values":24}}"#
    );
    let mut b = b"BRDFTAB-RAW\n".to_vec();
    b.extend_from_slice(&(header.len() as u64).to_le_bytes());
    b.extend_from_slice(header.as_bytes());
    b.resize(b.len() + 4 * values, 0);
    b
}

#[test]
fn a_raw_tables_header_cannot_make_its_reader_allocate_beyond_the_file() {
    let _turn = TURN.lock().unwrap_or_else(|p| p.into_inner());
    let d = TempDir::new("mem-raw");
    let p = d.join("t.raw");
    // The honest file (2 × 1 × 2 × 2 stored nodes × 3 channels) opens.
    std::fs::write(&p, raw_with_theta_size("2", 24)).unwrap();
    assert_eq!(Table::open_raw(&p).unwrap().values().len(), 24);
    // θh of 20 million nodes over the same 24 values: the grid's layout alone held a start
    // per node (160 MB), allocated before the values were counted. Opening a file of under
    // 1 kB reads it (1 kB), parses a header of a few hundred bytes and refuses: a few kB in
    // all, far below the 1 MiB allowed here.
    for size in [
        "20000000",
        "1099511627776",
        "4611686018427387904",
        "-1",
        "1e300",
    ] {
        let bytes = raw_with_theta_size(size, 24);
        assert!(bytes.len() < 1024);
        std::fs::write(&p, &bytes).unwrap();
        let (r, _, peak) = measure(|| Table::open_raw(&p));
        assert!(
            peak < 1 << 20,
            "θh size {size}: the reader's peak was {peak} bytes"
        );
        let e = r.expect_err("a grid larger than the file's values");
        assert!(
            matches!(
                e,
                brdftab::Error::Format { .. } | brdftab::Error::Json { .. }
            ),
            "{e}"
        );
    }
}
