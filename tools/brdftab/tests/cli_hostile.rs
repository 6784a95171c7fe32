//! Hostile input through the CLI: a corrupt table read lazily, a FIFO as SOURCE, an output that
//! is the input, a missing output directory, stale temporary files, huge inputs echoed in
//! errors, NaN directions. Every case ends in a correct answer or `error: ...` with status 1 —
//! never a hang, a silent zero or a lost file.

mod common;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use brdftab::testkit::TempDir;
use common::{brdftab, brdftab_with_stdin};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Makes a FIFO at `p` (Unix only: the FIFO cases are Unix's; a directory's run everywhere).
#[cfg(unix)]
fn mkfifo(p: &Path) {
    let c = std::ffi::CString::new(s(p)).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
}

const CT: &str = r#"{"model": "cook_torrance", "m": 0.3}"#;

/// Bakes a small table to `good` and writes a copy with one bit of chunk 0 flipped to `bad`.
fn good_and_bad(d: &Path) -> (PathBuf, PathBuf) {
    use brdftab::store::{Store, StoreOptions};
    let good = d.join("good.btdb");
    let r = brdftab(&["bake", CT, "-o", s(&good), "--preset", "small"]);
    assert!(r.ok, "{}", r.stderr);
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
    let d = TempDir::new("hostile-corrupt");
    let (good, bad) = good_and_bad(d.path());
    let pair = "0 0 1 0 0 1\n";
    let r = brdftab_with_stdin(&["eval", s(&good)], pair);
    assert!(r.ok && r.stdout.trim() != "0e0 0e0 0e0", "{}", r.stdout);
    // (0, 0, 1), (0, 0, 1) is θh = 0: chunk 0, the corrupt one.
    let r = brdftab_with_stdin(&["eval", s(&bad)], &format!("0.1 0 1 0 0 1\n{pair}{pair}"));
    assert!(!r.ok, "{}", r.stdout);
    assert!(
        r.stderr.starts_with("error: ") && r.stderr.contains("checksum"),
        "{}",
        r.stderr
    );
    assert!(
        !r.stdout.contains("0e0"),
        "eval printed the corrupt chunk's zero: {}",
        r.stdout
    );
    // (pdf and sample read the sampler, built from pairs that may miss chunk 0: they fail only
    // when they touched it.) The albedo at normal incidence integrates over θh = 0.
    let r = brdftab(&["albedo", s(&bad), "--theta", "0"]);
    assert!(!r.ok && r.stderr.contains("checksum"), "{}", r.stderr);
    // Writers refuse and leave no file.
    for out in ["out.bsdf", "out.binary", "out.btdb", "out.tbl"] {
        let o = d.join(out);
        let r = brdftab(&["convert", s(&bad), s(&o), "--pairs", "0"]);
        assert!(
            !r.ok && r.stderr.contains("checksum"),
            "convert to {out}: {}",
            r.stderr
        );
        assert!(!o.exists(), "convert wrote {out} from a corrupt table");
    }
    let npy = d.join("t.npy");
    let r = brdftab(&["export", s(&bad), "--npy", s(&npy)]);
    assert!(!r.ok && r.stderr.contains("checksum"), "{}", r.stderr);
    assert!(!npy.exists(), "export left a partial .npy");
    let r = brdftab(&["db", "verify", s(&bad)]);
    assert!(!r.ok && r.stderr.contains("checksum"), "{}", r.stderr);
    // Everything else that evaluates the table: an image, a fit or a timing of its zeros is
    // no result (each once printed one and exited 0).
    let png = d.join("x.png");
    for args in [
        vec!["slice", s(&bad), "-o", s(&png)],
        vec![
            "render",
            s(&bad),
            "-o",
            s(&png),
            "--size",
            "8x8",
            "--spp",
            "1",
        ],
        vec!["fit", s(&bad), "--model", "ggx"],
        vec!["bench", s(&bad), "--pairs", "1000"],
        vec!["sample", s(&bad), "--wo", "0,0,1", "--count", "3"],
    ] {
        let r = brdftab(&args);
        assert!(
            !r.ok && r.stderr.starts_with("error: ") && r.stderr.contains("checksum"),
            "{args:?}: {}{}",
            r.stdout,
            r.stderr
        );
        assert!(!png.exists(), "{args:?} wrote an image of a corrupt table");
    }
}

