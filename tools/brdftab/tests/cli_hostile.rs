//! Hostile input through the CLI: a corrupt table read lazily, a FIFO as SOURCE, an output that
//! is the input, a missing output directory, stale temporary files, huge inputs echoed in
//! errors, NaN directions. Every case ends in a correct answer or `error: ...` with status 1 —
//! never a hang, a silent zero or a lost file.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Runs brdftab with `stdin`; kills it and fails after 60 s (a hang is a failure, not a wait).
fn brdftab(args: &[&str], stdin: &str) -> (bool, String, String) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_brdftab"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // A process that refuses its input at once may exit before reading it: a broken pipe here
    // is its answer, not a failure of the test.
    if let Err(e) = c.stdin.take().unwrap().write_all(stdin.as_bytes()) {
        assert_eq!(e.kind(), std::io::ErrorKind::BrokenPipe, "{e}");
    }
    let t0 = Instant::now();
    while c.try_wait().unwrap().is_none() {
        if t0.elapsed() > Duration::from_secs(60) {
            c.kill().unwrap();
            panic!("brdftab {args:?} hung (killed after 60 s)");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = c.wait_with_output().unwrap();
    let s = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (o.status.success(), s(&o.stdout), s(&o.stderr))
}

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("brdftab-hostile-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const CT: &str = r#"{"model": "cook_torrance", "m": 0.3}"#;

/// Bakes a small table to `good` and writes a copy with one bit of chunk 0 flipped to `bad`.
fn good_and_bad(d: &Path) -> (PathBuf, PathBuf) {
    use brdftab::store::{Store, StoreOptions};
    let good = d.join("good.btdb");
    let (ok, _, e) = brdftab(&["bake", CT, "-o", s(&good), "--preset", "small"], "");
    assert!(ok, "{e}");
    let mut b = std::fs::read(&good).unwrap();
    let st = Store::from_bytes("t", b.clone(), StoreOptions::default()).unwrap();
    let raw = st.single().unwrap().raw_chunk(0).unwrap().to_vec();
    let at = b.windows(raw.len()).position(|w| w == raw).unwrap();
    b[at + raw.len() / 2] ^= 0x10;
    let bad = d.join("bad.btdb");
    std::fs::write(&bad, b).unwrap();
    (good, bad)
}

#[test]
fn a_corrupt_chunk_read_lazily_is_an_error_everywhere() {
    let d = tmpdir("corrupt");
    let (good, bad) = good_and_bad(&d);
    let pair = "0 0 1 0 0 1\n";
    let (ok, out, _) = brdftab(&["eval", s(&good)], pair);
    assert!(ok && out.trim() != "0e0 0e0 0e0", "{out}");
    // (0, 0, 1), (0, 0, 1) is θh = 0: chunk 0, the corrupt one.
    let (ok, out, e) = brdftab(&["eval", s(&bad)], &format!("0.1 0 1 0 0 1\n{pair}{pair}"));
    assert!(!ok, "{out}");
    assert!(e.starts_with("error: ") && e.contains("checksum"), "{e}");
    assert!(
        !out.contains("0e0"),
        "eval printed the corrupt chunk's zero: {out}"
    );
    // (pdf and sample read the sampler, built from pairs that may miss chunk 0: they fail only
    // when they touched it.) The albedo at normal incidence integrates over θh = 0.
    let (ok, _, e) = brdftab(&["albedo", s(&bad), "--theta", "0"], "");
    assert!(!ok && e.contains("checksum"), "{e}");
    // Writers refuse and leave no file.
    for out in ["out.bsdf", "out.binary", "out.btdb", "out.tbl"] {
        let o = d.join(out);
        let (ok, _, e) = brdftab(&["convert", s(&bad), s(&o), "--pairs", "0"], "");
        assert!(!ok && e.contains("checksum"), "convert to {out}: {e}");
        assert!(!o.exists(), "convert wrote {out} from a corrupt table");
    }
    let npy = d.join("t.npy");
    let (ok, _, e) = brdftab(&["export", s(&bad), "--npy", s(&npy)], "");
    assert!(!ok && e.contains("checksum"), "{e}");
    assert!(!npy.exists(), "export left a partial .npy");
    let (ok, _, e) = brdftab(&["db", "verify", s(&bad)], "");
    assert!(!ok && e.contains("checksum"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_fifo_or_a_directory_as_source_is_refused_at_once() {
    let d = tmpdir("fifo");
    let fifo = d.join("pipe.btdb");
    let c = std::ffi::CString::new(s(&fifo)).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let dir = d.join("dir.bsdf");
    std::fs::create_dir(&dir).unwrap();
    for src in [&fifo, &dir] {
        for args in [
            vec!["info", s(src)],
            vec!["eval", s(src)],
            vec!["db", "list", s(src)],
        ] {
            let t0 = Instant::now();
            let (ok, _, e) = brdftab(&args, "0 0 1 0 0 1\n");
            assert!(!ok && e.contains("not a regular file"), "{args:?}: {e}");
            assert!(t0.elapsed() < Duration::from_secs(20), "{args:?} was slow");
        }
    }
    let fifo_json = d.join("spec.json");
    let c = std::ffi::CString::new(s(&fifo_json)).unwrap();
    // SAFETY: as above.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let (ok, _, e) = brdftab(&["eval", s(&fifo_json)], "");
    assert!(!ok && e.contains("a FIFO"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn an_output_that_is_the_input_is_refused_and_the_input_kept() {
    let d = tmpdir("same");
    let rgl = brdftab::measured::data::rgl_dir().expect("data/rgl ships");
    let p = d.join("p.bsdf");
    std::fs::copy(rgl.join("paper_white_rgb.bsdf"), &p).unwrap();
    let before = std::fs::read(&p).unwrap();
    // The same file, spelled three ways (and through a symlink).
    let link = d.join("link.bsdf");
    std::os::unix::fs::symlink(&p, &link).unwrap();
    let dotted = d.join(".").join("p.bsdf");
    for out in [&p, &dotted, &link] {
        let (ok, _, e) = brdftab(&["convert", s(&p), s(out), "--pairs", "0"], "");
        assert!(!ok && e.contains("is the input"), "{e}");
    }
    assert_eq!(
        std::fs::read(&p).unwrap(),
        before,
        "the measurement changed"
    );
    let (good, _) = good_and_bad(&d);
    let before = std::fs::read(&good).unwrap();
    let (ok, _, e) = brdftab(&["bake", s(&good), "-o", s(&good)], "");
    assert!(!ok && e.contains("is the input"), "{e}");
    let (ok, _, e) = brdftab(&["export", s(&good), "--npy", s(&good)], "");
    assert!(!ok && e.contains("is the input"), "{e}");
    assert_eq!(std::fs::read(&good).unwrap(), before);
    // Another entry of the database the source reads is fine.
    let db = d.join("lib.btdb");
    let (ok, _, e) = brdftab(
        &["db", "add", s(&db), CT, "--name", "a", "--preset", "small"],
        "",
    );
    assert!(ok, "{e}");
    let entry = format!("{}#a", s(&db));
    let (ok, _, e) = brdftab(
        &[
            "db",
            "add",
            s(&db),
            &entry,
            "--name",
            "b",
            "--preset",
            "small",
        ],
        "",
    );
    assert!(ok, "{e}");
    let (ok, _, e) = brdftab(
        &[
            "db",
            "add",
            s(&db),
            &entry,
            "--name",
            "a",
            "--replace",
            "--preset",
            "small",
        ],
        "",
    );
    assert!(!ok && e.contains("is the input"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_missing_output_directory_is_named_not_an_internal_file() {
    let d = tmpdir("missing");
    let gone = d.join("no-such-dir");
    for (args, out) in [
        (vec!["bake", CT, "--preset", "small", "-o"], "x.btdb"),
        (
            vec!["db", "add", "--name", "x", "--preset", "small"],
            "x.btdb",
        ),
        (vec!["convert", CT, "--pairs", "0"], "out.bsdf"),
        (vec!["convert", CT, "--pairs", "0"], "out.binary"),
    ] {
        let o = gone.join(out);
        let mut args = args.clone();
        match args[0] {
            "db" => drop(args.splice(2..2, [s(&o), CT])),
            "convert" => drop(args.splice(2..2, [s(&o)])),
            _ => args.push(s(&o)),
        }
        let (ok, _, e) = brdftab(&args, "");
        assert!(!ok, "{args:?}");
        assert!(
            e.contains(s(&o)) && e.contains("does not exist"),
            "{args:?}: {e}"
        );
        assert!(!e.contains(".tmp") && !e.contains(".lock"), "{args:?}: {e}");
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn temporary_files_of_killed_writers_are_removed_by_the_next_write() {
    let d = tmpdir("stale");
    // PID 4194305 is above Linux's largest pid_max: that writer is certainly gone.
    let stale = d.join(".x.btdb.tmp.4194305.123456");
    let live = d.join(format!(".x.btdb.tmp.{}.1", std::process::id()));
    let other = d.join(".y.btdb.tmp.4194305.1");
    for f in [&stale, &live, &other] {
        std::fs::write(f, b"").unwrap();
    }
    let (ok, _, e) = brdftab(
        &["bake", CT, "--preset", "small", "-o", s(&d.join("x.btdb"))],
        "",
    );
    assert!(ok, "{e}");
    assert!(
        !stale.exists(),
        "the dead writer's temporary file is still there"
    );
    assert!(live.exists(), "a live process's temporary file was removed");
    assert!(other.exists(), "another file's temporary file was removed");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn errors_quote_huge_inputs_in_part() {
    let d = tmpdir("huge");
    let big = "x".repeat(10 << 20);
    for (name, spec) in [
        ("model.json", format!(r#"{{"model": "{big}"}}"#)),
        (
            "kd.json",
            format!(r#"{{"model": "lambert", "kd": "{big}"}}"#),
        ),
        (
            "field.json",
            format!(r#"{{"model": "lambert", "{big}": 1}}"#),
        ),
    ] {
        let f = d.join(name);
        std::fs::write(&f, spec).unwrap();
        let (ok, _, e) = brdftab(&["eval", s(&f)], "");
        assert!(!ok && e.starts_with("error: "), "{name}");
        assert!(e.len() < 2000, "{name}: a {} byte error", e.len());
    }
    let (ok, _, e) = brdftab(&["eval", CT], &format!("0 0 1 0 0 {big}\n"));
    assert!(!ok && e.len() < 2000, "a {} byte error", e.len());
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn nan_directions_give_zero() {
    let d = tmpdir("nan");
    let (good, _) = good_and_bad(&d);
    let rgl = brdftab::measured::data::rgl_dir().expect("data/rgl ships");
    let paper = rgl.join("paper_white_rgb.bsdf");
    for src in [CT, s(&good), s(&paper)] {
        let (ok, out, e) = brdftab(
            &["eval", src],
            "nan 0 1 0 0 1\n0 0 1 0 inf 1\n0 0 0 0 0 1\n",
        );
        assert!(ok, "{src}: {e}");
        assert_eq!(out, "0e0 0e0 0e0\n".repeat(3), "{src}");
        let (ok, out, e) = brdftab(&["pdf", src], "nan 0 1 0 0 1\n0 0 1 0 0 NaN\n");
        assert!(ok, "{src}: {e}");
        assert_eq!(out, "0\n0\n", "{src}");
    }
    std::fs::remove_dir_all(&d).unwrap();
}
