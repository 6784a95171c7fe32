//! Paths whose names are not UTF-8. SOURCE arguments (session 41): `bake`, `convert`, `eval`,
//! `db add`, `albedo`, `check`, `sample`, `pdf`, `slice` and `fit` pass them to the library as
//! the bytes they are (they were refused by the argument parser: "invalid UTF-8 was detected in
//! one or more arguments"), and errors show them lossily. Every other path (session 42): the
//! outputs of `bake`, `convert`, `slice`, `render`, `export` and `import`, the databases of
//! `db`, the SOURCEs of `info`, `render`, `bench`, `export`, `import --like` and `view`,
//! `render --env FILE.exr`, and `demo --out`/`--rgl`.
#![cfg(all(unix, not(target_vendor = "apple")))]
// Apple's file systems refuse a file name that is not UTF-8 (APFS: EILSEQ), so these files
// cannot be made there; the byte handling itself is the other Unixes'.

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

/// `args` with each `@` replaced by the directory `d` (bytes that are not UTF-8) and the text
/// after it: `@/t.btdb` is `d/t.btdb`.
fn in_dir(d: &std::path::Path, args: &[&str]) -> Vec<OsString> {
    args.iter()
        .map(|a| match a.strip_prefix('@') {
            Some(rest) => {
                let mut p = d.as_os_str().to_owned();
                p.push(rest);
                p
            }
            None => OsString::from(a),
        })
        .collect()
}

fn run_in(d: &std::path::Path, args: &[&str]) -> Run {
    let a = in_dir(d, args);
    let r = brdftab_os(&a.iter().map(|x| x.as_os_str()).collect::<Vec<_>>(), "");
    assert!(r.ok, "{args:?}: exit {}: {}", r.code, r.stderr);
    r
}