#[test]
fn a_fifo_or_a_directory_as_source_is_refused_at_once() {
    let d = TempDir::new("hostile-fifo");
    let dir = d.join("dir.bsdf");
    std::fs::create_dir(&dir).unwrap();
    #[allow(unused_mut)] // a FIFO only on Unix
    let mut sources = vec![dir];
    #[cfg(unix)]
    sources.push({
        let fifo = d.join("pipe.btdb");
        mkfifo(&fifo);
        fifo
    });
    for src in &sources {
        for args in [
            vec!["info", s(src)],
            vec!["eval", s(src)],
            vec!["db", "list", s(src)],
        ] {
            let t0 = Instant::now();
            let r = brdftab_with_stdin(&args, "0 0 1 0 0 1\n");
            assert!(
                !r.ok && r.stderr.contains("not a regular file"),
                "{args:?}: {}",
                r.stderr
            );
            assert!(t0.elapsed() < Duration::from_secs(20), "{args:?} was slow");
        }
    }
    #[cfg(unix)]
    {
        let fifo_json = d.join("spec.json");
        mkfifo(&fifo_json);
        let r = brdftab(&["eval", s(&fifo_json)]);
        assert!(!r.ok && r.stderr.contains("a FIFO"), "{}", r.stderr);
    }
}

/// An output that is a FIFO is refused at once by every writer, before any work, and left as
/// it is: the atomic rename used to replace a FIFO (as root, `/dev/null` itself) with a plain
/// file, and the image writers blocked on it until killed. (FIFOs are Unix's; a directory's
/// case runs everywhere: the next test.)
#[cfg(unix)]
#[test]
fn a_fifo_as_output_is_refused_and_kept() {
    let d = TempDir::new("hostile-fifo-out");
    let (good, _) = good_and_bad(d.path());
    let rgl = brdftab::measured::data::rgl_dir().expect("data/rgl ships");
    let pw = rgl.join("paper_white_rgb.bsdf");
    let lam = r#"{"model": "lambert", "kd": 0.3}"#;
    let npy = d.join("v.npy");
    let r = brdftab(&["export", s(&good), "--npy", s(&npy)]);
    assert!(r.ok, "{}", r.stderr);
    for name in [
        "t.btdb", "t.npy", "t.png", "t.exr", "t.bsdf", "t.binary", "db.btdb",
    ] {
        let fifo = d.join(name);
        mkfifo(&fifo);
        let f = s(&fifo);
        let args: Vec<Vec<&str>> = match name {
            "t.btdb" => vec![
                vec!["bake", lam, "--preset", "small", "-o", f],
                vec!["import", s(&npy), "--like", s(&good), "-o", f],
            ],
            "t.npy" => vec![vec!["export", s(&good), "--npy", f]],
            "t.png" => vec![
                vec!["render", lam, "--size", "16", "--spp", "1", "-o", f],
                vec!["slice", lam, "-o", f],
            ],
            "t.exr" => vec![vec!["export", s(&good), "--exr", f, "--slice", "0,2"]],
            "t.bsdf" => vec![vec!["convert", s(&pw), f, "--pairs", "0"]],
            "t.binary" => vec![vec!["convert", lam, f]],
            _ => vec![vec![
                "db", "add", f, lam, "--name", "a", "--preset", "small",
            ]],
        };
        for a in args {
            let t0 = Instant::now();
            let r = brdftab(&a);
            assert!(
                !r.ok && r.stderr.contains("is a FIFO, not a regular file"),
                "{a:?}: {}",
                r.stderr
            );
            assert!(t0.elapsed() < Duration::from_secs(20), "{a:?} was slow");
            let m = std::fs::symlink_metadata(&fifo).unwrap();
            use std::os::unix::fs::FileTypeExt;
            assert!(m.file_type().is_fifo(), "{a:?} replaced the FIFO");
        }
    }
}

