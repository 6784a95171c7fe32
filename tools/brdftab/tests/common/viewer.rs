//! A `brdftab view` server for the viewer's tests, and plain-TCP requests to it.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Stdio};
use std::time::Duration;

use brdftab::testkit::TempDir;

use super::{brdftab, command};

/// A running `brdftab view`, killed on drop.
pub struct Viewer {
    pub child: Child,
    pub port: u16,
    /// The line it printed at start.
    pub line: String,
}

impl Drop for Viewer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts `brdftab view ARGS --port 0` and reads its port from the URL it prints.
pub fn start(args: &[&str]) -> Viewer {
    let mut all = vec!["view"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--port", "0"]);
    let mut child = command(&all)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let port = line
        .split("http://127.0.0.1:")
        .nth(1)
        .and_then(|r| r.trim().trim_end_matches('/').parse().ok())
        .unwrap_or_else(|| panic!("no URL in {line:?}"));
    Viewer { child, port, line }
}

/// Sends `raw` as is and returns the whole response, head and body.
pub fn send_raw(port: u16, raw: &[u8]) -> String {
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    // The server may answer (and close) before it has read an oversized request whole.
    let _ = s.write_all(raw);
    let mut out = Vec::new();
    let _ = s.read_to_end(&mut out);
    String::from_utf8_lossy(&out).into_owned()
}

/// Sends `raw` as is and returns (status, body).
pub fn send(port: u16, raw: &[u8]) -> (u16, String) {
    let text = send_raw(port, raw);
    let status = text
        .split(' ')
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or_else(|| panic!("no status in {text:?}"));
    let body = text.split_once("\r\n\r\n").map_or("", |x| x.1).to_owned();
    (status, body)
}

/// `GET target` with the right Host header.
pub fn get(v: &Viewer, target: &str) -> (u16, String) {
    let req = format!(
        "GET {target} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\n\r\n",
        v.port
    );
    send(v.port, req.as_bytes())
}

/// `GET target`, status 200, the body as JSON.
pub fn get_json(v: &Viewer, target: &str) -> serde_json::Value {
    let (status, body) = get(v, target);
    assert_eq!(status, 200, "{target}: {body}");
    serde_json::from_str(&body).unwrap()
}

/// A database of two tables (gold Cook-Torrance, matte Lambert) in `d`.
pub fn database(d: &TempDir) -> String {
    let db = d.file("lib.btdb");
    for (name, spec) in [
        (
            "gold",
            r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#,
        ),
        ("matte", r#"{"model": "lambert", "kd": 0.2}"#),
    ] {
        let r = brdftab(&["db", "add", &db, spec, "--name", name, "--preset", "small"]);
        assert!(r.ok, "{}", r.stderr);
    }
    db
}

/// Percent-encodes a query value.
pub fn enc(s: &str) -> String {
    s.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.' => (b as char).to_string(),
            _ => format!("%{b:02X}"),
        })
        .collect()
}
