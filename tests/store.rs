//! The brdftab file format and database, as a specification: round trips, database operations,
//! and refusal of every kind of bad input with a typed error (never a panic or a huge allocation).

use std::path::{Path, PathBuf};

use brdftab::codec::{Codec, Layout, Quant};
use brdftab::store::format::{self, Superblock, Toc};
use brdftab::store::{Source, Store, StoreOptions, TableHeader, Writer, db, export};
use brdftab::testkit::TempDir;
use brdftab::{Channels, Error};

/// A smooth specular-lobe-like table of shape [a, b, c, 3], chunks = slabs of axis 0.
fn lobe(shape: [usize; 3], seed: f32) -> Vec<f32> {
    let [a, b, c] = shape;
    let mut v = Vec::with_capacity(a * b * c * 3);
    for i in 0..a {
        for j in 0..b {
            for k in 0..c {
                let x = i as f32 / a as f32;
                let y = j as f32 / b as f32;
                let z = k as f32 / c as f32;
                let s = (-(x * x) * 40.0 - (y - 0.3).powi(2) * 5.0).exp() * 50.0
                    + 0.05 * (z * 3.0 + seed).cos().abs();
                v.extend_from_slice(&[s * 0.9, s, s * 1.1]);
            }
        }
    }
    v
}

fn header(name: &str, shape: [usize; 3], quant: Quant) -> TableHeader {
    TableHeader::new(
        name,
        Source::Other {
            description: "synthetic lobe".into(),
        },
        vec![shape[0] as u64, shape[1] as u64, shape[2] as u64, 3],
        Channels::Rgb,
        Codec {
            quant,
            level: 3,
            ..Codec::default()
        },
    )
}

const SHAPE: [usize; 3] = [6, 10, 20];

fn add(path: &Path, name: &str, quant: Quant, seed: f32) {
    let data = lobe(SHAPE, seed);
    let h = header(name, SHAPE, quant);
    let n = data.len() / SHAPE[0];
    db::put(path, h, true, |w| {
        for c in data.chunks(n) {
            w.chunk(c)?;
        }
        Ok(())
    })
    .unwrap();
}

#[test]
fn every_codec_round_trips_through_a_file() {
    let d = TempDir::new("store-roundtrip");
    let data = lobe(SHAPE, 0.0);
    for (k, q) in [
        Quant::F32,
        Quant::F16,
        Quant::Log16 {
            tolerance: 1e-3,
            floor: None,
        },
    ]
    .into_iter()
    .enumerate()
    {
        let p = d.join(format!("t{k}.btdb"));
        let n = data.len() / SHAPE[0];
        let chunks: Vec<(&[f32], Layout)> = data
            .chunks(n)
            .map(|c| (c, Layout::new(3, 20, 10)))
            .collect();
        db::write_table(&p, header("lobe", SHAPE, q), &chunks).unwrap();
        let s = Store::open(&p).unwrap();
        let t = s.single().unwrap();
        assert_eq!(t.chunk_count(), SHAPE[0]);
        let back = t.read_all().unwrap();
        for (a, b) in data.iter().zip(&back) {
            match q {
                Quant::F32 => assert_eq!(a.to_bits(), b.to_bits()),
                Quant::F16 => assert!((a - b).abs() <= a.abs() * 1e-3 + 1e-7),
                Quant::Log16 { tolerance, .. } => {
                    assert!(((a - b).abs() as f64) <= tolerance * *a as f64 + 1e-20)
                }
            }
        }
        // Lazy chunks equal the eager read and are cached.
        let c2 = t.chunk(2).unwrap();
        assert_eq!(&c2[..], &back[2 * n..3 * n]);
        assert_eq!(t.locate((2 * n + 5) as u64).unwrap(), (2, 5));
        assert_eq!(s.verify().unwrap(), SHAPE[0]);
        assert!(t.compressed_bytes() < (data.len() * 4) as u64);
    }
}

#[test]
fn database_rename_keeps_the_table_and_its_place() {
    let d = TempDir::new("store-db-rename");
    let p = d.join("db.btdb");
    add(&p, "a", Quant::F16, 0.0);
    add(&p, "b", Quant::F32, 1.0);
    add(&p, "c", Quant::F16, 2.0);
    let before = Store::open(&p).unwrap();
    let names = || {
        let s = Store::open(&p).unwrap();
        s.tables()
            .iter()
            .map(|e| e.name.clone())
            .collect::<Vec<_>>()
    };
    db::rename(&p, "b", "gold").unwrap();
    assert_eq!(names(), ["a", "gold", "c"]);
    let s = Store::open(&p).unwrap();
    // The values and every other header field are the old table's, bit for bit.
    let (old_t, new_t) = (before.table("b").unwrap(), s.table("gold").unwrap());
    assert_eq!(new_t.read_all().unwrap(), old_t.read_all().unwrap());
    let mut h = old_t.header().clone();
    h.name = "gold".into();
    assert_eq!(new_t.header(), &h);
    assert_eq!(db::verify(&p).unwrap(), 3 * SHAPE[0]);
    assert!(matches!(s.table("b"), Err(Error::NotFound(_))));
    let file = p.to_str().unwrap();
    let bytes = std::fs::read(&p).unwrap();

    // A taken NEW (`old` itself too), a missing OLD or database, a NEW the name rule refuses:
    // each an error naming the database or the argument, the file untouched.
    for (old, new) in [("a", "c"), ("a", "a")] {
        match db::rename(&p, old, new) {
            Err(Error::Duplicate { container, name }) => {
                assert_eq!((container.as_str(), name.as_str()), (file, new))
            }
            r => panic!("{old} -> {new}: {r:?}"),
        }
    }
    match db::rename(&p, "b", "x") {
        Err(e @ Error::NotFound(_)) => {
            let e = e.to_string();
            assert!(
                e.contains(file) && e.contains("`b`") && e.contains("gold"),
                "{e}"
            )
        }
        r => panic!("{r:?}"),
    }
    for bad in ["", "x#y", "x/y", "x\ny"] {
        match db::rename(&p, "a", bad) {
            Err(Error::InvalidArgument { name, .. }) => assert_eq!(name, "name", "{bad:?}"),
            r => panic!("{bad:?}: {r:?}"),
        }
    }
    assert_eq!(std::fs::read(&p).unwrap(), bytes);
    let missing = d.join("none.btdb");
    let e = db::rename(&missing, "a", "b").unwrap_err();
    assert!(matches!(e, Error::NotFound(_)), "{e}");
    assert!(e.to_string().contains("none.btdb"), "{e}");
    assert!(!missing.exists());
}

