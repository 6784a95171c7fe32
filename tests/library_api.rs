//! The library functions hosts call instead of re-implementing them (issue 13): one progress type,
//! the suite's metrics, `info` as text, option parsing, typed errors without CLI flags.

use std::sync::Mutex;

use brdftab::bake::{BakeRequest, BakeTarget};
use brdftab::progress::{Progress, Silent};
use brdftab::store::info;
use brdftab::table::presets::Preset;
use brdftab::testkit::TempDir;
use brdftab::{Channels, Error, ModelSpec};

const LAMBERT: &str = r#"{"model": "lambert", "kd": 0.25}"#;

fn lambert() -> Box<dyn brdftab::Brdf + Send + Sync> {
    ModelSpec::parse(LAMBERT)
        .unwrap()
        .build(&Channels::Rgb)
        .unwrap()
}

/// Records every call, so tests can check what a long operation reported.
#[derive(Default)]
struct Log(Mutex<Vec<String>>);

impl Progress for Log {
    fn begin(&self, what: &str, total: u64) {
        self.0.lock().unwrap().push(format!("begin {what} {total}"));
    }
    fn set(&self, done: u64) {
        self.0.lock().unwrap().push(format!("set {done}"));
    }
    fn end(&self) {
        self.0.lock().unwrap().push("end".into());
    }
}

impl Log {
    fn calls(&self) -> Vec<String> {
        self.0.lock().unwrap().clone()
    }
}

#[test]
fn bake_reports_its_values_and_the_report_reads_as_text() {
    let d = TempDir::new("api-bake");
    let out = d.join("l.btdb");
    let log = Log::default();
    let req = BakeRequest::new(LAMBERT).preset(Preset::Small);
    let r = req
        .run_with(&BakeTarget::file(out.to_str().unwrap()), &log)
        .unwrap();
    assert_eq!(log.calls()[0], format!("begin baking {}", r.values));
    let text = r.summary(&req.codec);
    assert!(
        text.starts_with("baked ") && text.contains("wrote "),
        "{text}"
    );
    let v = info::file_info(out.to_str().unwrap()).unwrap();
    let t = info::file_text(&v);
    assert!(
        t.contains("table `l`:") && t.contains("brdftab format, 1 table)"),
        "{t}"
    );
    let rows = info::list(out.to_str().unwrap()).unwrap();
    let l = info::list_text(&rows);
    assert!(
        l.lines().count() == 2 && l.lines().nth(1).unwrap().starts_with('l'),
        "{l}"
    );
}

#[test]
fn a_files_ratio_counts_every_table_also_when_one_is_asked_for() {
    let d = TempDir::new("api-ratio");
    let db = d.join("two.btdb");
    let db = db.to_str().unwrap();
    for name in ["a", "b"] {
        BakeRequest::new(LAMBERT)
            .preset(Preset::Small)
            .run_with(&BakeTarget::db(db, name), &Silent)
            .unwrap();
    }
    let whole = info::file_info(db).unwrap();
    let one = info::file_info(format!("{db}#a")).unwrap();
    let tables = whole["tables"].as_array().unwrap();
    let values: u64 = tables.iter().map(|t| t["values"].as_u64().unwrap()).sum();
    let bytes = whole["bytes"].as_u64().unwrap();
    assert_eq!(tables.len(), 2);
    // The file's figures are the file's, whichever tables are listed.
    assert_eq!(one["tables"].as_array().unwrap().len(), 1);
    assert_eq!(one["bytes"], whole["bytes"]);
    assert_eq!(one["ratio_to_f32"], whole["ratio_to_f32"]);
    let ratio = whole["ratio_to_f32"].as_f64().unwrap();
    assert_eq!(ratio, values as f64 * 4.0 / bytes as f64);
}

#[test]
fn a_table_named_like_a_measured_file_opens_as_the_table() {
    let d = TempDir::new("api-kind");
    let db = d.join("m.btdb");
    let db = db.to_str().unwrap();
    for name in ["paper.bsdf", "gold.binary", "spec.json"] {
        BakeRequest::new(LAMBERT)
            .preset(Preset::Small)
            .run_with(&BakeTarget::db(db, name), &Silent)
            .unwrap();
        let source = format!("{db}#{name}");
        assert_eq!(brdftab::classify(&source), brdftab::SourceKind::Table);
        let (b, model) = (
            brdftab::open(&source).unwrap(),
            brdftab::open(LAMBERT).unwrap(),
        );
        let (mut f, mut want) = ([0f32; 3], [0f32; 3]);
        b.eval(glam::DVec3::Z, glam::DVec3::Z, &mut f);
        model.eval(glam::DVec3::Z, glam::DVec3::Z, &mut want);
        // The table of the model (its values within the codec's rounding, 2^-11).
        assert!(
            (f[0] - want[0]).abs() <= want[0] * 1e-3,
            "{name}: {f:?} vs {want:?}"
        );
    }
}

