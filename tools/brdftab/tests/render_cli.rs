//! `brdftab render` end to end: a tiny render, and --compare writing the pair, the difference
//! image and the relative RMSE.

use std::process::Command;

fn brdftab() -> Command {
    Command::new(env!("CARGO_BIN_EXE_brdftab"))
}

fn tmp(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("brdftab-render-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn render_writes_png_and_exr() {
    for name in ["a.png", "a.exr"] {
        let out = tmp(name);
        let st = brdftab()
            .args([
                "render",
                r#"{"model":"lambert","kd":0.2}"#,
                "--size",
                "16x12",
                "--spp",
                "2",
                "-o",
            ])
            .arg(&out)
            .status()
            .unwrap();
        assert!(st.success());
        assert!(std::fs::metadata(&out).unwrap().len() > 0);
    }
    let img = brdftab_tools::preview::read_exr(tmp("a.exr")).unwrap();
    assert_eq!((img.width, img.height, img.channels), (16, 12, 3));
}

#[test]
fn compare_with_itself_is_zero_and_writes_diff() {
    let out = tmp("cmp.png");
    let o = brdftab()
        .args([
            "render",
            r#"{"model":"lambert","kd":0.2}"#,
            "--size",
            "16x16",
            "--spp",
            "2",
            "--compare",
            r#"{"model":"lambert","kd":0.2}"#,
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("relative RMSE: 0.000000"), "{stdout}");
    assert!(tmp("cmp-diff.png").exists());
}

#[test]
fn bad_arguments_are_errors() {
    for args in [
        vec!["--size", "16"],
        vec!["--mode", "fast"],
        vec!["--env", "nowhere.exr"],
        vec!["--light", "sun"],
        vec!["--spp", "0"],
    ] {
        let o = brdftab()
            .args(["render", r#"{"model":"lambert","kd":0.2}"#, "-o"])
            .arg(tmp("x.png"))
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(String::from_utf8_lossy(&o.stderr).starts_with("error:"));
    }
}
