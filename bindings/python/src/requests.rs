//! The request layer's long calls ([`brdftab::request`]): `bake`, `bake_cached`, `convert` and
//! `fit`, whose keyword arguments are the fields of its settings, run with the GIL released
//! and stop at Ctrl-C (`KeyboardInterrupt`, [`interruptible`]); each returns a dict (what the
//! CLI's `--json` prints).
//!
//! Why a module: the functions that take `**options` as settings and write files or fit
//! models, with the dicts of their reports.

use brdftab::request::{self, BakeSettings, ConvertOutput, ConvertSettings, FitSettings};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{guard, interruptible, lib_err};
use crate::values::{exact_path, path_arg, ser, settings_of, to_py};

fn report_dict(py: Python<'_>, r: &brdftab::bake::BakeReport) -> PyResult<Py<PyAny>> {
    let info = if r.info.is_null() {
        serde_json::json!({
            "file": r.output,
            "format": "raw",
            "tables": [{
                "name": r.name,
                "shape": r.grid.stored_shape(),
                "values": r.values,
                "channels": r.grid.channels().names(),
            }],
        })
    } else {
        // From the path written: `output` is `DB#NAME` for a database entry, and such a string
        // is looked up whole first (a file of that name beside the database would be read).
        r.output_info().map_err(lib_err)?
    };
    let d = to_py(py, &info)?;
    if let Some(t) = &r.written {
        exact_path(d.bind(py), "file", &[t.path().as_os_str()])?;
    }
    Ok(d)
}

/// Bakes SOURCE into OUTPUT: a `.btdb` file, or `DB#NAME` (a table of a database). The
/// keywords are the CLI's `bake` flags, snake_cased (`preset`, `grid`, `codec`, ...; the
/// fields of the library's `BakeSettings`). `name` names a `.btdb` file's table; with `DB#NAME`
/// it may only repeat NAME (another name is an error). Returns what `brdftab info --json OUTPUT`
/// reports. Ctrl-C stops it (KeyboardInterrupt; OUTPUT is left as it was).
#[pyfunction]
#[pyo3(signature = (source, output, **options))]
pub(crate) fn bake(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    output: &Bound<'_, PyAny>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    guard(|| {
        let (source, output) = (path_arg(source, "source")?, path_arg(output, "output")?);
        let (source, output) = (source.as_os_str(), output.as_os_str());
        let settings: BakeSettings = settings_of(options)?;
        let r =
            interruptible(py, |p| request::bake(source, output, &settings, p))?.map_err(lib_err)?;
        report_dict(py, &r)
    })
}

/// Checks `options` (the keywords of `bake`) for SOURCE as `bake` does before its work — every
/// field's value, nothing opened or baked — so that the Mitsuba plugin's scalar variants, which
/// evaluate the source itself, refuse the same `preset`/`grid` values as the JIT variants,
/// which bake a table with them.
#[pyfunction]
#[pyo3(signature = (source, **options))]
pub(crate) fn _check_bake_options(
    source: &Bound<'_, PyAny>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<()> {
    guard(|| {
        let source = path_arg(source, "source")?;
        let settings: BakeSettings = settings_of(options)?;
        settings.request(&source).map_err(lib_err)?;
        Ok(())
    })
}

/// The table of SOURCE baked with `options` (the keywords of `bake`), from the cache of baked
/// tables or baked into it now (the library's `cache` module): keyed by the source's content, the
/// settings and the library's version, in `cache_dir` (default `$BRDFTAB_CACHE_DIR`, else
/// `$XDG_CACHE_HOME/brdftab`, else `~/.cache/brdftab`). Safe under concurrent calls from many
/// processes. A cached file whose structure does not read (emptied, truncated) is baked again;
/// `refresh=True` bakes again whatever is there (for one whose chunk failed its checksum). Returns
/// `{"path": str, "hit": bool}`; open the table with `brdftab.open(path)`. SOURCE and
/// `cache_dir` are str, bytes or os.PathLike; `path` is the `os.fsdecode` str of the file's
/// name (it need not be UTF-8). Ctrl-C stops the bake (KeyboardInterrupt; nothing is cached).
#[pyfunction]
#[pyo3(signature = (source, cache_dir=None, refresh=false, **options))]
pub(crate) fn bake_cached(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    cache_dir: Option<&Bound<'_, PyAny>>,
    refresh: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    guard(|| {
        let source = path_arg(source, "source")?;
        let dir = match cache_dir.filter(|d| !d.is_none()) {
            Some(d) => Some(std::path::PathBuf::from(path_arg(d, "cache_dir")?)),
            None => None,
        };
        let settings: BakeSettings = settings_of(options)?;
        let c = interruptible(py, |p| {
            brdftab::cache::bake_cached_with(&source, &settings, dir.as_deref(), refresh, p)
        })?
        .map_err(lib_err)?;
        let d = pyo3::types::PyDict::new(py);
        // The path itself (os.fsdecode's str): a lossy one would name another file.
        d.set_item("path", c.path.into_os_string())?;
        d.set_item("hit", c.hit)?;
        Ok(d.into_any().unbind())
    })
}

