//! Errors, and the plumbing every call goes through: the `brdftab.Error` exception, the
//! mapping of library errors to it (argument errors to `ValueError`), and the wrappers that run
//! work with the GIL released and turn a panic into `brdftab.Error`.
//!
//! Why a module: every entry point of the extension goes through these, so what a library error
//! or a panic looks like in Python is decided in one place.

use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    brdftab,
    Error,
    PyException,
    "An error reported by the brdftab library (missing file, unknown model, corrupt table, ...); \
     the message is the library's."
);

/// Maps a library error: argument errors are `ValueError`, everything else `brdftab.Error`.
pub(crate) fn lib_err(e: brdftab::Error) -> PyErr {
    match e {
        brdftab::Error::InvalidArgument { .. } => PyValueError::new_err(e.to_string()),
        e => Error::new_err(e.to_string()),
    }
}

/// Runs `f`, turning a panic into `brdftab.Error` (no unwinding across the FFI boundary, and
/// nothing printed on stderr: [`brdftab::host::catch_quietly`]).
pub(crate) fn guard<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    brdftab::host::catch_quietly(f).unwrap_or_else(|p| {
        Err(Error::new_err(format!(
            "internal error in brdftab (please report): {p}"
        )))
    })
}

/// Runs long work (a bake, a fit, an albedo curve) with the GIL released, on the library's
/// fork-safe pool ([`brdftab::par`]), a panic becoming `brdftab.Error`.
pub(crate) fn unlocked<T: Send>(py: Python<'_>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    py.detach(|| brdftab::host::catch_quietly(|| brdftab::par::install(f)))
        .map_err(panic_err)
}

/// How long [`interruptible`] (and `Brdf.albedo`) leave the GIL released between checks for a
/// pending signal.
pub(crate) const SLICE: std::time::Duration = std::time::Duration::from_millis(50);

/// A [`brdftab::progress::Progress`] that reports nothing and asks the work to stop once
/// [`interruptible`] has seen a signal's exception.
struct Stop(std::sync::atomic::AtomicBool);

impl brdftab::progress::Progress for Stop {
    fn cancelled(&self) -> bool {
        self.0.load(std::sync::atomic::Ordering::Relaxed)
    }
}

/// [`unlocked`] for work that can stop: `f` runs on a thread of its own with a progress whose
/// `cancelled` the library asks between units of work, while this thread waits with the GIL
/// released and handles pending signals every [`SLICE`]. When a handler raises (Ctrl-C:
/// `KeyboardInterrupt`), the work is asked to stop, waited for (the library returns
/// `Error::Cancelled` within a unit of work per thread, leaving files as they were) and the
/// exception is raised. Without it, a bake of minutes ran to its end with Ctrl-C pending.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    f: impl FnOnce(&dyn brdftab::progress::Progress) -> T + Send,
) -> PyResult<T> {
    use std::sync::mpsc::{RecvTimeoutError, channel};
    let stop = Stop(std::sync::atomic::AtomicBool::new(false));
    let stop = &stop;
    std::thread::scope(|s| {
        let (tx, rx) = channel();
        s.spawn(move || {
            let r = brdftab::host::catch_quietly(|| brdftab::par::install(|| f(stop)));
            let _ = tx.send(r);
        });
        // The receiver moves into each wait and back (it may not be shared between threads).
        let mut rx = rx;
        loop {
            let (r, back) = py.detach(move || (rx.recv_timeout(SLICE), rx));
            rx = back;
            match r {
                Ok(r) => return r.map_err(panic_err),
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(panic_err("the work's thread ended without a result".into()));
                }
                Err(RecvTimeoutError::Timeout) => {}
            }
            if let Err(e) = py.check_signals() {
                stop.0.store(true, std::sync::atomic::Ordering::Relaxed);
                // Its result (an error or a finished operation) gives way to the exception.
                let _ = py.detach(move || rx.recv());
                return Err(e);
            }
        }
    })
}

/// Runs a batch call of `n` pairs: with the GIL released for the whole call unless it is one
/// pair (where releasing costs more than the lookup). The library's batch functions go to its
/// pool themselves.
pub(crate) fn batch<T: Send>(
    py: Python<'_>,
    n: usize,
    f: impl FnOnce() -> T + Send,
) -> PyResult<T> {
    let r = match n > 1 {
        true => py.detach(|| brdftab::host::catch_quietly(f)),
        false => brdftab::host::catch_quietly(f),
    };
    r.map_err(panic_err)
}

fn panic_err(m: String) -> PyErr {
    Error::new_err(format!("internal error in brdftab (please report): {m}"))
}