#[test]
fn database_add_replace_remove_list_verify() {
    let d = TempDir::new("store-db");
    let p = d.join("db.btdb");
    add(&p, "a", Quant::F16, 0.0);
    add(&p, "b", Quant::F32, 1.0);
    add(&p, "c", Quant::F16, 2.0);
    let names = |p: &Path| {
        db::list(p)
            .unwrap()
            .into_iter()
            .map(|(e, _)| e.name)
            .collect::<Vec<_>>()
    };
    assert_eq!(names(&p), ["a", "b", "c"]);

    // A reader opened now keeps seeing this version.
    let old = Store::open(&p).unwrap();
    let old_b = old.table("b").unwrap().read_all().unwrap();

    // Replace keeps the position; the other tables are copied byte for byte.
    add(&p, "b", Quant::F16, 5.0);
    assert_eq!(names(&p), ["a", "b", "c"]);
    let s = Store::open(&p).unwrap();
    assert_eq!(s.table("b").unwrap().header().codec.quant, Quant::F16);
    assert_eq!(
        s.table("a").unwrap().read_all().unwrap(),
        Store::open(&p)
            .unwrap()
            .table("a")
            .unwrap()
            .read_all()
            .unwrap()
    );
    assert_eq!(old.table("b").unwrap().read_all().unwrap(), old_b);

    // Adding an existing name without replace is refused.
    let e = db::put(&p, header("a", SHAPE, Quant::F16), false, |_| Ok(())).unwrap_err();
    assert!(e.to_string().contains("already holds"), "{e}");

    db::remove(&p, "a").unwrap();
    assert_eq!(names(&p), ["b", "c"]);
    assert!(matches!(db::remove(&p, "zzz"), Err(Error::NotFound(_))));
    assert!(matches!(
        Store::open(&p).unwrap().table("a"),
        Err(Error::NotFound(_))
    ));
    assert_eq!(db::verify(&p).unwrap(), 2 * SHAPE[0]);

    // A failed write leaves the database as it was and no temporary file behind.
    let e = db::put(&p, header("d", SHAPE, Quant::F16), false, |w| {
        w.chunk(&[f32::NAN; 600])
    })
    .unwrap_err();
    assert!(e.to_string().contains("index 0"), "{e}");
    assert_eq!(names(&p), ["b", "c"]);
    let stray: Vec<_> = std::fs::read_dir(d.path())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp."))
        .collect();
    assert!(stray.is_empty(), "{stray:?}");
}

