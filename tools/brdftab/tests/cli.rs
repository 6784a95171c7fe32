//! The `brdftab` command line as a user sees it: output contracts and error behaviour.

mod common;

use brdftab::testkit::TempDir;
use common::{Run, brdftab, brdftab_with_stdin};

/// Asserts the error contract: exit 1, stderr starts with `error:`, no panic, nothing on stdout.
fn assert_error(o: &Run, needle: &str) {
    assert_eq!(o.code, 1, "stderr: {}", o.stderr);
    assert!(o.stderr.starts_with("error:"), "stderr: {}", o.stderr);
    assert!(!o.stderr.contains("panicked"), "stderr: {}", o.stderr);
    assert!(
        o.stderr.to_lowercase().contains(&needle.to_lowercase()),
        "`{needle}` not in: {}",
        o.stderr
    );
}

fn numbers(line: &str) -> Vec<f64> {
    line.split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect()
}

const LAMBERT: &str = r#"{"model": "lambert", "kd": [0.1, 0.123456789, 0.3]}"#;

#[test]
fn eval_skips_blank_and_comment_lines_and_prints_one_line_per_pair() {
    let input = "# wi then wo\n0 0 1 0 0 1\n\n   \n0.3 0.1 1  -0.2 0.4 0.9\n# below the horizon:\n0 0 -1 0 0 1\n";
    let o = brdftab_with_stdin(&["eval", LAMBERT], input);
    assert_eq!(o.code, 0, "{}", o.stderr);
    let lines: Vec<&str> = o.stdout.lines().collect();
    assert_eq!(lines.len(), 3, "{}", o.stdout);
    for l in &lines[..2] {
        let v: Vec<f32> = l.split_whitespace().map(|t| t.parse().unwrap()).collect();
        // Full f32 precision: the printed value parses back to the same f32.
        assert_eq!(v, [0.1f32, 0.123_456_789_f64 as f32, 0.3f32], "{l}");
    }
    assert_eq!(numbers(lines[2]), [0.0; 3]);
}

