//! `brdftab._native`: the PyO3 extension behind the Python package `brdftab`.
//!
//! Thin over the library's request layer ([`brdftab::request`]: keyword arguments are its
//! settings' fields, validated there as for the CLI and the C ABI): this module converts numpy
//! arrays and Python values, releases the GIL around batch work (which runs on
//! rayon, as `eval_batch` does), and maps errors — `brdftab::Error` to `brdftab.Error` (argument
//! errors to `ValueError`), wrong shapes and dtypes to `ValueError`/`TypeError`. Every call runs
//! under `catch_unwind`: a panic becomes `brdftab.Error`, never an abort of the interpreter.
//!
//! The pure-Python side (`python/brdftab/__init__.py`) re-exports these names and adds
//! `Database` and `brdftab.mitsuba`.
//!
//! One concern per file: `errors.rs` (the `brdftab.Error` type, the mapping of library errors,
//! the GIL and panic plumbing every call goes through), `values.rs` (Python arguments to the
//! library's values and settings, JSON results to Python), `arrays.rs` (numpy arrays in and out
//! of batch calls), `brdf/` (the `Brdf` class), `table.rs` (the `Table` class and device
//! layouts), `sources.rs` (`open`, `check`, `info`), `db.rs` (the database functions),
//! `requests.rs` (`bake`, `bake_cached`, `convert`, `fit`) and `colour.rs` (`rgb_basis`).

mod arrays;
mod brdf;
mod colour;
mod db;
mod errors;
mod requests;
mod sources;
mod table;
mod values;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("Error", m.py().get_type::<errors::Error>())?;
    m.add_class::<brdf::PyBrdf>()?;
    m.add_class::<table::PyTable>()?;
    m.add_function(wrap_pyfunction!(sources::open, m)?)?;
    m.add_function(wrap_pyfunction!(sources::_reopen, m)?)?;
    m.add_function(wrap_pyfunction!(sources::check, m)?)?;
    m.add_function(wrap_pyfunction!(sources::info, m)?)?;
    m.add_function(wrap_pyfunction!(sources::_source_kind, m)?)?;
    m.add_function(wrap_pyfunction!(db::db_names, m)?)?;
    m.add_function(wrap_pyfunction!(db::db_remove, m)?)?;
    m.add_function(wrap_pyfunction!(db::db_rename, m)?)?;
    m.add_function(wrap_pyfunction!(db::_check_table_name, m)?)?;
    m.add_function(wrap_pyfunction!(db::db_import, m)?)?;
    m.add_function(wrap_pyfunction!(requests::bake, m)?)?;
    m.add_function(wrap_pyfunction!(requests::bake_cached, m)?)?;
    m.add_function(wrap_pyfunction!(requests::_check_bake_options, m)?)?;
    m.add_function(wrap_pyfunction!(requests::convert, m)?)?;
    m.add_function(wrap_pyfunction!(requests::fit, m)?)?;
    m.add_function(wrap_pyfunction!(colour::rgb_basis, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