/// A database that readers hold open — stores, a table of each not yet read, a lazily decoded
/// `TabulatedBrdf` (Python's `brdftab.open("x.btdb#b")` kept alive) — is still written by every
/// change through another handle, each writer renaming a new file over it: every reader keeps
/// reading the version it opened, chunks it had not touched included, and an open after the
/// changes sees the new version. On Windows a store holds nothing of the file
/// (`Store::open` reads it into memory there): a memory map kept the writers from replacing
/// the file, each failing with "Access denied" (session 43, under Wine).
#[test]
fn a_database_held_open_by_readers_is_still_written_and_each_reader_keeps_its_version() {
    use brdftab::Brdf;
    use brdftab::store::tables;
    use brdftab::table::{Grid, Mapping, Param, Symmetry, Table, TabulatedBrdf};
    use glam::DVec3;
    let d = TempDir::new("store-held-open");
    let p = d.join("lib.btdb");
    let grid = Grid::with_sizes(
        Param::HalfDiff,
        [8, 1, 8, 16],
        [Mapping::Sqrt, Mapping::Uniform],
        Channels::Rgb,
        Symmetry {
            isotropic: true,
            reciprocal: true,
            bilateral: true,
        },
    )
    .unwrap();
    let table = |k: f64| {
        Table::from_fn(grid.clone(), "held", move |_, a, out| {
            for (c, o) in out.iter_mut().enumerate() {
                *o = (k + a[0].cos() + 0.5 * a[2].sin()) as f32 * (1.0 + c as f32);
            }
        })
    };
    let codec = Codec {
        quant: Quant::F32, // lossless: a stored table evaluates as the table itself
        level: 1,
        ..Codec::default()
    };
    let save = |name: &str, k: f64| {
        let source = Source::Other {
            description: "held".into(),
        };
        tables::save(&p, name, source, &table(k), codec, true).unwrap()
    };
    save("a", 1.0);
    save("b", 2.0);
    save("c", 3.0);
    let source = format!("{}#b", p.display());
    let (wi, wo) = (DVec3::new(0.3, 0.1, 0.9), DVec3::new(-0.2, 0.4, 0.8));
    let eval = |f: &dyn Brdf| {
        let mut v = [0f32; 3];
        f.eval(wi, wo, &mut v);
        v
    };
    let names = |s: &Store| {
        s.tables()
            .iter()
            .map(|e| e.name.clone())
            .collect::<Vec<_>>()
    };
    let old_b = eval(&TabulatedBrdf::from_table(table(2.0)));
    let old_values = Store::open(&p).unwrap().table("b").unwrap().read_all();
    let old_values = old_values.unwrap();

    // The readers, none of which has read a chunk yet. A map is kept only where it does not
    // keep the file from being replaced.
    let held_brdf = tables::open_brdf(&source, false).unwrap();
    assert_eq!(held_brdf.loaded_chunks(), 0);
    let opts = StoreOptions::default();
    #[cfg(not(windows))]
    let mapped = Some(("mapped", Store::open_mapped(&p, opts).unwrap()));
    #[cfg(windows)]
    let mapped = None;
    let stores: Vec<_> = [
        ("open", Store::open(&p).unwrap()),
        ("in memory", Store::open_in_memory(&p, opts).unwrap()),
    ]
    .into_iter()
    .chain(mapped)
    .collect();
    let held: Vec<_> = stores.iter().map(|(_, s)| s.table("b").unwrap()).collect();

    // Another handle replaces, adds, removes and renames.
    save("b", 20.0);
    save("d", 4.0);
    db::remove(&p, "a").unwrap();
    db::rename(&p, "c", "c2").unwrap();

    // Every reader reads the version it opened.
    assert_eq!(eval(&held_brdf), old_b);
    for ((how, s), t) in stores.iter().zip(&held) {
        assert_eq!(names(s), ["a", "b", "c"], "{how}");
        assert_eq!(t.read_all().unwrap(), old_values, "{how}");
        assert_eq!(s.verify().unwrap(), 3 * 8, "{how}");
    }
    // A new open sees the new version.
    let now = Store::open(&p).unwrap();
    assert_eq!(names(&now), ["b", "c2", "d"]);
    let new_b = eval(&tables::open_brdf(&source, false).unwrap());
    assert_eq!(new_b, eval(&TabulatedBrdf::from_table(table(20.0))));
    assert_ne!(new_b, old_b);
    assert_eq!(
        now.table("c2").unwrap().read_all().unwrap(),
        stores[0].1.table("c").unwrap().read_all().unwrap()
    );
}

/// `Store::open_in_memory` keeps nothing of the file open once it returns (what lets writers
/// replace a database on Windows, where `Store::open` is it); a map keeps the file mapped.
#[cfg(target_os = "linux")]
#[test]
fn a_store_read_into_memory_holds_no_descriptor_or_map_of_its_file() {
    let d = TempDir::new("store-in-memory");
    let p = d.join("held.btdb");
    add(&p, "a", Quant::F16, 0.0);
    let real = std::fs::canonicalize(&p).unwrap();
    let fds = || {
        std::fs::read_dir("/proc/self/fd")
            .unwrap()
            .filter_map(|e| std::fs::read_link(e.ok()?.path()).ok())
            .filter(|l| *l == real)
            .count()
    };
    let maps = || {
        let maps = std::fs::read_to_string("/proc/self/maps").unwrap();
        maps.lines()
            .filter(|l| l.ends_with(real.to_str().unwrap()))
            .count()
    };
    let s = Store::open_in_memory(&p, StoreOptions::default()).unwrap();
    let t = s.table("a").unwrap();
    assert_eq!((fds(), maps()), (0, 0));
    let m = Store::open_mapped(&p, StoreOptions::default()).unwrap();
    assert_eq!(maps(), 1, "the check sees a map where there is one");
    assert_eq!(
        t.read_all().unwrap(),
        m.table("a").unwrap().read_all().unwrap()
    );
    assert_eq!(s.file_len(), m.file_len());
}

#[test]
fn cache_respects_its_memory_bound_and_eager_decodes_everything() {
    let d = TempDir::new("store-cache");
    let p = d.join("t.btdb");
    add(&p, "a", Quant::F16, 0.0);
    let chunk_bytes = 10 * 20 * 3 * 4;
    let s = Store::open_with(
        &p,
        StoreOptions {
            cache_bytes: 2 * chunk_bytes,
            eager: false,
        },
    )
    .unwrap();
    let t = s.table("a").unwrap();
    for i in 0..t.chunk_count() {
        t.chunk(i).unwrap();
    }
    assert!(format!("{s:?}").contains("tables"));
    let s = Store::open_with(
        &p,
        StoreOptions {
            cache_bytes: 1 << 30,
            eager: true,
        },
    )
    .unwrap();
    s.table("a").unwrap();
}

#[test]
fn nan_in_data_names_the_chunk_and_index() {
    let d = TempDir::new("store-nan");
    let mut w = Writer::create(d.join("x.btdb")).unwrap();
    w.begin_table(header("x", SHAPE, Quant::F32)).unwrap();
    let mut v = lobe(SHAPE, 0.0)[..600].to_vec();
    v[17] = f32::NAN;
    let e = w.chunk(&v).unwrap_err().to_string();
    assert!(
        e.contains("chunk 0") && e.contains("index 17") && e.contains("NaN"),
        "{e}"
    );
}

