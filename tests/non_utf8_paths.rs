//! A SOURCE is an `OsStr` (session 41): on Linux a file name is bytes, and a file whose name is
//! not UTF-8 opens, bakes and converts as any other — each kind, and `DB#NAME` of a database
//! whose path is not UTF-8. Until then every entry point took `&str`: such a file could not be
//! named at all (the CLI refused the argument, Python raised ValueError, the C ABI returned
//! NULL with "`source` is not valid UTF-8").
#![cfg(unix)]

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
    request::convert(&merl, &format!("{lib}#m"), &settings, &Silent).unwrap();
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
