//! The bake-to-file unit tests: targets (file, database, raw, MERL), staging, names, refusals
//! before the bake, and the accuracy report of the written table.

use super::*;
use crate::bake::{SymmetryChoice, codec, tmp};
use crate::source::OpenOptions;
use crate::table::presets::Preset;

/// A measured (accuracy-reporting) streamed bake through a link into a directory whose
/// name is not UTF-8: the staging file goes beside the link's target, whose name is bytes,
/// and is renamed over it; nothing is left beside the link.
// Not on Apple's file systems, which refuse a name that is not UTF-8 (APFS: EILSEQ).
#[cfg(all(unix, not(target_vendor = "apple")))]
#[test]
fn a_measured_bake_through_a_link_into_a_non_utf8_directory_is_staged_beside_its_target() {
    use std::os::unix::ffi::OsStrExt;
    let d = tmp("staging_non_utf8");
    let odd = d.join(std::ffi::OsStr::from_bytes(b"dir\xff"));
    std::fs::create_dir(&odd).unwrap();
    let link = d.join("t.btdb");
    std::os::unix::fs::symlink(odd.join("t.btdb"), &link).unwrap();
    let mut req = BakeRequest::new(r#"{"model":"ggx","alpha":0.3}"#).preset(Preset::Small);
    req.accuracy_pairs = 4096;
    let link = link.to_str().unwrap().to_owned();
    let r = req.run(&BakeTarget::file(&link)).unwrap();
    assert!(r.accuracy.is_some());
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert!(odd.join("t.btdb").is_file());
    crate::open(&link).unwrap();
    let mut left: Vec<_> = std::fs::read_dir(d.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    left.sort();
    assert_eq!(left.len(), 2, "{left:?}"); // the directory and the link, no staging file
    assert_eq!(std::fs::read_dir(&odd).unwrap().count(), 1);
}

#[test]
fn file_db_and_raw_targets_give_the_same_table() {
    let d = tmp("targets");
    let spec = r#"{"model":"cook_torrance","m":0.4,"ks":0.5}"#;
    let req = BakeRequest::new(spec)
        .preset(Preset::Small)
        .codec(codec("f32", None, None, None, false).unwrap());
    let file = d.join("ct.btdb").to_str().unwrap().to_owned();
    let dbp = d.join("many.btdb").to_str().unwrap().to_owned();
    let raw = d.join("ct.tbl").to_str().unwrap().to_owned();
    let r1 = req.run(&BakeTarget::file(&file)).unwrap();
    let merl = d.join("ct.binary").to_str().unwrap().to_owned();
    let rm = req.run(&BakeTarget::Merl(merl.clone().into())).unwrap();
    assert!(rm.merl_cells && rm.output == merl);
    assert!(crate::measured::MerlBrdf::open(&merl).is_ok());
    let r2 = req.run(&BakeTarget::db(&dbp, "ct")).unwrap();
    let r3 = req.run(&BakeTarget::Raw(raw.clone().into())).unwrap();
    assert_eq!(r1.name, "ct");
    assert_eq!(r2.output, format!("{dbp}#ct"));
    assert_eq!(r1.info["values"], r2.info["values"]);
    assert_eq!(r1.values, r3.values);
    let a = crate::source::open_table(&file, &OpenOptions::default())
        .unwrap()
        .to_table()
        .unwrap();
    let b = crate::source::open_table(format!("{dbp}#ct"), &OpenOptions::default())
        .unwrap()
        .to_table()
        .unwrap();
    let c = Table::open_raw(&raw).unwrap();
    assert_eq!(a.values(), b.values());
    assert_eq!(a.values(), c.values());
    // A second add of the same name is refused; with replace it succeeds.
    assert!(req.run(&BakeTarget::db(&dbp, "ct")).is_err());
    let replace = BakeTarget::Db {
        path: dbp.clone().into(),
        name: "ct".into(),
        replace: true,
    };
    req.run(&replace).unwrap();
}

#[test]
fn a_bake_that_fails_to_write_leaves_the_old_file() {
    let d = tmp("failed_write");
    let out = d.join("keep.btdb").to_str().unwrap().to_owned();
    BakeRequest::new(r#"{"model":"lambert","kd":0.5}"#)
        .preset(Preset::Small)
        .run(&BakeTarget::file(&out))
        .unwrap();
    let before = std::fs::read(&out).unwrap();
    // f_r = 1e5 is beyond f16 (±65504): the encoding fails once the table is baked. The
    // default grid builds the table whole (the preset check's table), the small preset
    // streams it; neither may remove the old file first.
    let bright = r#"{"model":"lambert","kd":1e5}"#;
    let f16 = codec("f16", None, None, None, false).unwrap();
    for req in [
        BakeRequest::new(bright).codec(f16),
        BakeRequest::new(bright).preset(Preset::Small).codec(f16),
    ] {
        let e = req.run(&BakeTarget::file(&out)).unwrap_err();
        assert!(e.to_string().contains("f16"), "{e}");
        assert_eq!(std::fs::read(&out).unwrap(), before);
    }
}

#[test]
fn an_adaptive_grid_too_large_for_memory_is_an_error_not_an_abort() {
    use crate::bake::GridChoice;
    // "Before the work" scales with the machine (under qemu-user this runs 10–50× slower): a
    // refusal may take up to five bakes of a tiny adaptive grid — the same plan, 1 024 nodes —
    // timed here, and never less than 5 s. Baking the first grid (6·10⁸ nodes, 7.7 GB)
    // would take far longer.
    let t0 = Instant::now();
    BakeRequest::new(r#"{"model":"lambert","kd":0.5}"#)
        .grid(GridChoice::Adaptive(Some([16, 8, 8])))
        .table(&Silent)
        .unwrap();
    let bound = (5.0 * t0.elapsed().as_secs_f64()).max(5.0);
    for nodes in [
        [10_000_000, 8, 8],
        [usize::MAX, 4, 4],
        [8, 8, usize::MAX / 2],
    ] {
        let t0 = Instant::now();
        let e = BakeRequest::new(r#"{"model":"lambert","kd":0.5}"#)
            .grid(GridChoice::Adaptive(Some(nodes)))
            .table(&Silent)
            .map(|_| ())
            .unwrap_err();
        assert!(
            matches!(e, Error::InvalidArgument { ref name, .. } if name == "grid"),
            "{nodes:?}: {e}"
        );
        let took = t0.elapsed().as_secs_f64();
        assert!(
            took < bound,
            "{nodes:?}: refused only after work ({took:.2} s)"
        );
    }
}

#[test]
fn table_of_bakes_the_source_it_is_given_not_a_file_of_the_requests_name() {
    let d = tmp("table_of_merl_name");
    let merl = d.join("white.binary");
    let white = crate::open(r#"{"model":"lambert","kd":0.5}"#).unwrap();
    crate::measured::MerlBrdf::from_brdf(white.as_ref())
        .write(&merl)
        .unwrap();
    let dark = crate::open(r#"{"model":"lambert","kd":0.1}"#).unwrap();
    let (t, _) = BakeRequest::new(merl.to_str().unwrap())
        .table_of(dark.as_ref(), &Silent)
        .unwrap();
    let mut f = [0.0f32; 3];
    TabulatedBrdf::from_table(t).eval(glam::DVec3::Z, glam::DVec3::new(0.6, 0.0, 0.8), &mut f);
    assert!(f.iter().all(|&x| (x - 0.1).abs() < 1e-3), "{f:?}");
    // The file itself, handed over opened, still keeps its own cells.
    let file = crate::open(merl.to_str().unwrap()).unwrap();
    let (t, _) = BakeRequest::new(merl.to_str().unwrap())
        .table_of(file.as_ref(), &Silent)
        .unwrap();
    assert_eq!(
        t.grid(),
        crate::measured::MerlBrdf::open(&merl)
            .unwrap()
            .to_table()
            .grid()
    );
}

#[test]
fn fields_set_directly_are_checked_as_the_settings_are() {
    for (t, ss, field) in [
        (f64::NAN, 1, "symmetry_tolerance"),
        (-1.0, 1, "symmetry_tolerance"),
        (1e-3, 0, "supersample"),
    ] {
        let mut r = BakeRequest::new(r#"{"model":"lambert","kd":0.5}"#).preset(Preset::Small);
        r.symmetry_tolerance = t;
        r.supersample = ss;
        let e = r.table(&Silent).map(|_| ()).unwrap_err();
        assert!(
            matches!(e, Error::InvalidArgument { ref name, .. } if name == field),
            "{e}"
        );
    }
}

#[test]
fn a_converted_specs_default_name_is_its_model() {
    assert_eq!(source_stem(r#" {"model":"lambert","kd":0.3}"#), "lambert");
    assert_eq!(source_stem(r#"{"model":"ggx","alpha":0.1}"#), "ggx");
    assert_eq!(source_stem("{not json"), "table");
    assert_eq!(
        source_stem("data/rgl/paper_white_rgb.bsdf"),
        "paper_white_rgb"
    );
    assert_eq!(source_stem("lib.btdb#gold"), "gold");
}

/// A file's stem with a character no table name holds (`#`; `\`, a file name's character
/// on Unix) names its table with `_` there, a name every platform opens.
#[test]
fn a_stem_holds_no_character_a_table_name_refuses() {
    assert_eq!(stem("scans/x#2.bsdf"), "x_2");
    #[cfg(unix)]
    assert_eq!(stem(r"scans/a\b.bsdf"), "a_b");
    crate::store::name::check("name", &stem(r"a\b#c.bsdf")).unwrap();
}

#[test]
fn an_existing_name_is_refused_before_the_bake() {
    /// Counts the stages a bake begins.
    #[derive(Default)]
    struct Stages(std::sync::atomic::AtomicUsize);
    impl Progress for Stages {
        fn begin(&self, _: &str, _: u64) {
            self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
    }
    let d = tmp("duplicate_first");
    let db = d.join("lib.btdb").to_str().unwrap().to_owned();
    let req = BakeRequest::new(r#"{"model":"lambert","kd":0.5}"#).preset(Preset::Small);
    let target = |replace| BakeTarget::Db {
        path: db.clone().into(),
        name: "matte".into(),
        replace,
    };
    let stages = Stages::default();
    req.run_with(&target(false), &stages).unwrap();
    assert!(
        stages.0.into_inner() > 0,
        "the first bake reports its stages"
    );
    let before = std::fs::read(&db).unwrap();
    let stages = Stages::default();
    let e = req.run_with(&target(false), &stages).unwrap_err();
    assert!(
        matches!(e, Error::Duplicate { ref name, .. } if name == "matte"),
        "{e}"
    );
    assert_eq!(stages.0.into_inner(), 0, "refused before any stage began");
    assert_eq!(std::fs::read(&db).unwrap(), before);
    req.run(&target(true)).unwrap(); // replace still works
}

#[test]
fn provenance_and_accuracy_are_reported() {
    let d = tmp("prov");
    let spec = r#"{"model":"lambert","kd":0.3}"#;
    let out = d.join("l.btdb").to_str().unwrap().to_owned();
    let r = BakeRequest::new(spec)
        .preset(Preset::Small)
        .accuracy(2000)
        .run(&BakeTarget::file(&out))
        .unwrap();
    assert_eq!(r.info["source"]["kind"], "model");
    let acc = r.accuracy.unwrap();
    assert_eq!(acc.pairs, 2000);
    // log16 ≤ 1e-3 relative on a constant: the error is the codec's bound at most.
    assert!(acc.max_rel <= 1e-3, "{acc:?}");
}

/// The accuracy report reads the table it wrote by the output's path and the table's name,
/// never through a `DB#NAME` string: such a string is looked up whole first (a file named
/// `l.btdb#l` is read as itself, `store::name`), so a file of that name beside the output —
/// here a table of kd = 0.9 — was what the report measured (relative error 2).
#[test]
fn the_accuracy_report_reads_the_written_table_by_its_path() {
    let d = tmp("hash");
    let path = |f: &str| d.join(f).to_str().unwrap().to_owned();
    let decoy = path("decoy.btdb");
    let other = BakeRequest::new(r#"{"model":"lambert","kd":0.9}"#).preset(Preset::Small);
    other.run(&BakeTarget::file(&decoy)).unwrap();
    let req = BakeRequest::new(r#"{"model":"lambert","kd":0.3}"#)
        .preset(Preset::Small)
        .accuracy(2000);
    for (target, beside) in [
        (BakeTarget::file(path("l.btdb")), "l.btdb#l"),
        // A `#` in the output file's own name (table `x`).
        (BakeTarget::file(path("x.btdb#x")), "x.btdb#x#x"),
        (BakeTarget::db(path("db.btdb"), "m"), "db.btdb#m"),
    ] {
        std::fs::copy(&decoy, path(beside)).unwrap();
        let r = req.run(&target).unwrap();
        let acc = r.accuracy.unwrap();
        // log16 ≤ 1e-3 relative on a constant, as above.
        assert!(acc.max_rel <= 1e-3, "{target:?}: {acc:?}");
    }
}

/// The accuracy report of a table built whole is that of the table as written — the
/// codec's rounding included — to the bit: measured in memory before the codec, a log16
/// table at a 1e-2 tolerance read as if it were stored exactly.
#[test]
fn the_accuracy_report_of_a_table_built_whole_is_of_the_stored_table() {
    let d = tmp("as_stored");
    let req = BakeRequest::new(r#"{"model":"ggx","alpha":0.3}"#)
        .preset(Preset::Small)
        .quantity(Quantity::FrCosOut) // built whole before it is written
        .codec(codec("log16:1e-2", None, None, None, false).unwrap())
        .accuracy(2000);
    for target in [
        BakeTarget::file(d.join("t.btdb")),
        BakeTarget::db(d.join("db.btdb"), "t"),
    ] {
        let r = req.run(&target).unwrap();
        let got = r.accuracy.unwrap();
        let src = crate::open(r#"{"model":"ggx","alpha":0.3}"#).unwrap();
        let stored = tables::open_brdf_at(target.path(), Some("t"), false).unwrap();
        let interp = Interp::default_for(stored.grid());
        let want = Accuracy::measure(&stored.with_interp(interp), src.as_ref(), 2000).unwrap();
        assert_eq!(
            (got.rel_rmse, got.max_rel),
            (want.rel_rmse, want.max_rel),
            "{target:?}"
        );
    }
}

#[test]
fn an_explicit_symmetry_the_source_breaks_is_refused_unless_forced() {
    let d = tmp("sym");
    // The original Phong is not reciprocal.
    let spec = r#"{"model":"phong","ks":0.5,"n":20}"#;
    let out = d.join("p.btdb").to_str().unwrap().to_owned();
    let req = BakeRequest::new(spec)
        .preset(Preset::Small)
        .symmetry("isotropic,reciprocal".parse::<SymmetryChoice>().unwrap());
    assert!(matches!(
        req.run(&BakeTarget::file(&out)),
        Err(Error::Symmetry { .. })
    ));
    let mut forced = req.clone();
    forced.force = true;
    let r = forced.run(&BakeTarget::file(&out)).unwrap();
    assert!(r.forced.is_some());
}
