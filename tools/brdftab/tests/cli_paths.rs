//! SOURCE arguments whose file names are not UTF-8 (session 41): `bake`, `convert`, `eval`,
//! `db add`, `albedo`, `check`, `sample`, `pdf`, `slice` and `fit` pass them to the library as the bytes they are (they were refused by the argument
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

/// The other commands that read a SOURCE and nothing else: `albedo`, `check`, `sample`, `pdf`,
/// `slice` and `fit` open a Lambertian spec file whose name is not UTF-8 (the argument parser
/// refused it before: exit 2 with "invalid UTF-8"), and give what they give for the same
/// file under a UTF-8 name.
#[test]
fn the_reading_commands_take_a_source_whose_name_is_not_utf8() {
    let d = TempDir::new("cli-non-utf8-read");
    let spec = r#"{"model": "lambert", "kd": 0.25}"#;
    let (odd, plain) = (latin1(&d, "m.json"), d.path().join("m.json"));
    std::fs::write(&odd, spec).unwrap();
    std::fs::write(&plain, spec).unwrap();
    let s = |x: &str| OsString::from(x);
    let exr = d.path().join("slice.exr").to_string_lossy().into_owned();
    let cases: [(&[&str], &str); 6] = [
        (&["albedo", "@", "--theta", "0,60"], ""),
        (&["check", "@"], ""),
        (&["sample", "@", "--wo", "0.3,0,1", "--count", "2"], ""),
        (&["pdf", "@"], "0 0 1 0.6 0 0.8\n"),
        (&["slice", "@", "-o", &exr, "--size", "16"], ""),
        (&["fit", "@", "--model", "lambert", "--starts", "1"], ""),
    ];
    for (args, stdin) in cases {
        let with = |src: &PathBuf| -> Vec<OsString> {
            let a = args.iter();
            a.map(|&x| {
                if x == "@" {
                    src.clone().into_os_string()
                } else {
                    s(x)
                }
            })
            .collect()
        };
        let (a, b) = (with(&odd), with(&plain));
        let r = brdftab_os(&a.iter().map(|x| x.as_os_str()).collect::<Vec<_>>(), stdin);
        let want = brdftab_os(&b.iter().map(|x| x.as_os_str()).collect::<Vec<_>>(), stdin);
        assert!(want.ok, "{args:?}: {}", want.stderr);
        assert!(r.ok, "{args:?}: exit {}: {}", r.code, r.stderr);
        // Outputs that echo the source name show it lossily; the values agree.
        let lossy = r.stdout.replace("caf\u{FFFD}-m.json", "m.json");
        let want_out = want
            .stdout
            .replace(&d.path().to_string_lossy().to_string(), "");
        let got_out = lossy.replace(&d.path().to_string_lossy().to_string(), "");
        assert_eq!(got_out, want_out, "{args:?}");
    }
}
