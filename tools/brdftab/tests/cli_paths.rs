//! SOURCE arguments whose file names are not UTF-8 (session 41): `bake`, `convert`, `eval` and
//! `db add` pass them to the library as the bytes they are (they were refused by the argument
//! parser: "invalid UTF-8 was detected in one or more arguments"), and errors show them
//! lossily.
#![cfg(unix)]

mod common;

use std::ffi::{OsStr, OsString};
use std::os::unix::ffi::OsStringExt;
use std::path::PathBuf;

use brdftab::testkit::TempDir;
use common::{Run, command, run};

fn brdftab_os(args: &[&OsStr], stdin: &str) -> Run {
    let mut c = command(&[]);
    c.args(args);
    run(c, stdin)
}

/// `dir/caf\xE9-NAME` (Latin-1 é: not UTF-8).
fn latin1(d: &TempDir, name: &str) -> PathBuf {
    let mut b = b"caf\xe9-".to_vec();
    b.extend_from_slice(name.as_bytes());
    d.path().join(OsString::from_vec(b))
}

#[test]
fn bake_convert_eval_and_db_add_take_a_source_whose_name_is_not_utf8() {
    let d = TempDir::new("cli-non-utf8");
    let spec = latin1(&d, "matte.json");
    std::fs::write(&spec, r#"{"model": "lambert", "kd": [0.1, 0.2, 0.3]}"#).unwrap();
    let s = |x: &str| OsString::from(x);
    let (out, lib) = (d.path().join("t.btdb"), d.path().join("lib.btdb"));
    let pair = "0.6 0 0.8 0 0 1\n";

    let r = brdftab_os(
        &[
            &s("bake"),
            spec.as_os_str(),
            &s("-o"),
            out.as_os_str(),
            &s("--preset"),
            &s("small"),
        ],
        "",
    );
    assert!(r.ok, "{}", r.stderr);
    let want = brdftab_os(&[&s("eval"), out.as_os_str()], pair);
    assert!(want.ok && !want.stdout.is_empty(), "{}", want.stderr);
    // The spec file itself (a constant: the table holds it exactly), and the table under a
    // name that is not UTF-8.
    let table = latin1(&d, "t.btdb");
    std::fs::copy(&out, &table).unwrap();
    for source in [&spec, &table] {
        let r = brdftab_os(&[&s("eval"), source.as_os_str()], pair);
        assert_eq!(
            (r.ok, r.stdout.as_str()),
            (true, want.stdout.as_str()),
            "{}",
            r.stderr
        );
    }
    let mut entry = lib.clone().into_os_string();
    entry.push("#m");
    let r = brdftab_os(
        &[
            &s("convert"),
            table.as_os_str(),
            &entry,
            &s("--pairs"),
            &s("0"),
        ],
        "",
    );
    assert!(r.ok, "{}", r.stderr);
    let r = brdftab_os(
        &[
            &s("db"),
            &s("add"),
            lib.as_os_str(),
            spec.as_os_str(),
            &s("--name"),
            &s("n"),
            &s("--preset"),
            &s("small"),
        ],
        "",
    );
    assert!(r.ok, "{}", r.stderr);
    // `n` baked from the spec as `t.btdb` was, `m` re-baked from that table: the model's
    // values within the log16 codec's 1e-3, twice over for `m`.
    for name in ["m", "n"] {
        let mut e = lib.clone().into_os_string();
        e.push(format!("#{name}"));
        let r = brdftab_os(&[&s("eval"), &e], pair);
        assert!(r.ok, "{}", r.stderr);
        let got: Vec<f64> = r
            .stdout
            .split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect();
        assert_eq!(got.len(), 3, "{}", r.stdout);
        for (g, w) in got.iter().zip([0.1, 0.2, 0.3]) {
            assert!((g - w).abs() <= 2.1e-3 * w, "{name}: {g} vs {w}");
        }
    }

    // A missing file: an error naming it lossily, exit 1.
    let missing = latin1(&d, "missing.btdb");
    let r = brdftab_os(&[&s("eval"), missing.as_os_str()], pair);
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert!(
        r.stderr.starts_with("error:") && r.stderr.contains("caf\u{FFFD}-missing.btdb"),
        "{}",
        r.stderr
    );
}
