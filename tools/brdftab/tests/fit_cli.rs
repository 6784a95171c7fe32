//! The `fit`, `sample` and `pdf` commands, run as a user would.

use std::io::Write;
use std::process::{Command, Stdio};

fn brdftab(args: &[&str], stdin: &str) -> (String, String, i32) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_brdftab"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("brdftab runs");
    // The command may exit (on an error) before reading stdin: ignore a broken pipe.
    let _ = child.stdin.take().unwrap().write_all(stdin.as_bytes());
    let out = child.wait_with_output().unwrap();
    (
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
        out.status.code().unwrap_or(-1),
    )
}

const LAMBERT: &str = r#"{"model": "lambert", "kd": [0.1, 0.2, 0.3]}"#;

#[test]
fn fit_prints_a_spec_usable_as_a_source() {
    let (out, err, code) = brdftab(
        &["fit", LAMBERT, "--model", "lambert", "--pairs", "300"],
        "",
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(out.lines().count(), 1);
    let spec = out.trim();
    // The fitted spec evaluates like the source.
    let (f, err, code) = brdftab(&["eval", spec], "0 0 1 0.3 0.2 0.9\n");
    assert_eq!(code, 0, "{err}");
    let v: Vec<f64> = f.split_whitespace().map(|x| x.parse().unwrap()).collect();
    for (a, b) in v.iter().zip([0.1, 0.2, 0.3]) {
        assert!((a - b).abs() < 1e-5, "{f}");
    }
}

#[test]
fn fit_json_has_spec_rmse_and_starts() {
    let (out, err, code) = brdftab(
        &[
            "fit", LAMBERT, "--model", "lambert", "--pairs", "300", "--starts", "3", "--json",
        ],
        "",
    );
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(j["spec"]["model"], "lambert");
    assert!(j["rmse"].as_f64().unwrap() < 1e-4);
    assert!(j["iterations"].as_u64().is_some());
    assert_eq!(j["starts"].as_array().unwrap().len(), 3);
}

#[test]
fn fit_rejects_bad_params_with_a_message() {
    let (_, err, code) = brdftab(
        &[
            "fit",
            LAMBERT,
            "--model",
            "lambert",
            "--params",
            "terms[1].m",
        ],
        "",
    );
    assert_eq!(code, 1);
    assert!(err.starts_with("error:") && err.contains("terms"), "{err}");
    let (_, err, code) = brdftab(&["fit", LAMBERT, "--model", "mirror"], "");
    assert_eq!(code, 1);
    assert!(err.contains("mirror"), "{err}");
}

/// Every line of `sample` feeds back into `pdf` and gives the same density.
fn sample_and_pdf_agree(source: &str, wo: &str) {
    let (out, err, code) = brdftab(
        &["sample", source, "--wo", wo, "--count", "50", "--seed", "3"],
        "",
    );
    assert_eq!(code, 0, "{err}");
    let lines: Vec<Vec<f64>> = out
        .lines()
        .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
        .collect();
    assert!(lines.len() > 40, "{out}");
    let mut input = String::new();
    for l in &lines {
        assert_eq!(l.len(), 4 + 3, "wix wiy wiz pdf + 3 weights");
        input += &format!("{} {} {} {}\n", l[0], l[1], l[2], wo.replace(',', " "));
    }
    let (pdfs, err, code) = brdftab(&["pdf", source], &input);
    assert_eq!(code, 0, "{err}");
    let pdfs: Vec<f64> = pdfs.lines().map(|x| x.parse().unwrap()).collect();
    assert_eq!(pdfs.len(), lines.len());
    for (l, p) in lines.iter().zip(&pdfs) {
        assert!(
            (l[3] - p).abs() <= 1e-6 * p.abs().max(1e-300),
            "{source}: sample pdf {} vs pdf {p}",
            l[3]
        );
    }
}

#[test]
fn sample_pdf_matches_pdf_command() {
    sample_and_pdf_agree(LAMBERT, "-0.3,0.1,0.9");
}

#[test]
fn sample_pdf_matches_pdf_command_for_glossy_models() {
    for src in [
        r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 40}"#,
        r#"{"model": "cook_torrance", "m": 0.3}"#,
        r#"{"model": "ggx", "alpha": 0.2}"#,
    ] {
        sample_and_pdf_agree(src, "0.4,-0.2,0.8");
    }
}

#[test]
fn pdf_reads_stdin_like_eval() {
    let (out, err, code) = brdftab(
        &["pdf", LAMBERT],
        "# comment\n\n0 0 1 0 0 1\n0 0 -1 0 0 1\n",
    );
    assert_eq!(code, 0, "{err}");
    let v: Vec<f64> = out.lines().map(|x| x.parse().unwrap()).collect();
    assert!((v[0] - std::f64::consts::FRAC_1_PI).abs() < 1e-15);
    assert_eq!(v[1], 0.0);
    let (_, err, code) = brdftab(&["pdf", LAMBERT], "0 0 1 0 0 1\n0 0 x 0 0 1\n");
    assert_eq!(code, 1);
    assert!(err.contains("line 2"), "{err}");
}

#[test]
fn sample_rejects_a_bad_wo() {
    let (_, err, code) = brdftab(&["sample", LAMBERT, "--wo", "1,2"], "");
    assert_eq!(code, 1);
    assert!(err.contains("--wo"), "{err}");
    // Below the horizon: no direction can be drawn, nothing is printed.
    let (out, _, code) = brdftab(&["sample", LAMBERT, "--wo", "0,0,-1"], "");
    assert_eq!(code, 0);
    assert!(out.is_empty());
}

#[test]
fn fit_through_a_baked_table_file_recovers_cook_torrance() {
    let dir = std::env::temp_dir().join(format!("brdftab-fit-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let table = dir.join("ct.brdftab");
    let table = table.to_str().unwrap();
    let ct = r#"{"model": "cook_torrance", "m": 0.25, "ks": 0.8, "fresnel": "none"}"#;
    let (_, err, code) = brdftab(&["bake", ct, "-o", table, "--preset", "small"], "");
    assert_eq!(code, 0, "{err}");
    let (out, err, code) = brdftab(
        &[
            "fit",
            table,
            "--model",
            "cook_torrance",
            "--grey",
            "--pairs",
            "1500",
            "--starts",
            "3",
        ],
        "",
    );
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    let (m, ks) = (j["m"].as_f64().unwrap(), j["ks"].as_f64().unwrap());
    assert!(
        (m - 0.25).abs() < 0.005 && (ks - 0.8).abs() < 0.016,
        "{out}"
    );
}
