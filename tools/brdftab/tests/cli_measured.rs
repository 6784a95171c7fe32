//! The CLI on measured files: info, eval, slice, convert.

mod common;

use brdftab::testkit::TempDir;
use common::{brdftab, brdftab_with_stdin};

/// The shipped RGL file `name` (`data/rgl`, see `brdftab::measured::data`); a missing file
/// fails loudly.
fn rgl(name: &str) -> String {
    brdftab::measured::data::rgl_file(name)
        .unwrap_or_else(|e| panic!("{e}"))
        .display()
        .to_string()
}

#[test]
fn info_eval_slice_convert() {
    let f = rgl("paper_white_rgb.bsdf");
    let r = brdftab(&["info", &f]);
    assert!(r.ok, "{}", r.stderr);
    assert!(
        r.stdout.contains("White A4 paper (160 gsm)"),
        "{}",
        r.stdout
    );
    assert!(
        r.stdout
            .contains("9d641fbb56358275509b2b1053d1002313e2dabc7b3ec202eb5c5a6943f7b70e")
    );
    assert!(r.stdout.contains("f32[1,8,3,32,32]"), "{}", r.stdout);

    let r = brdftab_with_stdin(&["eval", &f], "0.5 0 0.866 -0.5 0 0.866\n");
    assert!(r.ok, "{}", r.stderr);
    let v: Vec<f64> = r
        .stdout
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(v.len(), 3);
    assert!((v[1] - 0.2853).abs() < 1e-3, "{}", r.stdout);

    let dir = TempDir::new("cli-measured");
    let png = dir.join("s.png");
    let r = brdftab(&[
        "slice",
        &f,
        "-o",
        png.to_str().unwrap(),
        "--kind",
        "polar",
        "--theta-in",
        "30",
        "--size",
        "32",
    ]);
    assert!(r.ok, "{}", r.stderr);
    assert!(r.stderr.contains("log10") && png.exists(), "{}", r.stderr);

    let bin = dir.join("pw.binary");
    let r = brdftab(&["convert", &f, bin.to_str().unwrap()]);
    assert!(r.ok, "{}", r.stderr);
    let r = brdftab(&["info", bin.to_str().unwrap()]);
    assert!(r.ok, "{}", r.stderr);
    assert!(r.stdout.contains("material:    unknown"), "{}", r.stdout);

    // `--json` on measured files (it used to print the text): the same facts.
    let j = |file: &str| -> serde_json::Value {
        let r = brdftab(&["info", file, "--json"]);
        assert!(r.ok, "{}", r.stderr);
        serde_json::from_str(&r.stdout).unwrap_or_else(|e| panic!("{e}: {}", r.stdout))
    };
    let v = j(&f);
    assert_eq!(v["format"], "rgl");
    assert_eq!(v["description"], "White A4 paper (160 gsm)");
    assert_eq!(
        v["sha256"],
        "9d641fbb56358275509b2b1053d1002313e2dabc7b3ec202eb5c5a6943f7b70e"
    );
    assert_eq!(v["channels"], serde_json::json!(["R", "G", "B"]));
    let v = j(bin.to_str().unwrap());
    assert_eq!(v["format"], "merl");
    assert_eq!(v["material"], serde_json::Value::Null);
    assert_eq!(v["dims"], serde_json::json!([90, 90, 180]));

    // A truncated file is an error with the file name, exit code 1, no panic.
    let bad = dir.join("bad.bsdf");
    std::fs::write(&bad, &std::fs::read(&f).unwrap()[..500]).unwrap();
    let r = brdftab(&["info", bad.to_str().unwrap()]);
    assert!(
        !r.ok && r.stderr.starts_with("error: ") && r.stderr.contains("bad.bsdf"),
        "{}",
        r.stderr
    );
}