#[test]
fn npy_and_exr_exports() {
    let d = TempDir::new("store-export");
    let p = d.join("t.btdb");
    add(&p, "a", Quant::F32, 0.0);
    let s = Store::open(&p).unwrap();
    let t = s.table("a").unwrap();
    let out = d.join("a.npy");
    export::npy(&t, &out, None).unwrap();
    let b = std::fs::read(&out).unwrap();
    assert_eq!(&b[..8], b"\x93NUMPY\x01\x00");
    let hl = u16::from_le_bytes([b[8], b[9]]) as usize;
    assert_eq!((10 + hl) % 64, 0);
    let hdr = std::str::from_utf8(&b[10..10 + hl]).unwrap();
    assert!(
        hdr.contains("'shape': (6, 10, 20, 3)") && hdr.contains("'<f4'"),
        "{hdr}"
    );
    let data = lobe(SHAPE, 0.0);
    assert_eq!(b.len(), 10 + hl + data.len() * 4);
    let v: Vec<f32> = b[10 + hl..]
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(v, data);

    let sl = export::Slice::parse("2,0:0,4", 3).unwrap();
    let (w, h, px) = export::slice(&t, &sl, None).unwrap();
    assert_eq!((w, h), (20, 6));
    // pixel (x=7, y=3) = node [3, 4, 7]
    let o = ((3 * 10 + 4) * 20 + 7) * 3;
    assert_eq!(&px[(3 * 20 + 7) * 3..][..3], &data[o..o + 3]);
    export::exr(&t, &sl, None, d.join("a.exr"), true).unwrap();
    export::exr(&t, &sl, None, d.join("a32.exr"), false).unwrap();
    assert!(std::fs::metadata(d.join("a.exr")).unwrap().len() > 100);
    assert!(export::Slice::parse("1,1", 3).is_err());
    assert!(export::slice(&t, &export::Slice::parse("0,1:0,0,99", 3).unwrap(), None).is_err());
}

/// `export --half` wrote values below f16's smallest subnormal as 0 without a word (it refuses
/// those above 65504): the export now counts them. And the EXR was written in place (`to_file`
/// truncated the old file first), so a kill mid-write left a truncated file and another hard
/// link saw the new bytes: now a temporary file is renamed over it, as every other output.
#[test]
fn exr_half_counts_values_flushed_to_zero_and_replaces_the_file_atomically() {
    let d = TempDir::new("store-exr-half");
    let p = d.join("t.btdb");
    let mut data = lobe(SHAPE, 0.0);
    let [_, b, c] = SHAPE;
    for k in 0..c {
        // Row y = 0 of the slice (nodes [0, 4, k]): 1e-9 < 2^-25, written as 0 in f16.
        data[((4 * c) + k) * 3..][..3].fill(1e-9);
        // Row y = 1 (nodes [1, 4, k]): 1e-7 is an f16 subnormal, not 0.
        data[((b + 4) * c + k) * 3..][..3].fill(1e-7);
    }
    let h = header("a", SHAPE, Quant::F32);
    let n = data.len() / SHAPE[0];
    db::put(&p, h, true, |w| {
        for ch in data.chunks(n) {
            w.chunk(ch)?;
        }
        Ok(())
    })
    .unwrap();
    let s = Store::open(&p).unwrap();
    let t = s.table("a").unwrap();
    let sl = export::Slice::parse("2,0:0,4", 3).unwrap();
    let (out, keep) = (d.join("a.exr"), d.join("keep.exr"));
    std::fs::write(&out, b"old").unwrap();
    std::fs::hard_link(&out, &keep).unwrap();
    assert_eq!(export::exr(&t, &sl, None, &out, true).unwrap(), 20 * 3);
    assert_eq!(std::fs::read(&keep).unwrap(), b"old");
    assert!(std::fs::metadata(&out).unwrap().len() > 100);
    assert_eq!(export::exr(&t, &sl, None, &out, false).unwrap(), 0);
    // No temporary file is left beside it.
    let names: Vec<_> = (std::fs::read_dir(d.path()).unwrap())
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(!names.iter().any(|n| n.contains(".tmp.")), "{names:?}");
}

// ---------------------------------------------------------------------------------------------
// Bad input.

fn sample_file(d: &Path) -> (PathBuf, Vec<u8>) {
    let p = d.join("sample.btdb");
    add(&p, "a", Quant::F16, 0.0);
    add(
        &p,
        "b",
        Quant::Log16 {
            tolerance: 1e-3,
            floor: None,
        },
        1.0,
    );
    let b = std::fs::read(&p).unwrap();
    (p, b)
}

/// Opens bytes as a file and verifies everything; returns the error (panics if it succeeds).
fn open_err(d: &Path, bytes: &[u8]) -> Error {
    let _ = d;
    match Store::from_bytes("bad.btdb", bytes.to_vec(), StoreOptions::default())
        .and_then(|s| s.verify())
    {
        Ok(_) => panic!("damaged file accepted"),
        Err(e) => e,
    }
}

/// Replaces the TOC (and optionally appends `extra` bytes before it), resealing the superblock,
/// so a test can plant a specific lie past all checksums.
fn reseal(bytes: &[u8], extra: &[u8], edit: impl FnOnce(&mut Toc, u64)) -> Vec<u8> {
    let sb = Superblock::parse("x", bytes).unwrap();
    let mut toc: Toc =
        serde_json::from_slice(&bytes[sb.toc.offset as usize..][..sb.toc.len as usize]).unwrap();
    let mut out = bytes[..sb.toc.offset as usize].to_vec();
    let extra_at = out.len() as u64;
    out.extend_from_slice(extra);
    edit(&mut toc, extra_at);
    let tj = serde_json::to_vec(&toc).unwrap();
    let toc_block = format::Block {
        offset: out.len() as u64,
        len: tj.len() as u64,
        xxh3: format::xxh3(&tj),
    };
    out.extend_from_slice(&tj);
    let sb = Superblock {
        version: sb.version,
        toc: toc_block,
        file_len: out.len() as u64,
    };
    out[..64].copy_from_slice(&sb.to_bytes());
    out
}

