//! `brdftab view`'s server under clients that trickle or idle, and what it touches: a slow
//! client is cut off by one deadline for its whole request, a refused `spec=` path is never
//! looked up, and the start line counts its materials.

mod common;

use std::io::{BufRead, Read, Write};
use std::net::TcpStream;
use std::process::Stdio;
use std::time::{Duration, Instant};

use brdftab::testkit::TempDir;
use common::viewer::{enc, get, get_json, start};

const LAMBERT: &str = r#"{"model":"lambert","kd":0.5}"#;

#[test]
fn clients_that_trickle_their_request_are_cut_off_and_block_no_one() {
    let v = start(&[LAMBERT]);
    let port = v.port;
    // Four clients sending a byte of a request head every second: each read is well within any
    // per-read timeout, so only a deadline for the whole request ends them.
    let tricklers: Vec<_> = (0..4)
        .map(|_| {
            std::thread::spawn(move || {
                let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
                s.set_read_timeout(Some(Duration::from_millis(1000)))
                    .unwrap();
                let t0 = Instant::now();
                let mut out = Vec::new();
                let head = b"GET /api/materials?x=aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa";
                for &b in head.iter().cycle() {
                    if t0.elapsed() > Duration::from_secs(15) || s.write_all(&[b]).is_err() {
                        break;
                    }
                    // The answer arrives while we wait for the next byte's turn.
                    let mut buf = [0u8; 512];
                    match s.read(&mut buf) {
                        Ok(0) => break,
                        Ok(n) => out.extend_from_slice(&buf[..n]),
                        Err(_) => {}
                    }
                }
                (t0.elapsed(), String::from_utf8_lossy(&out).into_owned())
            })
        })
        .collect();
    // Meanwhile a plain request is answered at once.
    std::thread::sleep(Duration::from_millis(1500));
    let t0 = Instant::now();
    assert_eq!(get(&v, "/api/materials").0, 200);
    assert!(t0.elapsed() < Duration::from_secs(2), "{:?}", t0.elapsed());
    for t in tricklers {
        let (took, out) = t.join().unwrap();
        assert!(
            took < Duration::from_secs(9) && out.starts_with("HTTP/1.1 408"),
            "cut off after {took:?}: {out:?}"
        );
    }
}

#[test]
fn a_refused_spec_path_is_never_looked_up() {
    // `classify` looks for a file named like a `FILE#NAME` string; the viewer must refuse
    // a page's non-inline SOURCE before that. Seen with strace where it can trace.
    let traced = std::process::Command::new("strace")
        .args(["-f", "-e", "trace=%file", "-o", "/dev/null", "true"])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !traced {
        eprintln!("skipped: strace cannot trace here");
        return;
    }
    let d = TempDir::new("view-stat");
    let log = d.file("trace.txt");
    let probe = d.file("probe.btdb#x");
    let bin = env!("CARGO_BIN_EXE_brdftab");
    // The server runs as a shell that says its pid and execs it: killing strace detaches its
    // tracee, which served on (an orphan `brdftab view` left by every run of this test).
    let mut child = std::process::Command::new("strace")
        .args(["-f", "-e", "trace=%file", "-o", &log, "sh", "-c"])
        .args([
            "echo $$; exec \"$0\" \"$@\"",
            bin,
            "view",
            LAMBERT,
            "--port",
            "0",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut out = std::io::BufReader::new(child.stdout.take().unwrap());
    let (mut pid, mut line) = (String::new(), String::new());
    out.read_line(&mut pid).unwrap();
    out.read_line(&mut line).unwrap();
    let port: u16 = line
        .split("http://127.0.0.1:")
        .nth(1)
        .and_then(|r| r.trim().trim_end_matches('/').parse().ok())
        .unwrap_or_else(|| panic!("no URL in {line:?}"));
    let req = format!(
        "GET /api/polar?spec={} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n",
        enc(&probe)
    );
    let (status, body) = common::viewer::send(port, req.as_bytes());
    let killed = std::process::Command::new("kill")
        .args(["-9", pid.trim()])
        .status();
    let _ = child.kill();
    let _ = child.wait();
    assert!(killed.is_ok_and(|s| s.success()), "pid {pid:?}");
    // The server is gone, not serving on as an orphan.
    let deadline = Instant::now() + Duration::from_secs(10);
    while TcpStream::connect(("127.0.0.1", port)).is_ok() {
        assert!(Instant::now() < deadline, "the traced server still serves");
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(
        status == 400 && body.contains("only inline"),
        "{status} {body}"
    );
    let trace = std::fs::read_to_string(&log).unwrap();
    assert!(!trace.contains("probe.btdb"), "looked up:\n{trace}");
}

#[test]
fn the_start_line_counts_its_materials() {
    let v = start(&[LAMBERT]);
    assert!(
        v.line.starts_with("brdftab view: 1 material at"),
        "{}",
        v.line
    );
    drop(v);
    let v = start(&[LAMBERT, LAMBERT]);
    assert!(
        v.line.starts_with("brdftab view: 2 materials at"),
        "{}",
        v.line
    );
    assert_eq!(get_json(&v, "/api/materials").as_array().unwrap().len(), 2);
}

#[test]
fn a_slow_figure_asked_for_by_many_clients_at_once_is_computed_once() {
    // The page asks for a material's albedo, plausibility and error figures on every click,
    // each taking seconds on a large table: requests arriving while the first computes used to
    // compute it again each (25 at once took 13 s for a figure of 1.7 s), and the cores were
    // busy with copies.
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::{Arc, Barrier};
    let reg = Arc::new(brdftab_tools::view::Registry::open(&[LAMBERT.to_owned()]).unwrap());
    let (calls, n) = (Arc::new(AtomicUsize::new(0)), 8);
    let start = Arc::new(Barrier::new(n));
    let threads: Vec<_> = (0..n)
        .map(|_| {
            let (reg, calls, start) = (reg.clone(), calls.clone(), start.clone());
            std::thread::spawn(move || {
                start.wait();
                reg.cached("albedo:0".into(), || {
                    calls.fetch_add(1, Ordering::SeqCst);
                    std::thread::sleep(Duration::from_millis(300));
                    "slow".into()
                })
            })
        })
        .collect();
    for t in threads {
        assert_eq!(t.join().unwrap().as_str(), "slow");
    }
    assert_eq!(calls.load(Ordering::SeqCst), 1);
    // Another key is its own figure, computed while nothing else waits.
    let other = reg.cached("albedo:1".into(), || "other".into());
    assert_eq!((other.as_str(), calls.load(Ordering::SeqCst)), ("other", 1));
}
