//! `brdftab render` end to end: a tiny render, and --compare writing the pair, the difference
//! image and the relative RMSE.

mod common;

use brdftab::testkit::TempDir;
use common::brdftab;

#[test]
fn render_writes_png_and_exr() {
    let dir = TempDir::new("render-cli");
    for name in ["a.png", "a.exr"] {
        let out = dir.join(name);
        let r = brdftab(&[
            "render",
            r#"{"model":"lambert","kd":0.2}"#,
            "--size",
            "16x12",
            "--spp",
            "2",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(r.ok, "{}", r.stderr);
        assert!(std::fs::metadata(&out).unwrap().len() > 0);
    }
    let img = brdftab_tools::preview::read_exr(dir.join("a.exr")).unwrap();
    assert_eq!((img.width, img.height, img.channels), (16, 12, 3));
}

#[test]
fn exposure_scales_an_exr_output() {
    // The EXR ignored `--exposure` (session 41): the same render at +1 and -1 stop must hold
    // exactly twice and half the values of the render at 0 (same seed: the same image).
    let dir = TempDir::new("render-cli-exposure");
    let render = |ev: &str| {
        let out = dir.join(format!("e{ev}.exr"));
        let r = brdftab(&[
            "render",
            r#"{"model":"lambert","kd":0.2}"#,
            "--size",
            "8x6",
            "--spp",
            "2",
            "--exposure",
            ev,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(r.ok, "{}", r.stderr);
        brdftab_tools::preview::read_exr(&out).unwrap().data
    };
    let base = render("0");
    assert!(base.iter().any(|&v| v > 0.0));
    for (ev, k) in [("1", 2.0f32), ("-1", 0.5)] {
        let want: Vec<f32> = base.iter().map(|v| v * k).collect();
        assert_eq!(render(ev), want, "--exposure {ev}");
    }
}

#[test]
fn compare_with_itself_is_zero_and_writes_diff() {
    let dir = TempDir::new("render-cli-compare");
    let out = dir.join("cmp.png");
    let o = brdftab(&[
        "render",
        r#"{"model":"lambert","kd":0.2}"#,
        "--size",
        "16x16",
        "--spp",
        "2",
        "--compare",
        r#"{"model":"lambert","kd":0.2}"#,
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.ok, "{}", o.stderr);
    assert!(o.stdout.contains("relative RMSE: 0.000000"), "{}", o.stdout);
    assert!(dir.join("cmp-diff.png").exists());
}

#[test]
fn bad_arguments_are_errors() {
    let dir = TempDir::new("render-cli-bad");
    for args in [
        vec!["--size", "16"],
        vec!["--mode", "fast"],
        vec!["--env", "nowhere.exr"],
        vec!["--light", "sun"],
        vec!["--spp", "0"],
    ] {
        let x = dir.join("x.png");
        let mut all = vec![
            "render",
            r#"{"model":"lambert","kd":0.2}"#,
            "-o",
            x.to_str().unwrap(),
        ];
        all.extend(&args);
        let o = brdftab(&all);
        assert_eq!(o.code, 1, "{args:?}");
        assert!(o.stderr.starts_with("error:"));
    }
}