#[test]
fn a_table_file_is_not_written_under_a_measured_files_name() {
    // A bake or save to `m.bsdf` or `m.binary` wrote a brdftab table that the library then
    // read as an RGL or MERL file and refused (the MERL reader as a truncated file with a
    // header of 1146372745 × 436866370 × 1).
    let d = TempDir::new("api-measured-name");
    let req = BakeRequest::new(LAMBERT).preset(Preset::Small);
    for name in ["m.bsdf", "m.binary", "M.BSDF", "m.json"] {
        let p = d.join(name);
        for target in [BakeTarget::File(p.clone()), BakeTarget::Raw(p.clone())] {
            let e = req.run(&target);
            assert_eq!(field(e), "output", "{name}");
            assert!(!p.exists(), "{name}");
        }
    }
    // Saved from a table: refused alike; `.btdb` and `DB#NAME` (the name is the table's) are
    // written.
    let source = lambert();
    let grid = Preset::Small
        .grid(None, brdftab::table::Symmetry::default(), Channels::Rgb)
        .unwrap();
    let (table, _) = brdftab::table::bake(source.as_ref(), &grid, &Default::default()).unwrap();
    let settings = brdftab::request::SaveSettings::default();
    let src = || brdftab::store::Source::Model {
        spec: serde_json::json!({"model": "lambert"}),
    };
    for name in ["s.bsdf", "s.binary"] {
        let p = d.join(name);
        let e = brdftab::request::save_table(&table, &p, src(), &settings);
        assert_eq!(field(e), "output", "{name}");
        assert!(!p.exists(), "{name}");
    }
    let db = format!("{}#s.bsdf", d.join("s.btdb").display());
    brdftab::request::save_table(&table, &db, src(), &settings).unwrap();
    assert_eq!(brdftab::classify(&db), brdftab::SourceKind::Table);
    // A table copied to such a name is read as what its name says and refused as such, with
    // what the file is.
    let btdb = d.join("s.btdb");
    for name in ["c.bsdf", "c.binary"] {
        let p = d.join(name);
        std::fs::copy(&btdb, &p).unwrap();
        let e = brdftab::open(p.to_str().unwrap())
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("but a brdftab table (its signature)"), "{e}");
    }
}

#[test]
fn a_taken_name_is_a_duplicate_error_naming_no_flag() {
    let d = TempDir::new("api-dup");
    let db = d.join("x.btdb").display().to_string();
    let req = BakeRequest::new(LAMBERT).preset(Preset::Small);
    req.run(&BakeTarget::db(&db, "a")).unwrap();
    let e = req.run(&BakeTarget::db(&db, "a")).unwrap_err();
    assert!(
        matches!(&e, Error::Duplicate { name, .. } if name == "a"),
        "{e}"
    );
    assert!(!e.to_string().contains("--"), "{e}");
}

/// The field an argument error names (panics on any other error).
fn field(r: Result<impl std::fmt::Debug, Error>) -> String {
    match r {
        Err(Error::InvalidArgument { name, .. }) => name,
        r => panic!("not an argument error: {r:?}"),
    }
}

