//! A SOURCE is an `OsStr` (session 41): on Linux a file name is bytes, and a file whose name is
//! not UTF-8 opens, bakes and converts as any other — each kind, and `DB#NAME` of a database
//! whose path is not UTF-8. Until then every entry point took `&str`: such a file could not be
//! named at all (the CLI refused the argument, Python raised ValueError, the C ABI returned
//! NULL with "`source` is not valid UTF-8"). Every output and every other path (session 42):
//! `request::{bake, convert, save_table, import_npy}` write to `DB#NAME` or a file whose path is
//! not UTF-8, `BakeTarget` holds a path, `store::info` and `measured::info` read such files, and
//! the cache of baked tables lives in such a directory.
#![cfg(all(unix, not(target_vendor = "apple")))]
// Apple's file systems refuse a file name that is not UTF-8 (APFS: EILSEQ), so these files
// cannot be made there; the byte handling itself is the other Unixes'.

use std::ffi::{OsStr, OsString};
use std::os::unix::ffi::{OsStrExt, OsStringExt};
use std::path::{Path, PathBuf};

use brdftab::bake::{BakeRequest, BakeTarget};
use brdftab::progress::Silent;
use brdftab::request::{self, ConvertSettings};
use brdftab::source::{SourceKind, classify};
use brdftab::table::presets::Preset;
use brdftab::testkit::TempDir;
use brdftab::{Error, Result};
use glam::DVec3;

const LAMBERT: &str = r#"{"model": "lambert", "kd": [0.1, 0.2, 0.3]}"#;

/// `dir/` + `caf\xE9-` (Latin-1 é: not UTF-8) + `rest`.
fn latin1(dir: &Path, rest: &str) -> PathBuf {
    let mut name = b"caf\xe9-".to_vec();
    name.extend_from_slice(rest.as_bytes());
    let p = dir.join(OsString::from_vec(name));
    assert!(p.to_str().is_none(), "the name must not be UTF-8");
    p
}

/// `path` + `#name`, as bytes.
fn db_name(path: &Path, name: &str) -> OsString {
    let mut s = path.as_os_str().to_owned();
    s.push("#");
    s.push(name);
    s
}

fn eval(source: impl AsRef<OsStr>) -> Result<Vec<f32>> {
    let b = brdftab::open(source)?;
    let mut f = vec![0.0; b.channels().len()];
    b.eval(DVec3::new(0.6, 0.0, 0.8), DVec3::Z, &mut f);
    Ok(f)
}

fn small(source: impl AsRef<OsStr>) -> BakeRequest {
    BakeRequest::new(source).preset(Preset::Small)
}

#[test]
fn every_kind_opens_from_a_name_that_is_not_utf8() {
    let d = TempDir::new("non-utf8-open");
    let want = eval(LAMBERT).unwrap();

    // A spec file.
    let spec = latin1(d.path(), "matte.json");
    std::fs::write(&spec, LAMBERT).unwrap();
    assert_eq!(classify(&spec), SourceKind::Spec);
    assert_eq!(eval(&spec).unwrap(), want);

    // A table file, and a table of a database whose path is not UTF-8 (`DB#NAME` split on
    // its bytes); written under UTF-8 names (outputs are strings), renamed.
    let tmp = d.join("t.btdb");
    small(LAMBERT)
        .run(&BakeTarget::file(tmp.to_str().unwrap()))
        .unwrap();
    let table = latin1(d.path(), "matte.btdb");
    std::fs::rename(&tmp, &table).unwrap();
    assert_eq!(classify(&table), SourceKind::Table);
    let from_table = eval(&table).unwrap();
    assert_eq!(from_table, eval(tmp_db(&d, "t2.btdb", "matte").1).unwrap());
    let (db, _) = tmp_db(&d, "lib.btdb", "matte");
    let db_latin1 = latin1(d.path(), "lib.btdb");
    std::fs::rename(&db, &db_latin1).unwrap();
    let entry = db_name(&db_latin1, "matte");
    assert_eq!(classify(&entry), SourceKind::Table);
    assert_eq!(eval(&entry).unwrap(), from_table);
    // The same through the request layer's open, eager.
    let settings = request::OpenSettings {
        eager: Some(true),
        ..Default::default()
    };
    assert!(request::open(&entry, &settings).unwrap().health().is_ok());

    // A MERL file (written from the model) and an RGL file (a shipped one, copied).
    let merl = latin1(d.path(), "matte.binary");
    let model = brdftab::open(LAMBERT).unwrap();
    brdftab::measured::MerlBrdf::from_brdf(model.as_ref())
        .write(&merl)
        .unwrap();
    assert_eq!(classify(&merl), SourceKind::Merl);
    for (a, b) in eval(&merl).unwrap().iter().zip(&want) {
        // MERL stores f64 cell values scaled per channel: well within 1e-3 for a constant.
        assert!((a - b).abs() <= 1e-3 * b, "{a} vs {b}");
    }
    let rgl = latin1(d.path(), "paper.bsdf");
    let shipped = brdftab::measured::data::rgl_file("paper_white_rgb.bsdf").unwrap();
    std::fs::copy(&shipped, &rgl).unwrap();
    assert_eq!(classify(&rgl), SourceKind::Rgl);
    assert_eq!(eval(&rgl).unwrap(), eval(&shipped).unwrap());
}

