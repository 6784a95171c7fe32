//! The database functions the pure-Python `brdftab.Database` wraps: list, check a name, remove,
//! rename, import a table.
//!
//! Why a module: these manage the tables of a database file; they open no BRDF.

use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::errors::{guard, interruptible, lib_err, unlocked};
use crate::values::path_arg;

/// The names of the tables of database `path`, in file order: its table of contents, read
/// with the GIL released (listing 5,000 tables held it for 0.27 s, also reading every table's
/// header, which `info` reads and the names do not need).
#[pyfunction]
pub(crate) fn db_names(py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    guard(|| {
        let path = path_arg(path, "path")?;
        unlocked(py, || {
            let s = brdftab::store::Store::open(&path)?;
            Ok(s.tables().iter().map(|e| e.name.clone()).collect())
        })?
        .map_err(lib_err)
    })
}

/// Checks a table name against the library's rule (the one the CLI and the C ABI apply):
/// `ValueError` naming `name` for an empty name or one with `#`, `/`, `\` or a control
/// character.
#[pyfunction]
pub(crate) fn _check_table_name(name: &str) -> PyResult<()> {
    guard(|| brdftab::store::name::check("name", name).map_err(lib_err))
}

/// Removes table `name` from database `path`, with the GIL released: the database is
/// rewritten, after waiting for its lock (another writer's turn). Ctrl-C stops it, in that
/// wait too (`KeyboardInterrupt`, the database as it was).
#[pyfunction]
pub(crate) fn db_remove(py: Python<'_>, path: &Bound<'_, PyAny>, name: &str) -> PyResult<()> {
    guard(|| {
        let path = path_arg(path, "path")?;
        interruptible(py, |p| brdftab::store::db::remove_with(&path, name, p))?.map_err(lib_err)
    })
}

/// Renames table `old` of database `path` to `new`, with the GIL released as `db_remove` does:
/// the database is rewritten after waiting for its lock; Ctrl-C stops it.
#[pyfunction]
pub(crate) fn db_rename(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    old: &str,
    new: &str,
) -> PyResult<()> {
    guard(|| {
        let path = path_arg(path, "path")?;
        interruptible(py, |p| brdftab::store::db::rename_with(&path, old, new, p))?.map_err(lib_err)
    })
}

/// Adds the table of a single-table file's bytes (what `bake` writes to a `.btdb` path) to
/// database `path` as `name`, copying its encoded chunks (no re-encoding; checksums checked),
/// after waiting for the database's lock; Ctrl-C stops it.
///
/// `data` is read where it is: a `bytes` object is immutable, and the `PyBackedBytes` keeps it
/// alive while the store reads it. (It was extracted into a `Vec<u8>`, a copy whose allocation
/// failure aborts the process rather than raising MemoryError: a table near the size of memory
/// killed the interpreter.) Anything else is the wrapper's to turn into `bytes`.
#[pyfunction]
#[pyo3(signature = (path, name, data, replace=false))]
pub(crate) fn db_import(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    name: &str,
    data: Bound<'_, PyBytes>,
    replace: bool,
) -> PyResult<()> {
    guard(|| {
        let opts = brdftab::store::StoreOptions {
            eager: false,
            ..Default::default()
        };
        let path = path_arg(path, "path")?;
        let data = pyo3::pybacked::PyBackedBytes::from(data);
        interruptible(py, |p| {
            let s = brdftab::store::Store::from_bytes("the bytes", data, opts)?;
            let from = match s.tables() {
                [t] => t.name.clone(),
                ts => {
                    return Err(brdftab::Error::arg(
                        "data",
                        format!(
                            "the bytes hold {} tables; add_bytes takes a single-table file's \
                             bytes (import a database's tables one by one: Database.add with \
                             DB#NAME)",
                            ts.len()
                        ),
                    ));
                }
            };
            brdftab::store::db::import_with(&path, &s, &from, name, replace, p)
        })?
        .map_err(lib_err)
    })
}