#[test]
fn eval_wavelengths_gives_one_column_per_wavelength() {
    let o = brdftab_with_stdin(
        &[
            "eval",
            r#"{"model": "lambert", "kd": 0.25}"#,
            "--wavelengths",
            "400,500,600,700",
        ],
        "0 0 1 0 0.6 0.8\n0 0 1 0 0 1\n",
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    let lines: Vec<&str> = o.stdout.lines().collect();
    assert_eq!(lines.len(), 2);
    for l in lines {
        assert_eq!(numbers(l), [0.25; 4]);
    }
}

#[test]
fn eval_reads_a_spec_file() {
    let dir = TempDir::new("cli-spec");
    let path = dir.join("lambert.json");
    std::fs::write(&path, r#"{"model": "lambert", "kd": 0.2}"#).unwrap();
    let o = brdftab_with_stdin(&["eval", path.to_str().unwrap()], "0 0 1 0 0 1\n");
    assert_eq!(o.code, 0, "{}", o.stderr);
    let v: Vec<f32> = o
        .stdout
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    assert_eq!(v, [0.2f32; 3]);
    let bad = dir.join("bad.json");
    std::fs::write(&bad, "{\"model\": ").unwrap();
    assert_error(&brdftab(&["eval", bad.to_str().unwrap()]), "bad.json");
}

#[test]
fn malformed_stdin_line_names_the_line() {
    let o = brdftab_with_stdin(&["eval", LAMBERT], "0 0 1 0 0 1\n\n0 0 1 0 zero 1\n");
    assert_error(&o, "line 3");
    let o = brdftab_with_stdin(&["eval", LAMBERT], "0 0 1 0 0\n");
    assert_error(&o, "line 1");
    let o = brdftab_with_stdin(&["eval", LAMBERT], "0 0 1 0 0 1 7\n");
    assert_error(&o, "line 1");
}

#[test]
fn bad_specs_are_errors_naming_the_problem() {
    assert_error(&brdftab(&["eval", r#"{"model": "bogus"}"#]), "bogus");
    assert_error(
        &brdftab(&["eval", r#"{"model": "lambert", "kd": 0.3, "kx": 1}"#]),
        "kx",
    );
    assert_error(
        &brdftab(&["eval", r#"{"model": "lambert", "kd": -0.3}"#]),
        "kd",
    );
    assert_error(
        &brdftab(&["eval", r#"{"model": "lambert", "kd": "#]),
        "json",
    );
    assert_error(&brdftab(&["check", r#"{"model": "lambert"}"#]), "kd");
    assert_error(
        &brdftab(&["albedo", "/no/such/file.json"]),
        "/no/such/file.json",
    );
}

#[test]
fn bad_arguments_are_errors() {
    assert_error(&brdftab(&["eval", LAMBERT, "--bogus"]), "--bogus");
    assert_error(&brdftab(&["frobnicate"]), "frobnicate");
    assert_error(&brdftab(&[]), "subcommand");
    assert_error(&brdftab(&["check"]), "SOURCE");
    assert_error(
        &brdftab(&["eval", LAMBERT, "--wavelengths", "400,blue"]),
        "--wavelengths",
    );
    assert_error(&brdftab(&["albedo", LAMBERT, "--theta", "10,x"]), "--theta");
    assert_error(&brdftab(&["albedo", LAMBERT, "--theta", "-5"]), "--theta");
    assert_error(&brdftab(&["albedo", LAMBERT, "--theta", "95"]), "--theta");
}

#[test]
fn albedo_is_for_light_above_the_horizon() {
    // cos(90°) in f64 is 6e-17 > 0: 90 was evaluated as a light just above the horizon, where
    // Ward's albedo diverges (it printed 386351.9). Refused, like every θ′ outside [0, 90).
    let ward = r#"{"model":"ward","ks":0.1,"alpha_x":0.2,"alpha_y":0.2}"#;
    for t in ["90", "0,90", "90.0"] {
        let o = brdftab(&["albedo", ward, "--theta", t]);
        assert_error(&o, "--theta");
        assert_error(&o, "above the horizon");
        assert!(o.stdout.is_empty(), "{}", o.stdout);
    }
    let o = brdftab(&["albedo", ward, "--theta", "89.999"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(numbers(o.stdout.trim())[1].is_finite());
}

#[test]
fn albedo_prints_tiny_and_huge_numbers_in_exponent_form() {
    // `--theta 1e-300` printed the angle as 0.000…0001 (302 characters), and `--theta 1e300`
    // refused it with a 301-digit number.
    let o = brdftab(&["albedo", LAMBERT, "--theta", "1e-300,12.5"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    let lines: Vec<&str> = o.stdout.lines().collect();
    assert!(lines[0].starts_with("1e-300 "), "{}", o.stdout);
    assert!(lines[1].starts_with("12.5 "), "{}", o.stdout);
    assert!(lines.iter().all(|l| l.len() < 60), "{}", o.stdout);
    let o = brdftab(&["albedo", LAMBERT, "--theta", "1e300"]);
    assert_error(&o, "1e300°");
    assert!(o.stderr.len() < 200, "{}", o.stderr);
}

#[test]
fn albedo_takes_the_lights_azimuth() {
    // The albedo was that of light from azimuth 0 only: GGX α = (0.01, 1) reflects 0.517 at
    // θ′ = 89° from there, 0.904 from φ′ = 0.3 rad. φ′ = 90° on (α_x, α_y) is φ′ = 0 on
    // (α_y, α_x), each integral to 1e-6 (printed to 7 digits).
    let aniso = r#"{"model":"ggx","alpha_x":0.01,"alpha_y":1}"#;
    let turned = r#"{"model":"ggx","alpha_x":1,"alpha_y":0.01}"#;
    let run = |args: &[&str]| {
        let o = brdftab(args);
        assert_eq!(o.code, 0, "{}", o.stderr);
        numbers(o.stdout.trim())
    };
    let at = run(&["albedo", aniso, "--theta", "0,80,89", "--phi", "90"]);
    let want = run(&["albedo", turned, "--theta", "0,80,89"]);
    for (a, w) in at.iter().zip(&want) {
        assert!((a - w).abs() <= 5e-6 * w.abs(), "{a} vs {w}");
    }
    let a = run(&[
        "albedo",
        aniso,
        "--theta",
        "89",
        "--phi",
        "17.188733853924695",
    ]);
    assert!((a[1] - 0.904).abs() < 2e-3, "{a:?}");
    let o = brdftab(&["albedo", aniso, "--phi", "nan"]);
    assert_error(&o, "--phi");
}

/// The angles a slice's legend and errors echo are printed as `albedo` prints its angles
/// (`text::shortest`): 1e-300° read as "0.000…1" with 300 zeros and 1e300° as 301 digits.
#[test]
fn a_slice_echoes_its_angles_in_their_shortest_form() {
    let dir = TempDir::new("cli-slice-echo");
    let png = dir.join("s.png");
    let png = png.to_str().unwrap();
    let base = ["slice", LAMBERT, "-o", png, "--size", "8"];
    let polar = [
        &base[..],
        &["--kind=polar", "--theta-in=1e-300", "--phi-in=1e300"],
    ]
    .concat();
    let o = brdftab(&polar);
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(
        o.stderr.contains("θi = 1e-300°, φi = 1e300°"),
        "{}",
        o.stderr
    );
    let o = brdftab(&[&base[..], &["--kind=halfdiff", "--phi-d=1e-300"]].concat());
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(o.stderr.contains("φd = 1e-300°"), "{}", o.stderr);
    let o = brdftab(&[&base[..], &["--kind=polar", "--theta-in=1e300"]].concat());
    assert_error(&o, "1e300° is outside [0°, 90°)");
    assert!(!o.stderr.contains("000000"), "{}", o.stderr);
}

#[test]
fn a_polar_slice_is_for_light_above_the_horizon() {
    // The incidence was clamped into [0°, 90°]: 120 and -5 drew the 90° and 0° slices silently.
    let dir = TempDir::new("cli-slice-theta");
    let png = dir.join("s.png");
    let png = png.to_str().unwrap();
    for t in ["90", "120", "-5"] {
        let args = [
            "slice", LAMBERT, "-o", png, "--kind", "polar", "--size", "8",
        ];
        let flag = format!("--theta-in={t}");
        let o = brdftab(&[&args[..], &[flag.as_str()]].concat());
        assert_error(&o, "--theta-in");
        assert_error(&o, "above the horizon");
    }
    let args = [
        "slice", LAMBERT, "-o", png, "--kind", "polar", "--size", "8",
    ];
    let o = brdftab(&[&args[..], &["--theta-in", "89.9"]].concat());
    assert_eq!(o.code, 0, "{}", o.stderr);
    // An azimuth that is not a number drew an all-black image with exit 0.
    for (kind, flag) in [("polar", "--phi-in"), ("halfdiff", "--phi-d")] {
        let args = ["slice", LAMBERT, "-o", png, "--kind", kind, "--size", "8"];
        let bad = format!("{flag}=nan");
        let o = brdftab(&[&args[..], &[bad.as_str()]].concat());
        assert_error(&o, flag);
    }
}

#[test]
fn bake_target_error_reports_the_search_and_names_its_flag() {
    let dir = TempDir::new("cli-target");
    let out = dir.file("t.btdb");
    let ggx = r#"{"model": "ggx", "alpha": 0.3}"#;
    let o = brdftab(&["bake", ggx, "-o", &out, "--target-error", "1%"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    // A model's table is judged in the grazing band too (3× the target).
    assert!(
        o.stderr
            .contains("note: target error 1.00% and 3.00% in the grazing band (")
            && o.stderr.contains("): met by"),
        "{}",
        o.stderr
    );
    for bad in [
        "--target-error=abc",
        "--target-error=0",
        "--target-error=-1%",
    ] {
        let o = brdftab(&["bake", ggx, "-o", &out, bad]);
        assert_error(&o, "--target-error");
    }
    // A fixed grid cannot take a target: the library's refusal names the flag.
    let o = brdftab(&[
        "bake",
        ggx,
        "-o",
        &out,
        "--preset",
        "small",
        "--target-error",
        "1%",
    ]);
    assert_error(&o, "--target-error");
}

#[test]
fn help_and_version_succeed() {
    let o = brdftab(&["--help"]);
    assert_eq!(o.code, 0);
    assert!(o.stdout.contains("albedo") && o.stdout.contains("check"));
    let o = brdftab(&["--version"]);
    assert_eq!(o.code, 0);
    assert!(o.stdout.starts_with("brdftab "));
}

#[test]
fn albedo_prints_theta_and_one_column_per_channel() {
    let o = brdftab(&["albedo", LAMBERT, "--theta", "0,45,89"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    let rows: Vec<Vec<f64>> = o.stdout.lines().map(numbers).collect();
    assert_eq!(rows.len(), 3);
    for (row, theta) in rows.iter().zip([0.0, 45.0, 89.0]) {
        assert_eq!(row.len(), 4);
        assert_eq!(row[0], theta);
        for (a, kd) in row[1..].iter().zip([0.1f32, 0.123_456_789_f64 as f32, 0.3]) {
            let expect = kd as f64 * std::f64::consts::PI;
            assert!((a - expect).abs() < 1e-6 * expect, "{a} vs {expect}");
        }
    }
    let o = brdftab(&[
        "albedo",
        r#"{"model": "lambert", "kd": 0.1}"#,
        "--theta",
        "30",
        "--wavelengths",
        "450,550",
    ]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert_eq!(numbers(o.stdout.trim()).len(), 3);
}

#[test]
fn check_json_has_the_documented_fields() {
    let o = brdftab(&["check", r#"{"model": "lambert", "kd": 0.5}"#, "--json"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert_eq!(o.stdout.lines().count(), 1, "one JSON object on one line");
    let v: serde_json::Value = serde_json::from_str(&o.stdout).unwrap();
    assert_eq!(v["positive"], true);
    assert_eq!(v["min_value"], 0.5);
    assert_eq!(v["reciprocal"], true);
    assert_eq!(v["max_reciprocity_error"], 0.0);
    assert_eq!(v["energy_conserving"], false);
    let a = v["max_albedo"].as_f64().unwrap();
    assert!((a - 0.5 * std::f64::consts::PI).abs() < 1e-6);
    assert!(v["max_albedo_theta_deg"].is_number());
    // Every degree 0..89, then 89.9° and 89.99° (albedos that grow without bound at the
    // horizon pass 1 only there).
    assert_eq!(v["albedo_curve"].as_array().unwrap().len(), 92);
}

#[test]
fn check_text_and_models_and_demo_run() {
    let o = brdftab(&["check", r#"{"model": "lambert", "kd": 0.3}"#]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(o.stdout.contains("energy conserving:  yes"), "{}", o.stdout);
    let o = brdftab(&["models"]);
    assert_eq!(o.code, 0);
    assert!(o.stdout.contains("reciprocal_phong"));
    let o = brdftab(&["models", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&o.stdout).unwrap();
    assert!(v.as_array().unwrap().len() >= 10);
    let o = brdftab(&["demo", "--plausibility"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(o.stdout.contains("lambert kd=0.3"), "{}", o.stdout);
    assert!(
        o.stdout
            .lines()
            .any(|l| l.starts_with("lambert kd=0.5") && l.contains("NO"))
    );
}

#[test]
fn demo_bakes_into_a_database_and_prints_where() {
    let dir = TempDir::new("cli-demo");
    let out = dir.path().to_str().unwrap();
    // As a user of a checkout standing alone: no `$BRDFTAB_RGL_DIR`, run from elsewhere (no
    // `data/` or `../shared` beside the working directory); the shipped `data/rgl` is found.
    let mut cmd = common::command(&["demo", "--quick", "--preset", "small", "--out", out]);
    cmd.env_remove("BRDFTAB_RGL_DIR").current_dir(dir.path());
    let o = common::run(cmd, "");
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(o.stdout.contains("cook_torrance_gold"), "{}", o.stdout);
    assert!(!o.stderr.contains("no RGL directory"), "{}", o.stderr);
    // The seven measured materials are baked and reported.
    for m in [
        "rgl_cc_ibiza_sunset",
        "rgl_cc_iris_purple_gem",
        "rgl_cg_sunflower",
        "rgl_colodur_napoli_4f",
        "rgl_paper_white",
        "rgl_satin_rosaline",
        "rgl_vch_golden_yellow",
    ] {
        assert!(o.stdout.contains(m), "{m} missing from:\n{}", o.stdout);
    }
    assert!(o.stdout.contains("demo.btdb"), "{}", o.stdout);
    assert!(dir.join("demo.btdb").is_file());
}

/// A half/diff slice is at φh = 0: all of an isotropic BRDF, one slice of an anisotropic one,
/// which the printed description says (it named only φd).
#[test]
fn a_halfdiff_slice_says_which_phi_h_it_shows_of_an_anisotropic_source() {
    let d = TempDir::new("cli-slice-aniso");
    let png = d.file("s.png");
    let aniso = r#"{"model": "ward", "ks": 0.5, "alpha_x": 0.1, "alpha_y": 0.3}"#;
    let iso = r#"{"model": "ward", "ks": 0.5, "alpha_x": 0.2, "alpha_y": 0.2}"#;
    for (spec, named) in [(aniso, true), (iso, false)] {
        let r = brdftab(&["slice", spec, "-o", &png, "--size", "16"]);
        assert!(r.ok, "{}", r.stderr);
        assert_eq!(r.stderr.contains("φh = 0°"), named, "{spec}: {}", r.stderr);
        assert!(r.stdout.is_empty(), "{}", r.stdout);
    }
}