/// Converts SOURCE into OUTPUT as `brdftab convert` does: an RGL `.bsdf`, a MERL `.binary`,
/// `DB#NAME`, a `.btdb` file (a table named after the input) or a raw table. The keywords are
/// the CLI's `convert` flags, snake_cased: those of `bake` and `pairs`, `interp`, `resolution`,
/// `theta_i`, `phi_i`, `ndf_resolution` (the fields of the library's `ConvertSettings`). Ctrl-C
/// stops it (KeyboardInterrupt; OUTPUT is left as it was).
#[pyfunction]
#[pyo3(signature = (source, output, **options))]
pub(crate) fn convert(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    output: &Bound<'_, PyAny>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    guard(|| {
        let (source, output) = (path_arg(source, "source")?, path_arg(output, "output")?);
        let (source, output) = (source.as_os_str(), output.as_os_str());
        let settings: ConvertSettings = settings_of(options)?;
        let out = interruptible(py, |p| request::convert(source, output, &settings, p))?
            .map_err(lib_err)?;
        let d = match out {
            ConvertOutput::Merl(r) => serde_json::json!({
                "output": r.output,
                "format": "merl",
                "source": r.source,
                "grid": "merl 90x90x180 cell means",
                "seconds": r.seconds,
            }),
            ConvertOutput::Rgl(r) => {
                let f = &r.written.fields;
                serde_json::json!({
                    "output": output.to_string_lossy(),
                    "format": "rgl",
                    "source": r.source,
                    "bytes": r.written.bytes,
                    "resolution": f.n,
                    "theta_i": f.theta_i.len(),
                    "phi_i": f.phi_i.len(),
                    "seconds": r.seconds,
                    "error": r.error.map(|e| serde_json::json!({
                        "pairs": e.pairs,
                        "rel_rmse": e.rel_rmse,
                        "per_channel": e.per_channel,
                        "max_rel": e.max_rel,
                        "whole": e.fidelity.whole,
                        "grazing": e.fidelity.grazing,
                        "albedo": e.fidelity.albedo,
                    })),
                })
            }
            ConvertOutput::Table { report: r, .. } => {
                let d = serde_json::json!({
                    "output": r.output,
                    "format": "table",
                    "source": r.source,
                    "grid": r.grid.summary(),
                    "values": r.values,
                    "seconds": r.seconds,
                    "accuracy": r.accuracy,
                });
                let d = to_py(py, &d)?;
                d.bind(py).set_item("info", report_dict(py, &r)?)?;
                exact_path(d.bind(py), "output", &[output])?;
                return Ok(d);
            }
        };
        let d = to_py(py, &d)?;
        exact_path(d.bind(py), "output", &[output])?;
        Ok(d)
    })
}

/// Fits `model` (a name such as "ggx", a sum "lambert+ggx", or a JSON spec) to SOURCE; returns
/// the dict of `brdftab fit --json`. The keywords are the CLI's `fit` flags, snake_cased
/// (`params`, `starts`, `pairs`, `max_theta_deg`, ...; the fields of the library's
/// `FitSettings`). Ctrl-C stops it (KeyboardInterrupt).
#[pyfunction]
#[pyo3(signature = (source, model, **options))]
pub(crate) fn fit(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    model: &str,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    guard(|| {
        let source = path_arg(source, "source")?;
        let settings: FitSettings = settings_of(options)?;
        let result =
            interruptible(py, |p| request::fit(&source, model, &settings, p))?.map_err(lib_err)?;
        ser(py, &result)
    })
}