/// A directory or an empty path as output is refused, on every OS.
#[test]
fn a_directory_or_an_empty_path_as_output_is_refused() {
    let d = TempDir::new("hostile-dir-out");
    let lam = r#"{"model": "lambert", "kd": 0.3}"#;
    let r = brdftab(&["bake", lam, "--preset", "small", "-o", s(d.path())]);
    assert!(!r.ok && r.stderr.contains("is a directory"), "{}", r.stderr);
    let r = brdftab(&["bake", lam, "--preset", "small", "-o", ""]);
    assert!(
        !r.ok && r.stderr.contains("empty output path"),
        "{}",
        r.stderr
    );
}

#[test]
fn an_output_that_is_the_input_is_refused_and_the_input_kept() {
    let d = TempDir::new("hostile-same");
    let rgl = brdftab::measured::data::rgl_dir().expect("data/rgl ships");
    let p = d.join("p.bsdf");
    std::fs::copy(rgl.join("paper_white_rgb.bsdf"), &p).unwrap();
    let before = std::fs::read(&p).unwrap();
    // The same file, spelled three ways (and through a symlink, where links are Unix's).
    let dotted = d.join(".").join("p.bsdf");
    #[allow(unused_mut)]
    let mut outs = vec![p.clone(), dotted];
    #[cfg(unix)]
    outs.push({
        let link = d.join("link.bsdf");
        std::os::unix::fs::symlink(&p, &link).unwrap();
        link
    });
    for out in &outs {
        let r = brdftab(&["convert", s(&p), s(out), "--pairs", "0"]);
        assert!(!r.ok && r.stderr.contains("is the input"), "{}", r.stderr);
    }
    assert_eq!(
        std::fs::read(&p).unwrap(),
        before,
        "the measurement changed"
    );
    let (good, _) = good_and_bad(d.path());
    let before = std::fs::read(&good).unwrap();
    let r = brdftab(&["bake", s(&good), "-o", s(&good)]);
    assert!(!r.ok && r.stderr.contains("is the input"), "{}", r.stderr);
    // (a .btdb is no .npy name; a table named `.npy` onto itself: cli_inputs_outputs.rs)
    let r = brdftab(&["export", s(&good), "--npy", s(&good)]);
    assert!(!r.ok && r.stderr.contains("`--npy`"), "{}", r.stderr);
    assert_eq!(std::fs::read(&good).unwrap(), before);
    // Another entry of the database the source reads is fine.
    let db = d.join("lib.btdb");
    let r = brdftab(&["db", "add", s(&db), CT, "--name", "a", "--preset", "small"]);
    assert!(r.ok, "{}", r.stderr);
    let entry = format!("{}#a", s(&db));
    let r = brdftab(&[
        "db",
        "add",
        s(&db),
        &entry,
        "--name",
        "b",
        "--preset",
        "small",
    ]);
    assert!(r.ok, "{}", r.stderr);
    let r = brdftab(&[
        "db",
        "add",
        s(&db),
        &entry,
        "--name",
        "a",
        "--replace",
        "--preset",
        "small",
    ]);
    assert!(!r.ok && r.stderr.contains("is the input"), "{}", r.stderr);
}

#[test]
fn a_missing_output_directory_is_named_not_an_internal_file() {
    let d = TempDir::new("hostile-missing");
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
        let r = brdftab(&args);
        assert!(!r.ok, "{args:?}");
        assert!(
            r.stderr.contains(s(&o)) && r.stderr.contains("does not exist"),
            "{args:?}: {}",
            r.stderr
        );
        assert!(
            !r.stderr.contains(".tmp") && !r.stderr.contains(".lock"),
            "{args:?}: {}",
            r.stderr
        );
    }
}