#[test]
fn truncation_anywhere_is_a_typed_error() {
    let d = TempDir::new("store-trunc");
    let (_, b) = sample_file(d.path());
    // Through real files for a few lengths (the path goes through the mmap), in memory for all.
    for len in [0, 5, 63, 64, 100, b.len() - 1] {
        let p = d.join("trunc.btdb");
        std::fs::write(&p, &b[..len]).unwrap();
        let e = Store::open(&p).and_then(|s| s.verify()).unwrap_err();
        assert!(
            matches!(e, Error::Format { .. } | Error::Checksum { .. }),
            "{len}: {e}"
        );
    }
    for len in 0..b.len() {
        let e = open_err(d.path(), &b[..len]);
        assert!(
            matches!(e, Error::Format { .. } | Error::Checksum { .. }),
            "{len}: {e}"
        );
    }
}

#[test]
fn wrong_magic_and_newer_version() {
    let d = TempDir::new("store-magic");
    let (_, b) = sample_file(d.path());
    let mut m = b.clone();
    m[1] = b'X';
    assert!(open_err(d.path(), &m).to_string().contains("wrong magic"));
    let mut v = b.clone();
    let mut sb = Superblock::parse("x", &b).unwrap();
    sb.version = format::VERSION + 1;
    v[..64].copy_from_slice(&sb.to_bytes());
    let e = open_err(d.path(), &v).to_string();
    assert!(e.contains("newer"), "{e}");
}

#[test]
fn every_flipped_byte_is_caught() {
    let d = TempDir::new("store-flip");
    let (_, b) = sample_file(d.path());
    for i in 0..b.len() {
        let mut m = b.clone();
        m[i] ^= 0x10;
        let e = open_err(d.path(), &m);
        assert!(
            matches!(
                e,
                Error::Format { .. } | Error::Checksum { .. } | Error::Json { .. }
            ),
            "byte {i}: {e}"
        );
    }
}

#[test]
fn overflowing_chunk_ranges_are_refused() {
    let d = TempDir::new("store-overflow");
    let (_, b) = sample_file(d.path());
    let sb = Superblock::parse("x", &b).unwrap();
    let toc: Toc =
        serde_json::from_slice(&b[sb.toc.offset as usize..][..sb.toc.len as usize]).unwrap();
    let idx = toc.tables[0].index;
    for (field, val) in [
        (0usize, u64::MAX - 3),
        (1, u64::MAX),
        (1, 1 << 40),
        (2, u64::MAX),
        (2, 1 << 40),
    ] {
        let mut ib = b[idx.offset as usize..][..idx.len as usize].to_vec();
        ib[8 * field..8 * field + 8].copy_from_slice(&val.to_le_bytes());
        let m = reseal(&b, &ib, |t, at| {
            t.tables[0].index = format::Block {
                offset: at,
                len: ib.len() as u64,
                xxh3: format::xxh3(&ib),
            };
        });
        let e = open_err(d.path(), &m);
        assert!(
            matches!(e, Error::Format { .. }),
            "field {field} = {val}: {e}"
        );
    }
}

#[test]
fn absurd_dimensions_and_invalid_json_are_refused_before_allocating() {
    let d = TempDir::new("store-bomb");
    let (_, b) = sample_file(d.path());
    let mut h = header("a", SHAPE, Quant::F16);
    for (shape, values) in [
        (vec![1u64 << 20, 1 << 20, 1 << 20, 3], 1u64 << 62),
        (vec![u64::MAX, u64::MAX], 1 << 30),
        (vec![], 0),
        (vec![6, 10, 20, 3], 1 << 33), // more values than the shape holds
    ] {
        h.shape = shape;
        h.values = values;
        let j = serde_json::to_vec(&h).unwrap();
        let m = reseal(&b, &j, |t, at| {
            t.tables[0].header = format::Block {
                offset: at,
                len: j.len() as u64,
                xxh3: format::xxh3(&j),
            };
        });
        let e = open_err(d.path(), &m);
        assert!(matches!(e, Error::Format { .. }), "{e}");
    }
    // Invalid JSON in a header and in the TOC itself.
    let j = b"{\"name\": \"a\", nope".to_vec();
    let m = reseal(&b, &j, |t, at| {
        t.tables[0].header = format::Block {
            offset: at,
            len: j.len() as u64,
            xxh3: format::xxh3(&j),
        };
    });
    assert!(matches!(open_err(d.path(), &m), Error::Json { .. }));
    // A TOC claiming a huge index count.
    let m = reseal(&b, &[], |t, _| t.tables[0].chunks = u64::MAX / 2);
    assert!(matches!(open_err(d.path(), &m), Error::Format { .. }));
}

