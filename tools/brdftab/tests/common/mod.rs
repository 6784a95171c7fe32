//! What the CLI tests share: one way to run the `brdftab` binary.
//!
//! Every run feeds its stdin and drains stdout and stderr on their own threads (a command may
//! print more than a pipe holds before it has read all its input), and is killed after
//! [`TIMEOUT`]: a hang is a failure, not a wait.

// Each test binary compiles this module and uses part of it.
#![allow(dead_code)]

pub mod viewer;

use std::io::{Read, Write};
use std::process::{Command, Stdio};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a run may take before it counts as hung: far above the slowest command the tests
/// run (the quick `demo`, under a minute in a release build on a busy two-core machine; a debug
/// build is ten to thirty times slower).
pub const TIMEOUT: Duration = Duration::from_secs(if cfg!(debug_assertions) { 3600 } else { 600 });

/// A finished run of the binary.
#[derive(Debug)]
pub struct Run {
    /// Exit status 0.
    pub ok: bool,
    /// The exit code (−1 if a signal ended the process).
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

/// `brdftab ARGS` with an empty stdin.
pub fn brdftab(args: &[&str]) -> Run {
    run(command(args), "")
}

/// `brdftab ARGS` reading `stdin`.
pub fn brdftab_with_stdin(args: &[&str], stdin: &str) -> Run {
    run(command(args), stdin)
}

/// The command `brdftab ARGS`, for a run that also sets the environment or the working
/// directory; run it with [`run`].
pub fn command(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_brdftab"));
    c.args(args);
    c
}

/// Runs `cmd` with `stdin`, its output captured; kills it and panics after [`TIMEOUT`]. Both
/// outputs must be UTF-8.
pub fn run(mut cmd: Command, stdin: &str) -> Run {
    let what = format!(
        "brdftab {:?}",
        cmd.get_args()
            .map(|a| a.to_string_lossy())
            .collect::<Vec<_>>()
    );
    let mut child = cmd
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let mut pipe = child.stdin.take().unwrap();
    let input = stdin.to_owned();
    let feeder = std::thread::spawn(move || match pipe.write_all(input.as_bytes()) {
        // A process that refuses its input at once may exit before reading it: a broken pipe
        // is its answer, not a failure of the test.
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e),
        _ => Ok(()),
    });
    let stdout = drain(child.stdout.take().unwrap());
    let stderr = drain(child.stderr.take().unwrap());
    let t0 = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if t0.elapsed() > TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{what} hung (killed after {} s)", TIMEOUT.as_secs());
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let text = |h: JoinHandle<Vec<u8>>, name: &str| {
        String::from_utf8(h.join().unwrap())
            .unwrap_or_else(|e| panic!("{what}: {name} is not UTF-8: {e}"))
    };
    let (stdout, stderr) = (text(stdout, "stdout"), text(stderr, "stderr"));
    feeder
        .join()
        .unwrap()
        .unwrap_or_else(|e| panic!("{what}: writing stdin: {e}"));
    Run {
        ok: status.success(),
        code: status.code().unwrap_or(-1),
        stdout,
        stderr,
    }
}

/// Reads `r` to its end on a thread of its own.
fn drain(mut r: impl Read + Send + 'static) -> JoinHandle<Vec<u8>> {
    std::thread::spawn(move || {
        let mut b = Vec::new();
        r.read_to_end(&mut b).unwrap();
        b
    })
}
