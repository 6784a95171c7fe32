//! What the CLI reads and writes: output paths checked before any work, `export`'s flags, and
//! text lines whose numbers are no direction (NaN, infinite, zero length).

mod common;

use brdftab::testkit::TempDir;
use common::{Run, brdftab, brdftab_with_stdin};

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

#[test]
fn lines_that_are_no_direction_are_errors_naming_the_line() {
    // They printed 0 and succeeded: a reader could not tell them from a true 0. The library
    // answers 0 for them (README, Conventions); the CLI's text reader refuses them, whatever
    // the source: a spec, a table, an RGL file.
    let d = TempDir::new("io-nan");
    let t = d.file("t.btdb");
    assert!(brdftab(&["bake", LAMBERT, "-o", &t, "--preset", "small"]).ok);
    let rgl = brdftab::measured::data::rgl_dir().expect("data/rgl ships");
    let paper = rgl.join("paper_white_rgb.bsdf");
    let ok = "0 0 1 0 0 1\n";
    for (bad, needle) in [
        ("nan 0 1 0 0 1", "`nan` is not a finite number"),
        ("0 0 1 inf 0 1", "`inf` is not a finite number"),
        ("0 0 1 0 0 NaN", "`NaN` is not a finite number"),
        ("0 0 1 0 0 1e400", "`1e400` is not a finite number"),
        ("0 0 0 0 0 1", "wi (0 0 0) is the zero vector"),
        ("0 0 1 0 0 0", "wo (0 0 0) is the zero vector"),
    ] {
        let input = format!("{ok}# c\n{bad}\n{ok}");
        for (cmd, src) in [
            ("eval", LAMBERT),
            ("pdf", LAMBERT),
            ("eval", &t),
            ("pdf", paper.to_str().unwrap()),
        ] {
            let o = brdftab_with_stdin(&[cmd, src], &input);
            assert_eq!(o.code, 1, "{cmd} {src} {bad}: {}", o.stderr);
            let want = format!("error: stdin: line 3: {needle}");
            assert!(o.stderr.starts_with(&want), "{cmd} {bad}: {}", o.stderr);
            // The line before it was answered.
            assert_eq!(o.stdout.lines().count(), 1, "{cmd} {bad}: {}", o.stdout);
        }
    }
    // Below the horizon is a direction: 0, as README says.
    let o = brdftab_with_stdin(&["eval", LAMBERT], "0 0 -1 0 0 1\n");
    assert!(o.ok, "{}", o.stderr);
    assert_eq!(o.stdout, "0e0 0e0 0e0\n");
    // `sample --wo` that is no direction printed nothing and succeeded.
    for wo in ["0,0,0", "nan,0,1", "0,inf,1"] {
        refused(&brdftab(&["sample", LAMBERT, "--wo", wo]), &["`--wo`", wo]);
    }
    let o = brdftab(&["sample", LAMBERT, "--wo", "0,0,-1"]);
    assert!(o.ok && o.stdout.is_empty(), "{}", o.stderr);
}