/// A database `dir/file` holding table `name` baked from [`LAMBERT`]; its path and `DB#NAME`.
fn tmp_db(d: &TempDir, file: &str, name: &str) -> (PathBuf, OsString) {
    let p = d.join(file);
    small(LAMBERT)
        .run(&BakeTarget::db(p.to_str().unwrap(), name))
        .unwrap();
    let s = db_name(&p, name);
    (p, s)
}

#[test]
fn bake_and_convert_read_a_source_whose_name_is_not_utf8() {
    let d = TempDir::new("non-utf8-bake");
    let merl = latin1(d.path(), "matte.binary");
    let model = brdftab::open(LAMBERT).unwrap();
    brdftab::measured::MerlBrdf::from_brdf(model.as_ref())
        .write(&merl)
        .unwrap();

    // bake: the table evaluates as the file does; the provenance names the file (lossily:
    // a table header is JSON text), with the file's SHA-256.
    let out = d.join("baked.btdb");
    let r = small(&merl)
        .run(&BakeTarget::file(out.to_str().unwrap()))
        .unwrap();
    assert_eq!(r.info["source"]["file"], "caf\u{FFFD}-matte.binary");
    let (a, b) = (eval(&out).unwrap(), eval(&merl).unwrap());
    for (a, b) in a.iter().zip(&b) {
        assert!((a - b).abs() <= 2e-3 * b, "{a} vs {b}");
    }
    // The default table name is the file's stem, lossily.
    assert_eq!(brdftab::bake::source_stem(&merl), "caf\u{FFFD}-matte");

    // convert, to a database entry and to an RGL file, through the request layer.
    let settings = ConvertSettings {
        pairs: Some(0),
        ..Default::default()
    };
    let lib = d.join("lib.btdb");
    let lib = lib.to_str().unwrap();
    request::convert(&merl, format!("{lib}#m"), &settings, &Silent).unwrap();
    assert_eq!(eval(format!("{lib}#m")).unwrap(), a);
    let bsdf = d.join("m.bsdf");
    request::convert(&merl, bsdf.to_str().unwrap(), &settings, &Silent).unwrap();
    assert!(eval(&bsdf).is_ok());

    // The source is never overwritten by its own bake, whatever its name (here reached
    // through a link of a UTF-8 name, the output).
    let src = latin1(d.path(), "t.btdb");
    std::fs::copy(&out, &src).unwrap();
    let link = d.join("link.btdb");
    std::os::unix::fs::symlink(&src, &link).unwrap();
    match small(&src).run(&BakeTarget::file(link.to_str().unwrap())) {
        Err(Error::InvalidArgument { name, msg }) => {
            assert_eq!(name, "output");
            assert!(msg.contains("caf\u{FFFD}-t.btdb"), "{msg}");
        }
        r => panic!("{:?}", r.map(|r| r.output)),
    }
}

#[test]
fn errors_show_a_name_that_is_not_utf8_lossily() {
    let d = TempDir::new("non-utf8-errors");
    let missing = latin1(d.path(), "missing.btdb");
    match brdftab::open(&missing) {
        Err(e @ Error::NotFound(_)) => {
            assert!(e.to_string().contains("caf\u{FFFD}-missing.btdb"), "{e}")
        }
        r => panic!("{:?}", r.map(|b| b.describe())),
    }
    // A name after `#` that is not UTF-8 is no table name.
    let db = d.join("lib.btdb");
    let mut s = db.as_os_str().as_bytes().to_vec();
    s.extend_from_slice(b"#caf\xe9");
    match brdftab::open(OsStr::from_bytes(&s)) {
        Err(Error::InvalidArgument { name, msg }) => {
            assert_eq!(name, "source");
            assert!(msg.contains("not UTF-8"), "{msg}");
        }
        r => panic!("{:?}", r.map(|b| b.describe())),
    }
    // Inline JSON must be text.
    match brdftab::open(OsStr::from_bytes(b"{\"model\": \"lambert\", \"kd\": \xe9}")) {
        Err(Error::InvalidArgument { name, .. }) => assert_eq!(name, "source"),
        r => panic!("{:?}", r.map(|b| b.describe())),
    }
}