/// Linux only: the sweep tells a dead writer by its missing `/proc/PID` (`files::temp_path`);
/// elsewhere stale temporary files are left.
#[cfg(target_os = "linux")]
#[test]
fn temporary_files_of_killed_writers_are_removed_by_the_next_write() {
    let d = TempDir::new("hostile-stale");
    // PID 4194305 is above Linux's largest pid_max: that writer is certainly gone.
    let stale = d.join(".x.btdb.tmp.4194305.123456");
    let live = d.join(format!(".x.btdb.tmp.{}.1", std::process::id()));
    let other = d.join(".y.btdb.tmp.4194305.1");
    for f in [&stale, &live, &other] {
        std::fs::write(f, b"").unwrap();
    }
    let r = brdftab(&["bake", CT, "--preset", "small", "-o", s(&d.join("x.btdb"))]);
    assert!(r.ok, "{}", r.stderr);
    assert!(
        !stale.exists(),
        "the dead writer's temporary file is still there"
    );
    assert!(live.exists(), "a live process's temporary file was removed");
    assert!(other.exists(), "another file's temporary file was removed");
}

#[test]
fn errors_quote_huge_inputs_in_part() {
    let d = TempDir::new("hostile-huge");
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
        let r = brdftab(&["eval", s(&f)]);
        assert!(!r.ok && r.stderr.starts_with("error: "), "{name}");
        assert!(
            r.stderr.len() < 2000,
            "{name}: a {} byte error",
            r.stderr.len()
        );
    }
    let r = brdftab_with_stdin(&["eval", CT], &format!("0 0 1 0 0 {big}\n"));
    assert!(
        !r.ok && r.stderr.len() < 2000,
        "a {} byte error",
        r.stderr.len()
    );
}

#[test]
fn nan_directions_give_zero() {
    let d = TempDir::new("hostile-nan");
    let (good, _) = good_and_bad(d.path());
    let rgl = brdftab::measured::data::rgl_dir().expect("data/rgl ships");
    let paper = rgl.join("paper_white_rgb.bsdf");
    for src in [CT, s(&good), s(&paper)] {
        let r = brdftab_with_stdin(
            &["eval", src],
            "nan 0 1 0 0 1\n0 0 1 0 inf 1\n0 0 0 0 0 1\n",
        );
        assert!(r.ok, "{src}: {}", r.stderr);
        assert_eq!(r.stdout, "0e0 0e0 0e0\n".repeat(3), "{src}");
        let r = brdftab_with_stdin(&["pdf", src], "nan 0 1 0 0 1\n0 0 1 0 0 NaN\n");
        assert!(r.ok, "{src}: {}", r.stderr);
        assert_eq!(r.stdout, "0\n0\n", "{src}");
    }
}

/// A reader that went away (`brdftab models | head -1`) ends the command quietly with status 0:
/// never a panic (`println!` panics on a closed pipe). The pipe's read end is closed before
/// the command writes, so every write fails.
#[test]
fn a_closed_stdout_is_not_a_panic() {
    use std::process::Stdio;
    let d = TempDir::new("hostile-pipe");
    let table = d.path().join("t.btdb");
    let r = brdftab(&["bake", CT, "-o", s(&table), "--grid", "8x1x8x8"]);
    assert!(r.ok, "{}", r.stderr);
    let runs: [&[&str]; 7] = [
        &["models"],
        &["models", "--json"],
        &["--help"],
        &["info", s(&table)],
        &["db", "list", s(&table)],
        &["albedo", s(&table), "--theta", "0,45"],
        &["fit", s(&table), "--model", "lambert"],
    ];
    for args in runs {
        let mut child = common::command(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success() && !err.contains("panicked"),
            "{args:?}: {:?} {err}",
            out.status
        );
    }
}
