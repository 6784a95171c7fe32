//! The storage commands end to end: bake to the brdftab format, info, db add/list/rm/verify,
//! eval DB#NAME, export.

use std::process::Command;

fn brdftab(args: &[&str], stdin: Option<&str>) -> (bool, String, String) {
    use std::io::Write;
    let mut c = Command::new(env!("CARGO_BIN_EXE_brdftab"))
        .args(args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    if let Some(s) = stdin {
        c.stdin.take().unwrap().write_all(s.as_bytes()).unwrap();
    }
    drop(c.stdin.take());
    let o = c.wait_with_output().unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

#[test]
fn bake_info_db_eval_export() {
    let d = std::env::temp_dir().join(format!("brdftab-cli-store-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let p = |f: &str| d.join(f).display().to_string();
    let ct = r#"{"model": "cook_torrance", "m": 0.3}"#;

    let (ok, _, e) = brdftab(
        &[
            "bake",
            ct,
            "-o",
            &p("ct.btdb"),
            "--preset",
            "small",
            "--codec",
            "log16:1e-3",
        ],
        None,
    );
    assert!(ok, "{e}");
    let (ok, out, e) = brdftab(&["info", &p("ct.btdb"), "--json"], None);
    assert!(ok, "{e}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["format"], "btdb");
    assert_eq!(v["tables"][0]["codec"]["quant"], "log16");
    assert!(v["ratio_to_f32"].as_f64().unwrap() > 2.0);

    let db = p("lib.btdb");
    for (name, spec) in [("white", r#"{"model": "lambert", "kd": 0.5}"#), ("ct", ct)] {
        let (ok, _, e) = brdftab(
            &["db", "add", &db, spec, "--name", name, "--preset", "small"],
            None,
        );
        assert!(ok, "{e}");
    }
    let (ok, _, e) = brdftab(
        &["db", "add", &db, ct, "--name", "ct", "--preset", "small"],
        None,
    );
    assert!(!ok && e.contains("--replace"), "{e}");
    let (ok, out, _) = brdftab(&["db", "list", &db, "--json"], None);
    assert!(ok);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v.as_array().unwrap().len(), 2);
    let (ok, out, _) = brdftab(&["db", "verify", &db], None);
    assert!(ok && out.contains("ok"));

    let (ok, out, e) = brdftab(&["eval", &format!("{db}#white")], Some("0 0.6 0.8 0 0 1\n"));
    assert!(ok, "{e}");
    let f: Vec<f32> = out.split_whitespace().map(|x| x.parse().unwrap()).collect();
    assert!(f.iter().all(|x| (x - 0.5).abs() < 1e-3), "{out}");
    let (ok, _, e) = brdftab(&["eval", &db], Some(""));
    assert!(!ok && e.contains("#NAME"), "{e}");

    let (ok, _, e) = brdftab(
        &[
            "export",
            &format!("{db}#ct"),
            "--npy",
            &p("ct.npy"),
            "--exr",
            &p("ct.exr"),
            "--slice",
            "3,2",
        ],
        None,
    );
    assert!(ok, "{e}");
    assert!(
        std::fs::read(p("ct.npy"))
            .unwrap()
            .starts_with(b"\x93NUMPY")
    );

    let (ok, _, _) = brdftab(&["db", "rm", &db, "white"], None);
    assert!(ok);
    let (ok, _, e) = brdftab(&["eval", &format!("{db}#white")], Some(""));
    assert!(!ok && e.contains("not found"), "{e}");

    // A damaged file gives a typed error, not a panic.
    let mut b = std::fs::read(&db).unwrap();
    let n = b.len();
    b[n / 2] ^= 0x40;
    std::fs::write(p("bad.btdb"), &b).unwrap();
    let (ok, _, e) = brdftab(&["db", "verify", &p("bad.btdb")], None);
    assert!(
        !ok && e.starts_with("error:") && !e.contains("panicked"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
