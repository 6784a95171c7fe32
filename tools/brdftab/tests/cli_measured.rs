//! The CLI on measured files: info, eval, slice, convert.

use std::process::Command;

/// The shipped RGL file `name` (`data/rgl`, see `brdftab::measured::data`); a missing file
/// fails loudly.
fn rgl(name: &str) -> String {
    brdftab::measured::data::rgl_file(name)
        .unwrap_or_else(|e| panic!("{e}"))
        .display()
        .to_string()
}

fn run(args: &[&str], stdin: &str) -> (bool, String, String) {
    use std::io::Write;
    let mut child = Command::new(env!("CARGO_BIN_EXE_brdftab"))
        .args(args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(stdin.as_bytes())
        .unwrap();
    let o = child.wait_with_output().unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

#[test]
fn info_eval_slice_convert() {
    let f = rgl("paper_white_rgb.bsdf");
    let (ok, out, err) = run(&["info", &f], "");
    assert!(ok, "{err}");
    assert!(out.contains("White A4 paper (160 gsm)"), "{out}");
    assert!(out.contains("9d641fbb56358275509b2b1053d1002313e2dabc7b3ec202eb5c5a6943f7b70e"));
    assert!(out.contains("f32[1,8,3,32,32]"), "{out}");

    let (ok, out, err) = run(&["eval", &f], "0.5 0 0.866 -0.5 0 0.866\n");
    assert!(ok, "{err}");
    let v: Vec<f64> = out.split_whitespace().map(|x| x.parse().unwrap()).collect();
    assert_eq!(v.len(), 3);
    assert!((v[1] - 0.2853).abs() < 1e-3, "{out}");

    let dir = std::env::temp_dir().join(format!("brdftab-cli-measured-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("s.png");
    let (ok, out, err) = run(
        &[
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
        ],
        "",
    );
    assert!(ok, "{err}");
    assert!(out.contains("log10") && png.exists(), "{out}");

    let bin = dir.join("pw.binary");
    let (ok, _, err) = run(&["convert", &f, bin.to_str().unwrap()], "");
    assert!(ok, "{err}");
    let (ok, out, err) = run(&["info", bin.to_str().unwrap()], "");
    assert!(ok, "{err}");
    assert!(out.contains("material:    unknown"), "{out}");

    // A truncated file is an error with the file name, exit code 1, no panic.
    let bad = dir.join("bad.bsdf");
    std::fs::write(&bad, &std::fs::read(&f).unwrap()[..500]).unwrap();
    let (ok, _, err) = run(&["info", bad.to_str().unwrap()], "");
    assert!(
        !ok && err.starts_with("error: ") && err.contains("bad.bsdf"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
