//! `brdftab import` end to end: a table exported with `export --npy`, its array edited in the
//! test (as a user edits it in numpy), imported on the table's grid, and evaluated.

mod common;

use brdftab::store::npy::{npy_header, read_f32};
use brdftab::testkit::TempDir;
use common::{Run, brdftab, brdftab_with_stdin};

/// Direction pairs `wix wiy wiz wox woy woz`, above the horizon, one per line.
const PAIRS: &str = "0 0 1 0 0 1\n0.5 0 0.866 -0.5 0 0.866\n0.3 0.2 0.93 -0.25 0.1 0.96\n\
                     0.8 0.1 0.59 0.1 -0.7 0.7\n-0.6 0.3 0.74 0.55 0.4 0.73\n";

fn ok(r: Run) -> Run {
    assert!(r.ok, "{}", r.stderr);
    r
}

/// f_r of `source` at [`PAIRS`], every channel of every pair.
fn eval(source: &str) -> Vec<f32> {
    ok(brdftab_with_stdin(&["eval", source], PAIRS))
        .stdout
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect()
}

/// Writes `values` as a float32 `.npy` of `shape` (the library's header, as the export writes).
fn write_npy(path: &str, shape: &[usize], values: &[f32]) {
    let shape: Vec<u64> = shape.iter().map(|&d| d as u64).collect();
    let mut b = npy_header(&shape);
    b.extend(values.iter().flat_map(|x| x.to_le_bytes()));
    std::fs::write(path, b).unwrap();
}

/// A refused import: exit status 1 and one `error: ...` message holding `words`.
fn refused(args: &[String], words: &str) {
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let r = brdftab(&args);
    assert_eq!(r.code, 1, "{args:?}: {}", r.stderr);
    assert!(
        r.stderr.starts_with("error: ") && r.stderr.contains(words),
        "{args:?}: {}",
        r.stderr
    );
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
}

/// Doubling every stored value doubles every lookup exactly (each step of a lookup is linear,
/// and multiplying by 2 is exact in binary floating point), through export, import and the
/// lossless codec.
#[test]
fn an_edited_export_imports_and_evaluates_scaled() {
    let d = TempDir::new("cli-import");
    let p = |f: &str| d.file(f);
    let ct = r#"{"model": "cook_torrance", "m": 0.3}"#;
    ok(brdftab(&[
        "bake",
        ct,
        "-o",
        &p("ct.btdb"),
        "--preset",
        "small",
        "--codec",
        "f32",
    ]));
    ok(brdftab(&["export", &p("ct.btdb"), "--npy", &p("ct.npy")]));
    let (shape, values) = read_f32(p("ct.npy")).unwrap();
    assert_eq!(shape.len(), 5);
    let doubled: Vec<f32> = values.iter().map(|x| 2.0 * x).collect();
    write_npy(&p("ct2.npy"), &shape, &doubled);
    let r = ok(brdftab(&[
        "import",
        &p("ct2.npy"),
        "--like",
        &p("ct.btdb"),
        "-o",
        &p("ct2.btdb"),
        "--codec",
        "f32",
    ]));
    let line = format!(
        "wrote {} ({} values, codec f32)\n",
        p("ct2.btdb"),
        values.len()
    );
    assert_eq!(r.stderr, line);
    let (a, b) = (eval(&p("ct.btdb")), eval(&p("ct2.btdb")));
    assert_eq!(a.len(), 15);
    assert!(a.iter().all(|&x| x > 0.0), "{a:?}");
    assert_eq!(b, a.iter().map(|x| 2.0 * x).collect::<Vec<_>>());
    // The provenance says where the values came from.
    let r = ok(brdftab(&["info", &p("ct2.btdb"), "--json"]));
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    let want = format!("values from ct2.npy on the grid of {}", p("ct.btdb"));
    assert_eq!(v["tables"][0]["source"]["description"], want.as_str());

    // Into a database: an existing name needs --replace.
    let entry = format!("{}#scaled", p("lib.btdb"));
    let (ct2, like) = (p("ct2.npy"), p("ct.btdb"));
    let import = |extra: &[&str]| {
        let mut args = vec!["import", &ct2, "--like", &like, "-o", &entry];
        args.extend_from_slice(extra);
        brdftab(&args)
    };
    ok(import(&["--codec", "f32"]));
    let r = import(&["--codec", "f32"]);
    assert!(!r.ok && r.stderr.contains("--replace"), "{}", r.stderr);
    ok(import(&["--codec", "f32", "--replace"]));
    assert_eq!(eval(&entry), b);
}

