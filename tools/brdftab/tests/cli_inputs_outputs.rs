//! What the CLI writes: output paths checked before any work, and `export`'s flags.

mod common;

use brdftab::testkit::TempDir;
use common::{Run, brdftab};

const LAMBERT: &str = r#"{"model": "lambert", "kd": 0.5}"#;

/// Exit 1, `error:` first, no panic, nothing on stdout, and every needle in stderr.
fn refused(o: &Run, needles: &[&str]) {
    assert_eq!(o.code, 1, "stderr: {}", o.stderr);
    assert!(o.stderr.starts_with("error:"), "stderr: {}", o.stderr);
    assert!(!o.stderr.contains("panicked"), "stderr: {}", o.stderr);
    assert!(o.stdout.is_empty(), "stdout: {}", o.stdout);
    for n in needles {
        assert!(o.stderr.contains(n), "`{n}` not in: {}", o.stderr);
    }
}

#[test]
fn outputs_are_checked_before_the_work() {
    let d = TempDir::new("io-outputs");
    let gone = d.join("no-such-dir");
    let gone = gone.to_str().unwrap();
    // `render` printed its timing (it had rendered) and only then refused the extension.
    let jpg = d.file("a.jpg");
    let o = brdftab(&["render", LAMBERT, "-o", &jpg, "--size", "8x8", "--spp", "1"]);
    refused(&o, &["`--output`", ".png or .exr"]);
    assert!(!o.stderr.contains(" spp in "), "rendered: {}", o.stderr);
    let png = format!("{gone}/a.png");
    let o = brdftab(&["render", LAMBERT, "-o", &png, "--size", "8x8", "--spp", "1"]);
    refused(&o, &["`--output`", gone, "does not exist"]);
    assert!(!o.stderr.contains(" spp in "), "rendered: {}", o.stderr);
    // `slice` named the library's `output`.
    let o = brdftab(&["slice", LAMBERT, "-o", &jpg, "--size", "8"]);
    refused(&o, &["`--output`", ".exr or .png"]);
    refused(
        &brdftab(&["slice", LAMBERT, "-o", &png, "--size", "8"]),
        &["`--output`", "does not exist"],
    );
    // `export` wrote the .npy and then failed on the --exr's directory.
    let t = d.file("t.btdb");
    assert!(brdftab(&["bake", LAMBERT, "-o", &t, "--preset", "small"]).ok);
    let npy = d.file("t.npy");
    let exr = format!("{gone}/t.exr");
    let o = brdftab(&["export", &t, "--npy", &npy, "--exr", &exr, "--slice", "0,2"]);
    refused(&o, &["`--exr`", "does not exist"]);
    assert!(!std::path::Path::new(&npy).exists(), "the .npy was written");
}

#[test]
fn export_flags_agree_with_what_export_does() {
    let d = TempDir::new("io-export");
    let t = d.file("t.btdb");
    assert!(brdftab(&["bake", LAMBERT, "-o", &t, "--preset", "small"]).ok);
    // EXR bytes went into a .png.
    let png = d.file("a.png");
    refused(
        &brdftab(&["export", &t, "--exr", &png, "--slice", "0,2"]),
        &["`--exr`", ".exr"],
    );
    assert!(!std::path::Path::new(&png).exists());
    // --slice (and --half) are the EXR's: with --npy alone they did nothing.
    let npy = d.file("a.npy");
    refused(
        &brdftab(&["export", &t, "--npy", &npy, "--slice", "0,2"]),
        &["--exr"],
    );
    refused(
        &brdftab(&["export", &t, "--npy", &npy, "--half"]),
        &["--exr"],
    );
    assert!(!std::path::Path::new(&npy).exists());
    // The fixed indices are one per stored axis (four here); fewer were padded with zeros.
    let exr = d.file("a.exr");
    for bad in ["0,2:1", "0,2:0,0,0", "0,2:0,0,0,0,0"] {
        refused(
            &brdftab(&["export", &t, "--exr", &exr, "--slice", bad]),
            &["`--slice`", "of the 4 indices"],
        );
    }
    for good in ["0,2", "0,2:0,0,0,0", "2,0:9,0,9,0"] {
        let o = brdftab(&["export", &t, "--exr", &exr, "--slice", good]);
        assert!(o.ok, "{good}: {}", o.stderr);
    }
    let o = brdftab(&["export", "--help"]);
    assert!(
        o.stdout.contains("an index for every stored axis"),
        "{}",
        o.stdout
    );
    // A table that is itself the --npy output: the refusal names the flag, not `output`.
    let same = d.file("same.npy");
    std::fs::copy(&t, &same).unwrap();
    refused(
        &brdftab(&["export", &same, "--npy", &same]),
        &["`--npy`", "is the input"],
    );
    // The .npy of a table needs a .npy name too.
    refused(&brdftab(&["export", &t, "--npy", &t]), &["`--npy`", ".npy"]);
}

