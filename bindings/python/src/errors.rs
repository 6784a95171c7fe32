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