/// `--no-calibration`: another material's values on a calibrated table's grid are stored
/// without that table's albedo factors (measured for its own values); without the flag the
/// import keeps them.
#[test]
fn no_calibration_drops_the_like_tables_factors() {
    let d = TempDir::new("cli-import-cal");
    let p = |f: &str| d.file(f);
    let ggx = r#"{"model": "ggx", "alpha": 0.3}"#;
    let like = p("g.btdb");
    ok(brdftab(&[
        "bake",
        ggx,
        "-o",
        &like,
        "--grid",
        "adaptive:24x12x7",
    ]));
    ok(brdftab(&["export", &like, "--npy", &p("g.npy")]));
    let calibrated = |f: &str| {
        let r = ok(brdftab(&["info", f, "--json"]));
        let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
        v["tables"][0]["calibrated"].as_bool().unwrap()
    };
    assert!(calibrated(&like));
    let npy = p("g.npy");
    for (extra, want) in [(None, true), (Some("--no-calibration"), false)] {
        let out = p(&format!("out-{want}.btdb"));
        let mut args = vec!["import", &npy, "--like", &like, "-o", &out];
        args.extend(extra);
        ok(brdftab(&args));
        assert_eq!(calibrated(&out), want, "{extra:?}");
    }
}

/// A packed table (`inout` reciprocal: θi ≤ θo stored) exports its whole rectangle with NaN at
/// the nodes it does not store; imported as it is, they are ignored and the table is the same.
#[test]
fn a_packed_tables_export_imports_as_it_was() {
    let d = TempDir::new("cli-import-packed");
    let p = |f: &str| d.file(f);
    let phong = r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 5}"#;
    let r = ok(brdftab(&[
        "bake",
        phong,
        "-o",
        &p("t.btdb"),
        "--grid",
        "16x1x16x32",
        "--param",
        "inout",
        "--symmetry",
        "isotropic,reciprocal",
        "--codec",
        "f32",
    ]));
    assert!(r.stderr.contains("inout"), "{}", r.stderr);
    ok(brdftab(&["export", &p("t.btdb"), "--npy", &p("t.npy")]));
    let (_, values) = read_f32(p("t.npy")).unwrap();
    assert!(
        values.iter().any(|x| x.is_nan()),
        "a packed export has unstored nodes"
    );
    ok(brdftab(&[
        "import",
        &p("t.npy"),
        "--like",
        &p("t.btdb"),
        "-o",
        &p("back.btdb"),
        "--codec",
        "f32",
    ]));
    assert_eq!(eval(&p("back.btdb")), eval(&p("t.btdb")));
}

#[test]
fn bad_imports_exit_1_with_an_error() {
    let d = TempDir::new("cli-import-bad");
    let p = |f: &str| d.file(f);
    ok(brdftab(&[
        "bake",
        r#"{"model": "lambert", "kd": 0.5}"#,
        "-o",
        &p("l.btdb"),
        "--preset",
        "small",
    ]));
    ok(brdftab(&["export", &p("l.btdb"), "--npy", &p("l.npy")]));
    let (mut shape, values) = read_f32(p("l.npy")).unwrap();
    let (like, out) = (p("l.btdb"), p("out.btdb"));
    let import = |array: &str, like: &str| -> Vec<String> {
        ["import", array, "--like", like, "-o", &out]
            .map(String::from)
            .to_vec()
    };

    shape.swap(1, 3);
    write_npy(&p("wrong.npy"), &shape, &values);
    refused(&import(&p("wrong.npy"), &like), "field `shape`");
    refused(
        &import(&p("l.npy"), r#"{"model": "lambert", "kd": 0.5}"#),
        "invalid argument `--like`",
    );
    refused(&import(&p("l.npy"), &p("none.btdb")), "`--like`");
    let b = std::fs::read(p("l.npy")).unwrap();
    std::fs::write(p("cut.npy"), &b[..b.len() - 5]).unwrap();
    refused(&import(&p("cut.npy"), &like), "truncated");
    std::fs::write(p("text.npy"), "not an array").unwrap();
    refused(&import(&p("text.npy"), &like), "not a .npy file");
    let mut args = import(&p("l.npy"), &like);
    args.extend(["--codec".into(), "zip".into()]);
    refused(&args, "`--codec`");
    assert!(!std::path::Path::new(&out).exists());
}