/// A table whose index claims 51.5 GB of values (256 chunks of 50 M values, each within what
/// zstd could expand its 1,536 bytes to) in a file of 400 kB: reading it whole (`read_all`,
/// `to_table`, an eager open) is an error naming the file — it allocated the whole claim before
/// decoding a chunk, and aborted the process ("memory allocation failed") where that was more
/// than the machine's memory.
#[test]
fn a_table_claiming_more_values_than_memory_is_an_error_when_read_whole() {
    use brdftab::store::tables;
    use brdftab::table::{Grid, Mapping, Param, Symmetry};
    let d = TempDir::new("store-claim");
    let p = d.join("claim.btdb");
    let none = Symmetry {
        isotropic: false,
        reciprocal: false,
        bilateral: false,
    };
    let g = Grid::with_sizes(
        Param::HalfDiff,
        [256; 4],
        [Mapping::Sqrt, Mapping::Uniform],
        Channels::Rgb,
        none,
    )
    .unwrap();
    let src = Source::Other {
        description: "a claim".into(),
    };
    let h = TableHeader::for_grid("claim", src, &g, Codec::default());
    assert_eq!(h.values, 3 << 32);
    let per = h.values / 256;
    let mut w = Writer::create(&p).unwrap();
    w.begin_table(h).unwrap();
    for i in 0..256 {
        w.encoded_chunk(&[i as u8; 1536], per).unwrap();
    }
    w.end_table().unwrap();
    w.finish().unwrap();
    let s = Store::open(&p).unwrap();
    let t = s.table("claim").unwrap();
    t.grid().unwrap(); // header, index and grid agree: only the chunks tell
    let eager = tables::open_brdf(format!("{}#claim", p.display()), true);
    for e in [
        t.read_all().map(drop).unwrap_err(),
        t.to_table().map(drop).unwrap_err(),
        eager.map(drop).unwrap_err(),
    ] {
        assert!(matches!(e, Error::Format { .. }), "{e}");
        assert!(e.to_string().contains("claim.btdb"), "{e}");
    }
}

/// A claim of 68.7 GB (2^34 values less a few, the most a header may hold: 16,384 chunks of 1 M
/// values, each within what zstd could expand its 40 bytes to) by a table whose grid has the
/// one-array kernel (halfdiff, isotropic and bilateral, warped axes), opened lazily: its first
/// lookup gathers every chunk into one array, which reserved the whole claim unguarded and
/// aborted the process ("memory allocation failed") before decoding a chunk. Now it is an
/// error as the eager read's is: the lookup gives 0 and `health` names the file.
#[test]
fn a_one_array_table_claiming_more_values_than_memory_fails_its_first_lookup() {
    use brdftab::Brdf;
    use brdftab::table::adaptive::grid_with_warps;
    use brdftab::table::kernel::Kernel;
    use brdftab::table::warp::{Warp, WarpVar};
    use brdftab::table::{Grid, Symmetry};
    use glam::DVec3;
    let d = TempDir::new("store-claim-lazy");
    let p = d.join("claim.btdb");
    let sym = Symmetry {
        isotropic: true,
        reciprocal: false,
        bilateral: true,
    };
    let warps = [
        Warp::identity(WarpVar::SqrtSine),
        Warp::identity(WarpVar::HalfPower),
        Warp::identity(WarpVar::PseudoAngle),
    ];
    // The claim's grid: 16,384 θh × 174,760 θd × 2 φd nodes, RGB (within the grid's 2^40
    // values over the full domain). The library bakes no grid that large; the header says so.
    let small = grid_with_warps(Channels::Rgb, sym, [2, 2, 2], warps).unwrap();
    let mut j = serde_json::to_value(&small).unwrap();
    for (axis, size) in [
        ("theta1", 16384),
        ("phi1", 2),
        ("theta2", 174760),
        ("phi2", 2),
    ] {
        j[axis]["size"] = size.into();
    }
    let g: Grid = serde_json::from_value(j).unwrap();
    assert!(
        Kernel::new(&g).is_some(),
        "a grid the one-array kernel reads"
    );
    let src = Source::Other {
        description: "a claim".into(),
    };
    let h = TableHeader::for_grid("claim", src, &g, Codec::default());
    assert_eq!(h.values, 16384 * 174760 * 6);
    let per = h.values / 16384;
    let mut w = Writer::create(&p).unwrap();
    w.begin_table(h).unwrap();
    for i in 0..16384 {
        w.encoded_chunk(&[i as u8; 40], per).unwrap();
    }
    w.end_table().unwrap();
    w.finish().unwrap();
    let b = brdftab::store::tables::open_brdf(format!("{}#claim", p.display()), false).unwrap();
    let mut out = [1f32; 3];
    b.eval(
        DVec3::new(0.3, 0.1, 0.9),
        DVec3::new(-0.2, 0.4, 0.8),
        &mut out,
    );
    assert_eq!(out, [0.0; 3]);
    let e = b.health().unwrap_err();
    assert!(matches!(e, Error::Format { .. }), "{e}");
    assert!(e.to_string().contains("claim.btdb"), "{e}");
}