/// `export --half` wrote a value beyond f16's ±65504 (the peak of a sharp lobe) as an infinite
/// pixel without a word; it is refused, and the f32 slice holds the value.
#[test]
fn export_half_refuses_values_beyond_f16() {
    let d = TempDir::new("io-export-half");
    let t = d.file("sharp.btdb");
    let sharp = r#"{"model": "cook_torrance", "m": 0.05}"#;
    assert!(brdftab(&["bake", sharp, "-o", &t, "--preset", "small"]).ok);
    // x = θd, y = θh: row 0 is the θh node nearest the peak.
    let (h, f) = (d.file("h.exr"), d.file("f.exr"));
    refused(
        &brdftab(&["export", &t, "--exr", &h, "--slice", "2,0", "--half"]),
        &["`--half`", "65504", "f32"],
    );
    assert!(!std::path::Path::new(&h).exists());
    let o = brdftab(&["export", &t, "--exr", &f, "--slice", "2,0"]);
    assert!(o.ok, "{}", o.stderr);
    let img = brdftab_tools::preview::read_exr(&f).unwrap();
    let max = img.data.iter().fold(0.0f32, |m, &x| m.max(x));
    assert!(max > 65504.0 && max.is_finite(), "{max}");
    // A slice within the range (θd × φd at the last θh node) is written as half floats still.
    let o = brdftab(&[
        "export",
        &t,
        "--exr",
        &h,
        "--slice",
        "2,3:31,0,0,0",
        "--half",
    ]);
    assert!(o.ok, "{}", o.stderr);
}