/// Every output of the request layer, in a directory whose name is not UTF-8: a `.btdb` file and
/// `DB#NAME` (bake, convert, `save_table`, `import_npy`), a raw table, a MERL and an RGL file;
/// `info` of each, whose `file` shows the path lossily. Before session 42 outputs were `&str`
/// (such a path could not be passed), and the cache wrote its table to the lossy name
/// (`caf\u{FFFD}`, a directory that does not exist).
#[test]
fn every_output_is_written_to_a_path_that_is_not_utf8() {
    let d = TempDir::new("non-utf8-out");
    let dir = latin1(d.path(), "dir");
    std::fs::create_dir(&dir).unwrap();
    let settings = request::BakeSettings {
        preset: Some("small".into()),
        ..Default::default()
    };
    let want = eval(LAMBERT).unwrap();
    // Within the log16 codec's 1e-3 (twice over for a table re-encoded from a table).
    let close = |source: &OsStr| {
        for (g, w) in eval(source).unwrap().iter().zip(&want) {
            assert!((g - w).abs() <= 2.1e-3 * w, "{source:?}: {g} vs {w}");
        }
    };
    let (file, lib) = (dir.join("t.btdb"), dir.join("lib.btdb"));
    let r = request::bake(LAMBERT, &file, &settings, &Silent).unwrap();
    assert_eq!(r.written, Some(BakeTarget::file(&file)));
    assert_eq!(r.output, file.display().to_string());
    close(file.as_os_str());
    let r = request::bake(LAMBERT, db_name(&lib, "b"), &settings, &Silent).unwrap();
    assert_eq!(r.written, Some(BakeTarget::db(&lib, "b")));
    assert!(
        r.output.ends_with("caf\u{FFFD}-dir/lib.btdb#b"),
        "{}",
        r.output
    );
    close(&db_name(&lib, "b"));
    assert_eq!(
        BakeTarget::parse(db_name(&lib, "b"), None, true).unwrap(),
        BakeTarget::Db {
            path: lib.clone(),
            name: "b".into(),
            replace: true
        }
    );
    assert_eq!(
        brdftab::source::classify_output(db_name(&lib, "x.bsdf")),
        SourceKind::Table
    );

    // convert: to DB#NAME, a raw table, a MERL and an RGL file.
    let convert = ConvertSettings {
        pairs: Some(0),
        ..Default::default()
    };
    let (raw, merl, bsdf) = (dir.join("t.f32"), dir.join("m.binary"), dir.join("m.bsdf"));
    for out in [db_name(&lib, "c"), raw.clone().into(), merl.clone().into()] {
        request::convert(&file, &out, &convert, &Silent).unwrap();
        close(&out);
    }
    request::convert(LAMBERT, &bsdf, &convert, &Silent).unwrap();
    assert!(eval(&bsdf).is_ok());

    // save_table and import_npy: the values of `t.btdb`, exported and imported beside it.
    let table = brdftab::source::open_table(&file, &Default::default()).unwrap();
    let table = table.to_table().unwrap();
    let save = request::SaveSettings::default();
    request::save_table(&table, db_name(&lib, "s"), other(), &save).unwrap();
    close(&db_name(&lib, "s"));
    let st = brdftab::store::Store::open(&file)
        .unwrap()
        .single()
        .unwrap();
    let npy = dir.join("t.npy");
    brdftab::store::export::npy(&st, &npy, None).unwrap();
    let v = request::import_npy(&npy, db_name(&lib, "s"), db_name(&lib, "i"), &save, true);
    assert_eq!(v.unwrap()["tables"][0]["name"], "i");
    close(&db_name(&lib, "i"));

    // info of each kind: `file` is the path, lossily.
    use brdftab::store::info;
    let shown = |v: serde_json::Value| v["file"].as_str().unwrap_or_default().to_owned();
    assert_eq!(
        shown(info::file_info(&file).unwrap()),
        file.display().to_string()
    );
    let v = info::file_info(db_name(&lib, "c")).unwrap();
    assert_eq!(
        (shown(v.clone()), &v["tables"][0]["name"]),
        (lib.display().to_string(), &"c".into())
    );
    assert_eq!(info::list(&lib).unwrap().len(), 4);
    assert_eq!(info::table_info(&lib, "b").unwrap()["name"], "b");
    assert_eq!(
        shown(info::table_file_info(&raw).unwrap().0),
        raw.display().to_string()
    );
    for m in [&merl, &bsdf] {
        assert_eq!(
            shown(brdftab::measured::info::info(m).unwrap()),
            m.display().to_string()
        );
        let text = brdftab::measured::info::describe(m).unwrap();
        assert!(text.contains("caf\u{FFFD}-dir"), "{text}");
    }

    // The cache of baked tables in such a directory: baked there, then found there.
    let cache = dir.join("cache");
    let c = brdftab::cache::bake_cached(LAMBERT, &settings, Some(&cache), false).unwrap();
    assert!(
        !c.hit && c.path.starts_with(&cache) && c.path.is_file(),
        "{:?}",
        c.path
    );
    close(c.path.as_os_str());
    let again = brdftab::cache::bake_cached(&file, &settings, Some(&cache), false).unwrap();
    assert!(!again.hit && again.path != c.path);
    assert!(
        brdftab::cache::bake_cached(&file, &settings, Some(&cache), false)
            .unwrap()
            .hit
    );
}

fn other() -> brdftab::store::Source {
    brdftab::store::Source::Other {
        description: "values".into(),
    }
}