/// Every command writes its outputs into, and reads its inputs from, a directory whose name is
/// not UTF-8 (`caf\xE9`); what it prints shows the name with U+FFFD. Before session 42 the
/// argument parser refused every one of these paths (exit 2, "invalid UTF-8 was detected"), but
/// for SOURCEs of the commands above.
#[test]
fn every_output_and_every_command_takes_paths_whose_names_are_not_utf8() {
    let t = TempDir::new("cli-non-utf8-out");
    let d = latin1(&t, "dir");
    std::fs::create_dir(&d).unwrap();
    let shown = format!("{}", d.display());
    assert!(shown.contains("caf\u{FFFD}-dir"), "{shown}");
    let spec = r#"{"model": "lambert", "kd": 0.25}"#;
    let exists = |f: &str| in_dir(&d, &[f])[0].clone();
    let exists = |f: &str| assert!(PathBuf::from(exists(f)).is_file(), "{f} missing");

    // Outputs: a table file, a database entry, a database of `db add`, raw, MERL and RGL files.
    run_in(&d, &["bake", spec, "-o", "@/t.btdb", "--preset", "small"]);
    run_in(
        &d,
        &["bake", spec, "-o", "@/lib.btdb#m", "--preset", "small"],
    );
    run_in(
        &d,
        &[
            "db",
            "add",
            "@/lib.btdb",
            spec,
            "--name",
            "n",
            "--preset",
            "small",
        ],
    );
    run_in(&d, &["convert", "@/t.btdb", "@/lib.btdb#c", "--pairs", "0"]);
    run_in(&d, &["convert", "@/t.btdb", "@/t.f32", "--pairs", "0"]);
    run_in(&d, &["convert", spec, "@/x.binary", "--pairs", "0"]);
    let r = run_in(
        &d,
        &[
            "convert",
            spec,
            "@/x.bsdf",
            "--resolution",
            "8",
            "--theta-i",
            "3",
            "--phi-i",
            "1",
        ],
    );
    assert!(
        r.stderr.contains(&format!("{shown}/x.bsdf")),
        "{}",
        r.stderr
    );
    for f in [
        "@/t.btdb",
        "@/lib.btdb",
        "@/t.f32",
        "@/x.binary",
        "@/x.bsdf",
    ] {
        exists(f);
    }
    // What was written holds the spec's constant f_r (0.25, as `eval` of the spec gives it):
    // within log16's 1e-3, twice over for the table converted from a table (the raw f32 file
    // and the MERL file's cell means of a constant, in doubles, are well within that).
    for source in [
        "@/lib.btdb#m",
        "@/lib.btdb#n",
        "@/lib.btdb#c",
        "@/t.f32",
        "@/x.binary",
    ] {
        let a = in_dir(&d, &["eval", source]);
        let a: Vec<&OsStr> = a.iter().map(|x| x.as_os_str()).collect();
        let r = brdftab_os(&a, "0.6 0 0.8 0 0 1\n");
        assert!(r.ok, "{source}: {}", r.stderr);
        for v in r.stdout.split_whitespace() {
            let v: f64 = v.parse().unwrap();
            let want = 0.25;
            assert!((v - want).abs() <= 2.1e-3 * want, "{source}: {v} vs {want}");
        }
    }

    // The databases of `db`.
    let r = run_in(&d, &["db", "list", "@/lib.btdb"]);
    for name in ["m", "n", "c"] {
        assert!(r.stdout.contains(&format!("{name} ")), "{}", r.stdout);
    }
    run_in(&d, &["db", "rename", "@/lib.btdb", "n", "n2"]);
    let r = run_in(&d, &["db", "rm", "@/lib.btdb", "n2"]);
    assert!(
        r.stderr.contains(&format!("{shown}/lib.btdb")),
        "{}",
        r.stderr
    );
    let r = run_in(&d, &["db", "verify", "@/lib.btdb"]);
    assert!(
        r.stdout.starts_with(&format!("ok: {shown}/lib.btdb")),
        "{}",
        r.stdout
    );

    // `info` of every kind; JSON names the file lossily.
    for f in [
        "@/t.btdb",
        "@/lib.btdb#c",
        "@/t.f32",
        "@/x.binary",
        "@/x.bsdf",
    ] {
        let r = run_in(&d, &["info", f]);
        assert!(r.stdout.contains("caf\u{FFFD}-dir"), "{f}: {}", r.stdout);
        let r = run_in(&d, &["info", "--json", f]);
        let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
        let file = v["file"].as_str().unwrap_or_default();
        assert!(file.starts_with(&shown), "{f}: {file}");
    }
    let r = run_in(&d, &["info", "--json", "@/lib.btdb#m"]);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v["tables"][0]["name"], "m");

    // `export` and `import`, `render` (with --compare), `slice` and `bench`.
    run_in(
        &d,
        &[
            "export", "@/t.btdb", "--npy", "@/t.npy", "--exr", "@/t.exr", "--slice", "0,2",
        ],
    );
    run_in(
        &d,
        &[
            "import",
            "@/t.npy",
            "--like",
            "@/lib.btdb#m",
            "-o",
            "@/u.btdb",
        ],
    );
    let render = [
        "render", "@/t.btdb", "-o", "@/r.png", "--size", "8x8", "--spp", "1", "--mode", "lit",
    ];
    run_in(&d, &render);
    run_in(&d, &[&render[..], &["--compare", "@/lib.btdb#m"]].concat());
    // An image of it as the environment of another render (a lat-long `--env FILE.exr`).
    run_in(
        &d,
        &[
            &render[..2],
            &["-o", "@/env.exr", "--size", "16x8", "--mode", "lit"],
        ]
        .concat(),
    );
    run_in(&d, &[&render[..], &["--env", "@/env.exr"]].concat());
    run_in(&d, &["slice", "@/u.btdb", "-o", "@/s.png", "--size", "16"]);
    for f in [
        "@/t.npy",
        "@/t.exr",
        "@/u.btdb",
        "@/r.png",
        "@/r-diff.png",
        "@/s.png",
    ] {
        exists(f);
    }
    let r = run_in(&d, &["bench", "@/u.btdb", "--pairs", "1000"]);
    assert!(r.stdout.contains("caf\u{FFFD}-dir/u.btdb"), "{}", r.stdout);

    // `view` of the database: its two tables.
    let a = in_dir(&d, &["view", "@/lib.btdb", "--port", "0"]);
    let mut child = command(&[])
        .args(&a)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    let read = std::io::BufRead::read_line(
        &mut std::io::BufReader::new(child.stdout.take().unwrap()),
        &mut line,
    );
    let _ = child.kill();
    let _ = child.wait();
    read.unwrap();
    assert!(line.starts_with("brdftab view: 2 materials at"), "{line:?}");

    // A missing file: an error naming it lossily, exit 1.
    for args in [
        &["info", "@/none.btdb"][..],
        &["export", "@/none.btdb", "--npy", "@/n.npy"],
        &["db", "list", "@/none.btdb"],
    ] {
        let a = in_dir(&d, args);
        let r = brdftab_os(&a.iter().map(|x| x.as_os_str()).collect::<Vec<_>>(), "");
        assert_eq!(r.code, 1, "{args:?}: {}", r.stderr);
        assert!(
            r.stderr.starts_with("error:") && r.stderr.contains("caf\u{FFFD}-dir/none.btdb"),
            "{args:?}: {}",
            r.stderr
        );
    }
}

/// `demo --out DIR --rgl DIR` with directories whose names are not UTF-8: the database was
/// written to the lossy name (`caf\u{FFFD}`, a directory that does not exist: exit 1) and the RGL
/// files were opened by it ("no such file").
#[test]
fn demo_writes_into_and_reads_from_directories_whose_names_are_not_utf8() {
    let t = TempDir::new("cli-non-utf8-demo");
    let (out, rgl) = (latin1(&t, "out"), latin1(&t, "rgl"));
    std::fs::create_dir(&rgl).unwrap();
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/rgl");
    std::fs::copy(
        data.join("paper_white_rgb.bsdf"),
        rgl.join("paper_white_rgb.bsdf"),
    )
    .unwrap();
    let s = |x: &str| OsString::from(x);
    let args = [
        s("demo"),
        s("--quick"),
        s("--preset"),
        s("small"),
        s("--out"),
        out.clone().into_os_string(),
        s("--rgl"),
        rgl.into_os_string(),
    ];
    let r = brdftab_os(&args.iter().map(|x| x.as_os_str()).collect::<Vec<_>>(), "");
    assert!(r.ok, "exit {}: {}", r.code, r.stderr);
    assert!(r.stdout.contains("rgl_paper_white"), "{}", r.stdout);
    assert!(out.join("demo.btdb").is_file());
}
