//! `brdftab convert SOURCE out.bsdf`: the CLI call site of the RGL writer.

mod common;

use brdftab::testkit::TempDir;
use common::brdftab;

/// The shipped RGL files (the library's search: `$BRDFTAB_RGL_DIR`, `data/rgl`, `../shared`);
/// fails when none exists.
fn rgl_dir() -> std::path::PathBuf {
    brdftab::measured::data::rgl_dir()
        .expect("no RGL data directory: data/rgl ships with the crate")
}

#[test]
fn convert_writes_bsdf_files_and_reports_their_error() {
    let dir = TempDir::new("cli-rglw");
    let out = dir.join("ct.bsdf");
    let out_s = out.to_str().unwrap();
    let spec = r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#;
    let r = brdftab(&["convert", spec, out_s, "--pairs", "20000"]);
    assert!(r.ok, "{}", r.stderr);
    // The elevations are placed per source (16 to 32), the table 64 × 64 or 128 × 128. The
    // report is on stderr (a command that writes a file reports there; DESIGN.md), stdout empty.
    assert!(r.stdout.is_empty(), "{}", r.stdout);
    let layout = r
        .stderr
        .split("1 φi × ")
        .nth(1)
        .and_then(|t| t.split(" table").next())
        .unwrap_or_else(|| panic!("no layout in {}", r.stderr));
    let (nt, n) = layout.split_once(" θi, ").expect("θi, N×N");
    let nt: usize = nt.parse().unwrap();
    assert!((16..=32).contains(&nt), "{}", r.stderr);
    assert!(n == "64×64" || n == "128×128", "{}", r.stderr);
    let rmse: f64 = r
        .stderr
        .split("cos θi cos θo ")
        .nth(1)
        .and_then(|t| t.split(',').next())
        .and_then(|t| t.trim().parse().ok())
        .unwrap_or_else(|| panic!("no error figure in {}", r.stderr));
    assert!(rmse < 0.02, "{}", r.stderr);
    // What the cap hides is printed too: the whole hemisphere, the band past 80°, the albedo.
    let band: f64 = r
        .stderr
        .split("grazing band (a direction past 80°) ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no grazing figure in {}", r.stderr));
    assert!(band > 100.0 * rmse, "{}", r.stderr);
    assert!(r.stderr.contains("whole hemisphere") && r.stderr.contains("worst albedo"));
    let r = brdftab(&["info", out_s]);
    assert!(
        r.ok && r.stdout.contains("rgb") && r.stdout.contains(&format!("φi 1 × θi {nt}")),
        "{}",
        r.stdout
    );

    // Layout options, and a re-encoded RGL file keeping its own layout.
    let r = brdftab(&[
        "convert",
        spec,
        out_s,
        "--theta-i",
        "8",
        "--resolution",
        "32",
        "--pairs",
        "0",
    ]);
    assert!(
        r.ok && r.stderr.contains("1 φi × 8 θi, 32×32 table"),
        "{}{}",
        r.stderr,
        r.stderr
    );
    let paper = rgl_dir().join("paper_white_rgb.bsdf");
    let re = dir.join("paper.bsdf");
    let r = brdftab(&[
        "convert",
        paper.to_str().unwrap(),
        re.to_str().unwrap(),
        "--pairs",
        "20000",
    ]);
    assert!(
        r.ok && r.stderr.contains("1 φi × 8 θi, 32×32 table"),
        "{}{}",
        r.stderr,
        r.stderr
    );

    // Bad input: a clear error, no file.
    let zero = dir.join("zero.bsdf");
    let r = brdftab(&[
        "convert",
        r#"{"model": "lambert", "kd": 0}"#,
        zero.to_str().unwrap(),
    ]);
    assert!(
        !r.ok && r.stderr.starts_with("error: ") && r.stderr.contains("retro-reflection"),
        "{}",
        r.stderr
    );
    assert!(!zero.exists());
    let r = brdftab(&["convert", spec, out_s, "--phi-i", "2"]);
    assert!(!r.ok && r.stderr.contains("azimuths"), "{}", r.stderr);
}