#[test]
fn empty_table_names_and_control_characters_are_argument_errors_on_every_road() {
    use brdftab::request::{self, BakeSettings};
    let d = TempDir::new("api-names");
    let db = d.file("m.btdb");
    let settings = BakeSettings {
        preset: Some("small".into()),
        ..BakeSettings::default()
    };
    // `DB#` with nothing after the `#` was written as a file named `m.btdb#`.
    let out = format!("{db}#");
    assert_eq!(
        field(request::bake(LAMBERT, &out, &settings, &Silent)),
        "output"
    );
    assert!(!d.join("m.btdb#").exists() && !d.join("m.btdb").exists());
    // A NUL, a tab or an escape in NAME was stored as given.
    for name in ["\0", "a\tb", "\u{1b}[31m"] {
        let out = format!("{db}#{name}");
        assert_eq!(
            field(request::bake(LAMBERT, &out, &settings, &Silent)),
            "output"
        );
        let named = BakeSettings {
            name: Some(name.into()),
            ..settings.clone()
        };
        assert_eq!(field(request::bake(LAMBERT, &db, &named, &Silent)), "name");
    }
    assert!(!d.join("m.btdb").exists());
    // Reading: `m.btdb#` names no table; and a file of that name, when one exists, is read as
    // that file (a file on disk wins: `store::name`), here one brdftab cannot read.
    assert_eq!(field(brdftab::open(&out).map(|_| ())), "source");
    assert_eq!(field(info::file_info(&out)), "source");
    std::fs::write(d.join("m.btdb#"), b"not read").unwrap();
    let e = brdftab::open(&out).map(|_| ()).unwrap_err();
    assert!(
        matches!(e, Error::Unsupported(ref m) if m.contains("m.btdb#")),
        "{e}"
    );
    // The store's own entry points keep the same rule.
    request::bake(LAMBERT, format!("{db}#ok"), &settings, &Silent).unwrap();
    let s = brdftab::store::Store::open(&db).unwrap();
    let e = brdftab::store::db::import(d.join("n.btdb"), &s, "ok", "\0", false);
    assert_eq!(field(e), "name");
    assert!(!d.join("n.btdb").exists());
    // A default name (the output file's stem) is checked before the old file is replaced.
    let stem = d.file("a\u{7}b.btdb");
    std::fs::write(&stem, b"kept").unwrap();
    assert_eq!(
        field(request::bake(LAMBERT, &stem, &settings, &Silent)),
        "name"
    );
    assert_eq!(std::fs::read(&stem).unwrap(), b"kept");
}

/// A `#` in a file's own name: `a#b.btdb` was split into table `b.btdb` of a database `a` and
/// could not be opened. A string that names an existing file as a whole is that file; otherwise
/// it is `DB#NAME` as before.
#[test]
fn a_file_with_a_hash_in_its_name_opens_as_that_file() {
    let d = TempDir::new("api-hash");
    std::fs::create_dir(d.join("scan#2")).unwrap();
    let req = BakeRequest::new(LAMBERT).preset(Preset::Small);
    let plain = d.file("plain.btdb");
    req.run(&BakeTarget::file(&plain)).unwrap();
    let lambert_at = |b: &dyn brdftab::Brdf| {
        let mut f = [0.0f32; 3];
        b.eval(glam::DVec3::Z, glam::DVec3::Z, &mut f);
        f
    };
    let want = lambert_at(brdftab::open(&plain).unwrap().as_ref());
    for f in ["a#b.btdb", "scan#2/x#y.btdb"] {
        let whole = d.file(f);
        assert!(brdftab::open(&whole).is_err(), "{f}: nothing there yet");
        std::fs::copy(&plain, &whole).unwrap();
        let b = brdftab::open(&whole).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert_eq!(lambert_at(b.as_ref()), want, "{f}");
        assert_eq!(
            info::file_info(&whole).unwrap()["tables"][0]["name"],
            "plain"
        );
        assert!(brdftab::source::open_table(&whole, &Default::default()).is_ok());
    }
    // DB#NAME still opens a table when no file has the whole string as its name; a file that
    // does wins over the database.
    let db = d.file("lib.btdb");
    let glossy = r#"{"model": "ggx", "alpha": 0.3}"#;
    BakeRequest::new(glossy)
        .preset(Preset::Small)
        .run(&BakeTarget::db(&db, "g"))
        .unwrap();
    let entry = format!("{db}#g");
    let g = lambert_at(brdftab::open(&entry).unwrap().as_ref());
    assert_ne!(g, want);
    std::fs::copy(&plain, &entry).unwrap();
    assert_eq!(lambert_at(brdftab::open(&entry).unwrap().as_ref()), want);
    // An output keeps the DB#NAME rule whatever exists: table `b.btdb` of the database `a`.
    let out = d.file("a#b.btdb");
    assert_eq!(
        BakeTarget::parse(&out, None, false).unwrap(),
        BakeTarget::db(d.file("a"), "b.btdb")
    );
}

#[test]
fn library_argument_errors_name_settings_not_flags() {
    let errors = [
        "huge".parse::<Preset>().unwrap_err(),
        "polar".parse::<brdftab::table::Param>().unwrap_err(),
        "cubic".parse::<brdftab::table::Interp>().unwrap_err(),
    ];
    for e in errors {
        assert!(matches!(e, Error::InvalidArgument { .. }), "{e}");
        assert!(!e.to_string().contains("--"), "{e}");
    }
}