/// `export --npy` wrote the stored values, but nothing the CLI prints said where the nodes sit:
/// `info --json` lists every stored axis's node angles (the .npy's axes, in order). Checked
/// against the closed forms of the small halfdiff preset: θh = 90°·((i + ½)/n)² (Sqrt,
/// centres), θd = acos(1 − (i + ½)/n) (Cos, centres), φd = i·360°/64 (folded to 0..90°).
#[test]
fn info_json_places_the_exported_nodes() {
    let d = TempDir::new("io-info-axes");
    let t = d.file("ct.btdb");
    let ct = r#"{"model": "cook_torrance", "m": 0.3}"#;
    assert!(brdftab(&["bake", ct, "-o", &t, "--preset", "small"]).ok);
    let o = brdftab(&["info", &t, "--json"]);
    assert!(o.ok, "{}", o.stderr);
    let v: serde_json::Value = serde_json::from_str(&o.stdout).unwrap();
    let table = &v["tables"][0];
    let axes = table["axes"].as_array().expect("axes");
    let shape = table["shape"].as_array().unwrap();
    assert_eq!(axes.len() + 1, shape.len());
    let deg = |a: usize| -> Vec<f64> {
        let v = axes[a]["degrees"].as_array().unwrap();
        assert_eq!(v.len() as u64, shape[a].as_u64().unwrap(), "axis {a}");
        v.iter().map(|x| x.as_f64().unwrap()).collect()
    };
    let names: Vec<&str> = axes.iter().map(|a| a["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["theta_h", "phi_h", "theta_d", "phi_d"]);
    let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
    let (th, td, fd) = (deg(0), deg(2), deg(3));
    let n = th.len() as f64;
    for (i, x) in th.iter().enumerate() {
        let u = (i as f64 + 0.5) / n;
        assert!(close(*x, 90.0 * u * u), "θh {i}: {x}");
    }
    let n = td.len() as f64;
    for (i, x) in td.iter().enumerate() {
        let u = (i as f64 + 0.5) / n;
        assert!(close(*x, (1.0 - u).acos().to_degrees()), "θd {i}: {x}");
    }
    for (i, x) in fd.iter().enumerate() {
        assert!(close(*x, i as f64 * 360.0 / 64.0), "φd {i}: {x}");
    }
    assert!(close(*fd.last().unwrap(), 90.0));
    assert_eq!(axes[0]["mapping"], "Sqrt");
    assert_eq!(axes[2]["nodes"], "centers");
}

/// A missing input was "not found: x.btdb: no such file" to `eval` but "x.btdb: No such file or
/// directory (os error 2)" to `info`, `db`, `export`, `check` (and `x.btdb#t: ...` to `info`,
/// naming a file that nobody asked for). Every command and every kind of file now say it alike,
/// from the library's one check before every open.
#[test]
fn a_missing_input_is_reported_alike_by_every_command() {
    let d = TempDir::new("io-missing");
    let (btdb, bsdf, binary, json, npy) = (
        d.file("m.btdb"),
        d.file("m.bsdf"),
        d.file("m.binary"),
        d.file("m.json"),
        d.file("m.npy"),
    );
    let table = format!("{btdb}#t");
    let out = d.file("o.btdb");
    let like = d.file("like.btdb");
    assert!(brdftab(&["bake", LAMBERT, "-o", &like, "--preset", "small"]).ok);
    let runs: Vec<(Vec<&str>, &str)> = vec![
        (vec!["eval", &btdb], &btdb),
        (vec!["eval", &table], &btdb),
        (vec!["eval", &bsdf], &bsdf),
        (vec!["eval", &binary], &binary),
        (vec!["eval", &json], &json),
        (vec!["info", &btdb], &btdb),
        (vec!["info", &table], &btdb),
        (vec!["info", &bsdf], &bsdf),
        (vec!["info", &binary], &binary),
        (vec!["db", "list", &btdb], &btdb),
        (vec!["db", "verify", &btdb], &btdb),
        (vec!["db", "rm", &btdb, "t"], &btdb),
        (vec!["export", &table, "--npy", &npy], &btdb),
        (vec!["check", &bsdf], &bsdf),
        (vec!["albedo", &table], &btdb),
        (vec!["bake", &binary, "-o", &out], &binary),
        (vec!["convert", &bsdf, &out], &bsdf),
        (vec!["import", &npy, "--like", &like, "-o", &out], &npy),
    ];
    for (args, file) in runs {
        let o = common::brdftab_with_stdin(&args, "0 0 1 0 0 1\n");
        refused(&o, &[]);
        assert_eq!(
            o.stderr,
            format!("error: not found: {file}: no such file\n"),
            "{args:?}"
        );
    }
}

/// `info` and `export` named their SOURCE by the library's setting, `source`, where every other
/// command says `SOURCE` (the name their usage line shows): `export 'x.btdb#'` said "invalid
/// argument `source`", `eval 'x.btdb#'` "invalid argument `SOURCE`".
#[test]
fn every_command_names_its_source_alike() {
    let d = TempDir::new("io-source-name");
    let t = d.file("t.btdb");
    assert!(brdftab(&["bake", LAMBERT, "-o", &t, "--preset", "small"]).ok);
    let empty = format!("{t}#");
    let npy = d.file("t.npy");
    for args in [
        vec!["eval", &empty],
        vec!["info", &empty],
        vec!["export", &empty, "--npy", &npy],
    ] {
        let o = common::brdftab_with_stdin(&args, "0 0 1 0 0 1\n");
        refused(
            &o,
            &["invalid argument `SOURCE`", "no table name after `#`"],
        );
    }
    let o = brdftab(&["export", "--help"]);
    assert!(
        o.stdout
            .contains("Usage: brdftab export [OPTIONS] <SOURCE>"),
        "{}",
        o.stdout
    );
}

/// An output under a path whose directory part is a file (`t.btdb/x.png`): `db add` said
/// "Not a directory (os error 20)", `render` and `export` that the directory "does not exist"
/// (it does: it is a file), `bake` that it "is not a directory". All say the last now, before
/// any work.
#[test]
fn an_output_under_a_file_says_that_it_is_not_a_directory() {
    let d = TempDir::new("io-under-file");
    let t = d.file("t.btdb");
    assert!(brdftab(&["bake", LAMBERT, "-o", &t, "--preset", "small"]).ok);
    let under = |f: &str| format!("{t}/{f}");
    let (db, png, npy) = (under("lib.btdb"), under("x.png"), under("x.npy"));
    for args in [
        vec![
            "db", "add", &db, LAMBERT, "--name", "w", "--preset", "small",
        ],
        vec!["bake", LAMBERT, "-o", &db, "--preset", "small"],
        vec!["render", LAMBERT, "-o", &png, "--size", "8x8", "--spp", "1"],
        vec!["export", &t, "--npy", &npy],
    ] {
        let o = brdftab(&args);
        refused(&o, &[&format!("{t} is not a directory")]);
        assert!(!o.stderr.contains("baked"), "{args:?}: {}", o.stderr);
        assert_eq!(o.stderr.lines().count(), 1, "{}", o.stderr);
    }
}
