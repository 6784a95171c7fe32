//! Module functions on a SOURCE: `open` (and `_reopen`, its unpickling twin) as a `Brdf`,
//! `check` (the plausibility report) and `info` (what a brdftab file holds).
//!
//! Why a module: the entry points that take a SOURCE and open or describe it, apart from the
//! database functions (`db.rs`) and the request layer's bakes, conversions and fits
//! (`requests.rs`).

use brdftab::Channels;
use brdftab::source::OpenOptions;
use pyo3::prelude::*;

use crate::brdf::PyBrdf;
use crate::errors::{guard, lib_err, unlocked};
use crate::values::{channels_of, exact_path, file_part, path_arg, ser, to_py};

/// Opens SOURCE (a spec, table, `DB#NAME`, MERL `.binary` or RGL `.bsdf`) as a `Brdf`. A path
/// is a `str`, `bytes` or an `os.PathLike` (`bake`, `convert`, `check` and `fit` take the same):
/// a file name that is not UTF-8 opens as `bytes` or as the `str` `os.fsdecode` gives.
///
/// The GIL is released while the source is read (an eager table decodes every chunk: half a
/// second for a large preset's table).
#[pyfunction]
#[pyo3(signature = (source, *, interp = "auto", wavelengths = None, eager = true))]
pub(crate) fn open(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    interp: &str,
    wavelengths: Option<&Bound<'_, PyAny>>,
    eager: bool,
) -> PyResult<PyBrdf> {
    guard(|| {
        let source = path_arg(source, "source")?;
        let channels = channels_of(wavelengths)?;
        unlocked(py, || PyBrdf::open(&source, interp, channels, eager))?
    })
}

/// Unpickling: reopens a `Brdf` from its source and options.
#[pyfunction]
#[pyo3(signature = (source, interp, wavelengths, eager = true))]
pub(crate) fn _reopen(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    interp: &str,
    wavelengths: Option<Vec<f64>>,
    eager: bool,
) -> PyResult<PyBrdf> {
    guard(|| {
        let source = path_arg(source, "source")?;
        let ch = wavelengths
            .map(Channels::wavelengths)
            .transpose()
            .map_err(lib_err)?;
        unlocked(py, || PyBrdf::open(&source, interp, ch, eager))?
    })
}

/// The plausibility report of SOURCE as a dict with the keys of `brdftab check --json`.
#[pyfunction]
#[pyo3(signature = (source, *, wavelengths = None))]
pub(crate) fn check(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    wavelengths: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyAny>> {
    guard(|| {
        let source = path_arg(source, "source")?;
        let opts = OpenOptions {
            channels: channels_of(wavelengths)?,
            ..OpenOptions::default()
        };
        let report = unlocked(py, || {
            let brdf = brdftab::open_with(&source, &opts)?;
            brdftab::analysis::plausibility::check(
                brdf.as_ref(),
                &brdftab::analysis::plausibility::Options::default(),
            )
        })?
        .map_err(lib_err)?;
        ser(py, &report)
    })
}

/// What `brdftab info --json` reports of a brdftab file (`FILE`), one table (`DB#NAME`) or a
/// measured file (MERL `.binary`, RGL `.bsdf`): a `str`, `bytes` or `os.PathLike`, whose name
/// need not be UTF-8 (`file` is then the `str` `os.fsdecode` gives, which opens). The GIL is released while the file is read.
#[pyfunction]
pub(crate) fn info(py: Python<'_>, source: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
    guard(|| {
        let source = path_arg(source, "source")?;
        let source = source.as_os_str();
        use brdftab::SourceKind;
        let v = unlocked(py, || match brdftab::classify(source) {
            SourceKind::Merl | SourceKind::Rgl => brdftab::measured::info::info(source),
            _ => brdftab::store::info::file_info(source),
        })?;
        let d = to_py(py, &v.map_err(lib_err)?)?;
        exact_path(d.bind(py), "file", &[source, file_part(source)])?;
        Ok(d)
    })
}

/// The kind of SOURCE as the library classifies it (`spec`, `merl`, `rgl` or `table`): a
/// `DB#NAME` is a table whatever its name ends with. For the Mitsuba plugin, which chooses a
/// lookup by kind before it opens anything.
#[pyfunction]
pub(crate) fn _source_kind(source: &Bound<'_, PyAny>) -> PyResult<&'static str> {
    Ok(brdftab::source::classify(path_arg(source, "source")?).name())
}