#[test]
fn fit_reports_its_starts() {
    let src = lambert();
    let init = ModelSpec::parse(r#"{"model": "lambert", "kd": 0.1}"#).unwrap();
    let opts = brdftab::fit::FitOptions {
        pairs: 500,
        starts: 2,
        ..Default::default()
    };
    let log = Log::default();
    brdftab::fit::fit_with_progress(src.as_ref(), &init, &opts, &log).unwrap();
    assert_eq!(log.calls(), ["begin fitting 2", "set 1", "set 2", "end"]);
}

#[test]
fn the_lecture_table_has_a_row_per_model() {
    let t = brdftab::analysis::plausibility::lecture_table();
    for (label, _) in brdftab::analysis::plausibility::LECTURE_MODELS {
        assert!(t.lines().any(|l| l.starts_with(label)), "{label}:\n{t}");
    }
}

#[test]
fn declared_symmetry_is_taken_unverified() {
    use brdftab::bake::SymmetryChoice;
    assert_eq!(
        "declared".parse::<SymmetryChoice>().unwrap(),
        SymmetryChoice::Declared
    );
    let src = lambert();
    let (t, _) = BakeRequest::new(LAMBERT)
        .preset(Preset::Small)
        .symmetry(SymmetryChoice::Declared)
        .table(&Silent)
        .unwrap();
    assert_eq!(
        t.grid().symmetry(),
        brdftab::table::Symmetry::from_flags(src.flags())
    );
}

/// A delta lobe — a mirror alone, or a mirror term of a sum — has no f_r values to tabulate:
/// every bake and conversion refuses it before writing anything (a sum's table silently held
/// its smooth terms only, and a mirror written as a MERL file was zeros).
#[test]
fn sources_with_a_delta_lobe_are_refused_by_every_bake_and_conversion() {
    use brdftab::request::{self, BakeSettings, ConvertSettings};
    let dir = TempDir::new("delta-bakes");
    let sources = [
        r#"{"model": "mirror", "fresnel": {"conductor": "Au"}}"#,
        r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2}, {"model": "mirror"}]}"#,
        r#"{"model": "sum", "terms": [{"model": "ggx", "alpha": 0.2}, {"model": "refractor", "eta": 1.5}]}"#,
    ];
    for src in sources {
        let unsupported = |what: &str, r: Result<(), Error>| {
            assert!(
                matches!(r, Err(Error::Unsupported(ref m)) if m.contains("delta")),
                "{what} of {src}: {r:?}"
            )
        };
        let adaptive: BakeSettings = request::from_json(r#"{"target_error": 0.01}"#).unwrap();
        for (name, settings) in [
            ("bake", BakeSettings::default()),
            ("adaptive bake", adaptive),
        ] {
            let out = dir.join("t.btdb");
            let r = request::bake(src, out.to_str().unwrap(), &settings, &Silent);
            unsupported(name, r.map(|_| ()));
            assert!(!out.exists());
        }
        for ext in ["btdb", "bsdf", "binary"] {
            let out = dir.join(format!("c.{ext}"));
            let r = request::convert(
                src,
                out.to_str().unwrap(),
                &ConvertSettings::default(),
                &Silent,
            );
            unsupported(ext, r.map(|_| ()));
            assert!(!out.exists(), "{ext}");
        }
        let b = ModelSpec::parse(src)
            .unwrap()
            .build(&Channels::Rgb)
            .unwrap();
        unsupported(
            "in memory",
            BakeRequest::new(src)
                .table_of(b.as_ref(), &Silent)
                .map(|_| ()),
        );
    }
}

#[test]
fn an_opened_source_is_shared_between_threads_as_an_arc() {
    // What a renderer holding materials in `Arc<dyn Brdf>` writes.
    let opened = brdftab::open(r#"{"model": "lambert", "kd": 0.25}"#).unwrap();
    let shared: std::sync::Arc<dyn brdftab::Brdf + Send + Sync> = opened.into();
    let shared: std::sync::Arc<dyn brdftab::Brdf> = shared;
    let other = std::sync::Arc::clone(&shared);
    let wi = glam::DVec3::new(0.0, 0.6, 0.8);
    let f = std::thread::spawn(move || {
        let mut out = [0.0f32; 3];
        other.eval(wi, wi, &mut out);
        out
    })
    .join()
    .unwrap();
    assert_eq!(f, [0.25; 3]);
}