/// The in-repo substitute for a fuzzer (nightly is not available for `cargo fuzz`): thousands of
/// random mutations — byte flips, overwrites, truncations, splices — of a real database must
/// each give an error, never a panic or an accepted file.
#[test]
fn random_mutations_never_panic_or_pass() {
    let d = TempDir::new("store-mutate");
    let (_, b) = sample_file(d.path());
    // `BRDFTAB_MUTATIONS` asks for more (or fewer) mutations; a value that is not a positive
    // count is refused rather than run as the default or as no test at all.
    let iters: usize = match std::env::var("BRDFTAB_MUTATIONS") {
        Ok(s) => s
            .parse()
            .ok()
            .filter(|&n| n > 0)
            .unwrap_or_else(|| panic!("BRDFTAB_MUTATIONS={s:?}: not a positive count")),
        Err(_) => 3000,
    };
    let mut rng = 0x9E3779B97F4A7C15u64;
    let mut next = move || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        rng
    };
    let mut tried = 0;
    for it in 0..iters {
        let mut m = b.clone();
        for _ in 0..1 + next() % 4 {
            let at = (next() % m.len() as u64) as usize;
            match next() % 5 {
                0 => m[at] ^= 1 << (next() % 8),
                1 => m[at] = next() as u8,
                2 => m.truncate(at.max(1)),
                3 => {
                    let src = (next() % m.len() as u64) as usize;
                    let n = (next() % 64) as usize;
                    let chunk: Vec<u8> = m[src..(src + n).min(m.len())].to_vec();
                    let end = (at + chunk.len()).min(m.len());
                    m[at..end].copy_from_slice(&chunk[..end - at]);
                }
                _ => m.insert(at, next() as u8),
            }
        }
        if m == b {
            continue;
        }
        tried += 1;
        let r = std::panic::catch_unwind(|| {
            Store::from_bytes("m", m.clone(), StoreOptions::default()).and_then(|s| s.verify())
        });
        match r {
            Err(_) => panic!("mutation {it} panicked"),
            Ok(Ok(_)) => panic!("mutation {it} accepted"),
            Ok(Err(_)) => {}
        }
    }
    assert!(tried > 0, "no mutation changed the file");
}

// ---------------------------------------------------------------------------------------------
// Tables on grids (packed reciprocal layouts have chunks of different lengths).

#[test]
fn grid_tables_round_trip_including_packed_layouts() {
    use brdftab::store::tables;
    use brdftab::table::{Grid, Mapping, Param, Symmetry, Table};
    let d = TempDir::new("store-grid");
    let p = d.join("g.btdb");
    for (k, (param, sizes, sym)) in [
        (
            Param::HalfDiff,
            [9, 1, 9, 18],
            Symmetry {
                isotropic: true,
                reciprocal: true,
                bilateral: false,
            },
        ),
        (
            Param::InOut,
            [8, 1, 8, 16],
            Symmetry {
                isotropic: true,
                reciprocal: true,
                bilateral: false,
            },
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let g = Grid::with_sizes(
            param,
            sizes,
            [Mapping::Uniform, Mapping::Uniform],
            Channels::Rgb,
            sym,
        )
        .unwrap();
        let t = Table::from_fn(g, "test", |i, a, out| {
            for (c, o) in out.iter_mut().enumerate() {
                *o = (a[0].cos() * a[2].cos()).abs() as f32 * (1.0 + c as f32) + i[3] as f32 * 1e-3;
            }
        });
        let name = format!("t{k}");
        tables::save(
            &p,
            &name,
            Source::Other {
                description: "fn".into(),
            },
            &t,
            Codec {
                quant: Quant::F32,
                level: 3,
                ..Codec::default()
            },
            false,
        )
        .unwrap();
        let s = Store::open(&p).unwrap();
        let st = s.table(&name).unwrap();
        let back = st.to_table().unwrap();
        assert_eq!(back.values(), t.values());
        assert_eq!(back.grid(), t.grid());
        // npy with the grid's node offsets (unstored nodes of packed layouts are NaN).
        let g = st.grid().unwrap();
        let off = tables::node_offset(&g);
        let out = d.join(format!("{name}.npy"));
        export::npy(&st, &out, Some(&off)).unwrap();
        let n: u64 = st.header().shape.iter().product();
        let hl = 128; // header is padded to 64; small shapes fit in 128
        assert_eq!(std::fs::metadata(&out).unwrap().len(), hl + 4 * n);
    }
}

#[test]
fn stored_tables_evaluate_like_the_table_they_came_from() {
    use brdftab::Brdf;
    use brdftab::store::tables;
    use brdftab::table::{Grid, Mapping, Param, Symmetry, Table, TabulatedBrdf};
    use glam::DVec3;
    let d = TempDir::new("store-brdf");
    let p = d.join("g.btdb");
    let g = Grid::with_sizes(
        Param::HalfDiff,
        [16, 1, 16, 32],
        [Mapping::Sqrt, Mapping::Uniform],
        Channels::Rgb,
        Symmetry {
            isotropic: true,
            reciprocal: true,
            bilateral: true,
        },
    )
    .unwrap();
    let t = Table::from_fn(g, "test", |_, a, out| {
        for (c, o) in out.iter_mut().enumerate() {
            *o = (1.0 + a[0].cos() * 3.0 + a[2].sin()) as f32 * (1.0 + c as f32);
        }
    });
    tables::save(
        &p,
        "x",
        Source::Other {
            description: "fn".into(),
        },
        &t,
        Codec {
            quant: Quant::F32,
            level: 3,
            ..Codec::default()
        },
        false,
    )
    .unwrap();
    tables::save(
        &p,
        "y",
        Source::Other {
            description: "fn".into(),
        },
        &t,
        Codec {
            quant: Quant::F16,
            level: 3,
            ..Codec::default()
        },
        false,
    )
    .unwrap();
    let reference = TabulatedBrdf::from_table(t);
    let lazy = tables::open_brdf(format!("{}#x", p.display()), false).unwrap();
    let eager = tables::open_brdf(format!("{}#x", p.display()), true).unwrap();
    assert_eq!(lazy.loaded_chunks(), 0);
    let (wi, wo) = (DVec3::new(0.3, 0.1, 0.9), DVec3::new(-0.2, 0.4, 0.8));
    let (mut a, mut b, mut c) = ([0f32; 3], [0f32; 3], [0f32; 3]);
    reference.eval(wi, wo, &mut a);
    lazy.eval(wi, wo, &mut b);
    eager.eval(wi, wo, &mut c);
    assert_eq!(a, b);
    assert_eq!(a, c);
    // A lookup loads the chunks it touches — all of them at once for a table the fast kernel
    // reads (`table::kernel`: it holds the table in one array).
    if brdftab::table::kernel::Kernel::new(lazy.grid()).is_some() {
        assert_eq!(lazy.loaded_chunks(), lazy.grid().layout().chunk_count());
    } else {
        assert!(lazy.loaded_chunks() >= 1 && lazy.loaded_chunks() <= 2);
    }
    // A database with several tables needs a name.
    let e = tables::open_brdf(p.display().to_string(), false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("#NAME"), "{e}");
    assert!(tables::is_store_file(&p));
}

/// A Lambert table of `kd` 0.3 baked small, and its bytes with one bit of chunk 0 flipped.
fn lambert_with_a_damaged_chunk(d: &TempDir) -> Vec<u8> {
    let p = d.join("l.btdb");
    brdftab::BakeRequest::new(r#"{"model": "lambert", "kd": 0.3}"#)
        .preset(brdftab::table::presets::Preset::Small)
        .run(&brdftab::BakeTarget::file(p.to_str().unwrap()))
        .unwrap();
    let mut b = std::fs::read(&p).unwrap();
    let st = Store::from_bytes("x.btdb", b.clone(), StoreOptions::default()).unwrap();
    let raw = st.table("l").unwrap().raw_chunk(0).unwrap().to_vec();
    let at = b
        .windows(raw.len())
        .position(|w| w == raw.as_slice())
        .unwrap();
    b[at + raw.len() / 2] ^= 0x10;
    b
}

#[test]
fn the_analyses_of_a_table_with_a_damaged_chunk_are_its_error() {
    // Python's `brdftab.check` on a lazily opened table whose chunk failed its checksum gave a
    // report of the zeros read in its place (max albedo 0.928 for 0.995) and no error.
    let d = TempDir::new("store-lazy-analyses");
    let b = lambert_with_a_damaged_chunk(&d);
    let checksum = |e: &Error| matches!(e, Error::Checksum { .. });
    let st = Store::from_bytes("x.btdb", b.clone(), StoreOptions::default()).unwrap();
    let tab = st.table("l").unwrap().brdf().unwrap();
    let opts = brdftab::analysis::plausibility::Options::default();
    let e = brdftab::analysis::plausibility::check(&tab, &opts).unwrap_err();
    assert!(checksum(&e), "{e}");
    let st = Store::from_bytes("x.btdb", b, StoreOptions::default()).unwrap();
    let tab = st.table("l").unwrap().brdf().unwrap();
    let e = brdftab::analysis::albedo::albedo_curve(&tab, &[0.0, 1.0]).unwrap_err();
    assert!(checksum(&e), "{e}");
}

#[test]
#[cfg(unix)]
fn a_file_cut_short_or_rewritten_in_place_while_open_is_an_error_not_a_crash() {
    // `Store::open` mapped the file on Unix: another program truncating it in place
    // (`cp other.btdb db.btdb`) made the next chunk read a SIGBUS, which killed the process
    // (Python: "Fatal Python error: Bus error"). It now reads at offsets.
    let d = TempDir::new("store-cut-short");
    let p = d.join("l.btdb");
    let other = d.join("o.btdb");
    for (path, kd) in [(&p, 0.3), (&other, 0.6)] {
        brdftab::BakeRequest::new(format!(r#"{{"model": "lambert", "kd": {kd}}}"#))
            .preset(brdftab::table::presets::Preset::Small)
            .name("l")
            .run(&brdftab::BakeTarget::file(path.to_str().unwrap()))
            .unwrap();
    }
    let whole = std::fs::read(&p).unwrap();
    for cut in [100, whole.len() / 2] {
        std::fs::write(&p, &whole).unwrap();
        let st = Store::open(&p).unwrap();
        let t = st.table("l").unwrap();
        // In place, as `cp` and `truncate` do: the same inode, shorter.
        let f = std::fs::OpenOptions::new().write(true).open(&p).unwrap();
        f.set_len(cut as u64).unwrap();
        let e = t.read_all().unwrap_err();
        assert!(
            matches!(&e, Error::Format { msg, .. } if msg.contains("cut short")),
            "{cut}: {e}"
        );
    }
    // Rewritten in place with another table's bytes: its chunks fail their checksums.
    std::fs::write(&p, &whole).unwrap();
    let st = Store::open(&p).unwrap();
    let t = st.table("l").unwrap();
    let mut f = std::fs::OpenOptions::new().write(true).open(&p).unwrap();
    std::io::Write::write_all(&mut f, &std::fs::read(&other).unwrap()).unwrap();
    f.set_len(std::fs::read(&other).unwrap().len() as u64)
        .unwrap();
    let e = t.read_all().unwrap_err();
    assert!(
        matches!(&e, Error::Checksum { .. } | Error::Format { .. }),
        "{e}"
    );
}

#[test]
fn a_damaged_chunk_read_lazily_stays_a_checksum_error() {
    let d = TempDir::new("store-lazy-checksum");
    let b = lambert_with_a_damaged_chunk(&d);
    let st = Store::from_bytes("x.btdb", b, StoreOptions::default()).unwrap();
    let tab = st.table("l").unwrap().brdf().unwrap();
    let e = tab.load_all().unwrap_err();
    assert!(
        matches!(
            &e,
            Error::Checksum {
                what: brdftab::error::Section::Chunk { table, chunk: 0 },
                ..
            } if table == "l"
        ),
        "{e}"
    );
}
