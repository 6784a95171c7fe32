//! The `brdftab.Brdf` class: its state, how it is opened, and its Python surface — every
//! method's docstring and signature — in one `#[pymethods]` block (PyO3 takes one per class
//! without its `multiple-pymethods` feature). A method that computes runs its body, under
//! `guard`, from the file of its concern: `eval.rs` (f_r at direction pairs, spectral f_r,
//! albedo), `sample.rs` (the importance sampler: draws, their density, its node data for device
//! hosts) or `tables.rs` (the decoded table and its device layout).

mod eval;
mod sample;
mod tables;

use std::sync::Arc;

use brdftab::request::OpenSettings;
use brdftab::source::{self, OpenOptions, SourceKind};
use brdftab::table::{Table, TabulatedBrdf};
use brdftab::{Brdf, Channels};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::errors::{Error, guard, lib_err};
use crate::table::PyTable;
use crate::values::{ser, wavelengths_of};

/// A BRDF opened from a SOURCE: an analytic model spec, a table (`FILE`, `DB#NAME`), a MERL
/// `.binary` or an RGL `.bsdf` file. Directions are in the local frame (z = normal), both
/// pointing away from the surface; `wi` is the direction to the light, `wo` to the viewer.
/// Array arguments are anything numpy reads as real numbers; a `numpy.ma` masked array with
/// masked entries is a `ValueError` (fill or drop them first). Pickles by its source (its
/// file's path made absolute) and options; `copy.copy` and `copy.deepcopy` give the object itself (it is immutable).
/// `eval`, `pdf` and `sample` run with the GIL released and to their end, as numpy's ufuncs
/// do: Ctrl-C raises KeyboardInterrupt when the call returns (10^7 pairs: seconds); `albedo`
/// stops between angles.
#[pyclass(name = "Brdf", module = "brdftab", frozen)]
pub(crate) struct PyBrdf {
    inner: Arc<dyn Brdf + Send + Sync>,
    table: Option<Arc<TabulatedBrdf>>,
    source: std::ffi::OsString,
    /// The interpolation asked for: auto, nearest or linear.
    interp: String,
    wavelengths: Option<Vec<f64>>,
    eager: bool,
    /// An in-memory table (`Table.open`): `source` describes it, it names nothing to reopen
    /// (no pickling) or bake from.
    in_memory: bool,
}

impl PyBrdf {
    pub(crate) fn open(
        source: &std::ffi::OsStr,
        interp: &str,
        channels: Option<Channels>,
        eager: bool,
    ) -> PyResult<PyBrdf> {
        let settings = OpenSettings {
            interp: Some(interp.to_owned()),
            wavelengths: None,
            eager: Some(eager),
        };
        let opts = OpenOptions {
            channels: channels.clone(),
            ..settings.options().map_err(lib_err)?
        };
        // A table is kept as one (its interpolation, `table()`) unless it is stored with other
        // channels than those asked for: then `open_with` says why it cannot be opened.
        let table = match source::classify(source) {
            SourceKind::Table => Some(source::open_table(source, &opts).map_err(lib_err)?)
                .filter(|t| channels.as_ref().is_none_or(|c| c == t.channels())),
            _ => None,
        };
        let (inner, table): (Arc<dyn Brdf + Send + Sync>, _) = match table {
            Some(t) => {
                let t = Arc::new(t);
                (t.clone(), Some(t))
            }
            None => (
                Arc::from(brdftab::open_with(source, &opts).map_err(lib_err)?),
                None,
            ),
        };
        Ok(PyBrdf {
            inner,
            table,
            source: source.to_owned(),
            interp: interp.trim().to_ascii_lowercase(),
            wavelengths: wavelengths_of(&channels),
            eager,
            in_memory: false,
        })
    }

    /// `Table.open`: an in-memory table looked up with `interp` (auto, nearest or linear).
    pub(crate) fn from_table(table: Table, interp: &str) -> PyResult<PyBrdf> {
        let settings = OpenSettings {
            interp: Some(interp.to_owned()),
            ..OpenSettings::default()
        };
        let opts = settings.options().map_err(lib_err)?;
        let source = format!("<in-memory table: {}>", table.description()).into();
        let t = TabulatedBrdf::from_table(table);
        let i = opts.interp.unwrap_or_else(|| t.default_interp());
        let t = Arc::new(t.with_interp(i));
        Ok(PyBrdf {
            inner: t.clone(),
            table: Some(t),
            source,
            interp: interp.trim().to_ascii_lowercase(),
            wavelengths: None,
            eager: true,
            in_memory: true,
        })
    }

    fn c(&self) -> usize {
        self.inner.channels().len()
    }

    /// A lazily decoded chunk that failed (corrupt data) is an error, not silent zeros
    /// ([`Brdf::health`], sticky: the object stays failed). The library's error names the file
    /// and the chunk already.
    fn check_loaded(&self) -> PyResult<()> {
        self.inner
            .health()
            .map_err(|e| Error::new_err(e.to_string()))
    }
}

#[pymethods]
impl PyBrdf {
    /// Channel names as the CLI prints them: ["R", "G", "B"] or ["450nm", ...].
    #[getter]
    fn channels(&self) -> Vec<String> {
        self.inner.channels().names()
    }

    /// Wavelengths in nm of a spectral BRDF, or None for RGB.
    #[getter]
    fn wavelengths(&self) -> Option<Vec<f64>> {
        match self.inner.channels() {
            Channels::Wavelengths(w) => Some(w.clone()),
            _ => None,
        }
    }

    /// What the BRDF declares: {"delta", "reciprocal", "isotropic", "bilateral", "transmission",
    /// "lobes": {"diffuse", "glossy", "delta"}} (hosts map the lobes to their own flags).
    #[getter]
    fn flags(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        ser(py, &self.inner.flags())
    }

    /// The SOURCE string this BRDF was opened from (`"<in-memory table: ...>"` for
    /// `Table.open`); a file name that is not UTF-8 as `os.fsdecode` gives it.
    #[getter]
    fn source(&self) -> std::ffi::OsString {
        self.source.clone()
    }

    /// The interpolation lookups use: a table's ("linear" or "nearest"; with `interp="auto"`,
    /// the one its grid chose), a MERL file's ("nearest", its cells, unless "linear" was
    /// asked), an RGL file's ("linear", its format's own, whatever was asked); for an
    /// analytic model, which interpolates nothing, the interpolation asked for.
    #[getter]
    fn interp(&self) -> String {
        if let Some(t) = &self.table {
            return format!("{:?}", t.interp()).to_ascii_lowercase();
        }
        match (source::classify(&self.source), self.interp.as_str()) {
            (_, "linear") | (SourceKind::Rgl, _) => "linear".into(),
            (SourceKind::Merl, _) => "nearest".into(),
            _ => self.interp.clone(),
        }
    }

    /// A one-line description (model and parameters, or table and source).
    fn describe(&self) -> String {
        self.inner.describe()
    }

    fn __repr__(&self) -> String {
        format!(
            "<brdftab.Brdf {:?}: {}>",
            self.source.to_string_lossy(),
            self.inner.describe()
        )
    }

    /// f_r(wi, wo) in 1/sr (not times a cosine) as float32 of shape (..., c): wi and wo are
    /// (..., 3) arrays whose leading shapes broadcast by numpy's rules — (n, 3) against (n, 3)
    /// or (3,), an image of directions (h, w, 3), a grid `wi[:, None]` against `wo[None, :]` —
    /// and the result has the broadcast shape, (c,) for one pair of shape (3,). Directions need
    /// not be normalized; below the horizon, and
    /// for a direction with a NaN or infinite component or a zero vector, f_r = 0 (as in the
    /// library and the C ABI). A lazily opened table (`eager=False`) whose chunk fails its
    /// checksum raises `brdftab.Error`, then and on every later call.
    fn eval(
        &self,
        py: Python<'_>,
        wi: &Bound<'_, PyAny>,
        wo: &Bound<'_, PyAny>,
    ) -> PyResult<Py<PyAny>> {
        guard(|| self.eval_pairs(py, wi, wo))
    }

    /// f_r(wi, wo) at wavelengths `nm` (shape (k,) for every pair, or (..., k), one set per
    /// pair): float32 (..., k), the pairs' shape as in `eval`.
    /// Spectral channels are interpolated; analytic models use their spectral data; RGB
    /// channels become a spectrum of their colour (`brdftab.rgb_basis`). A
    /// wavelength must be finite and > 0 (the library's rule, as for `wavelengths=`): any
    /// other is a `ValueError`. Tables, MERL and RGL files look each pair up once for all k
    /// wavelengths.
    fn eval_spectral(
        &self,
        py: Python<'_>,
        wi: &Bound<'_, PyAny>,
        wo: &Bound<'_, PyAny>,
        nm: &Bound<'_, PyAny>,
    ) -> PyResult<Py<PyAny>> {
        guard(|| self.eval_spectral_pairs(py, wi, wo, nm))
    }

    /// The density (1/sr, solid angle) with which `sample(wo, u)` draws wi: float64 of the
    /// pairs' shape (as in `eval`; 0-d for one pair).
    fn pdf(
        &self,
        py: Python<'_>,
        wi: &Bound<'_, PyAny>,
        wo: &Bound<'_, PyAny>,
    ) -> PyResult<Py<PyAny>> {
        guard(|| self.pdf_pairs(py, wi, wo))
    }

    /// Draws wi for each wo (..., 3) from uniform numbers u in [0, 1)² (..., 2), their leading
    /// shapes broadcast as in `eval`; returns (wi (..., 3) float64, pdf (...) float64, weight
    /// (..., c) float32) with
    /// weight = f_r cos θi / pdf (`brdftab sample`'s conventions). Where no direction can be
    /// drawn (wo below the horizon, NaN, infinite or zero) wi, pdf and weight are 0; `u`
    /// outside [0, 1) (NaN included) is a `ValueError`.
    ///
    /// `nm` (wavelengths in nm, shape (k,) or (..., k)): the weights at those wavelengths,
    /// (..., k), instead of the channels — for a smooth draw f_r from `eval_spectral`, for a
    /// delta draw (a mirror) the lobe's reflectance at each wavelength over its `pdf` (the
    /// probability of choosing that lobe, 1 for a mirror alone); the draws are those without
    /// `nm`. `delta=True`: a fourth array, bool (...), true where the draw is a delta lobe's (a
    /// mirror term of a sum: its pdf is then the probability of choosing that lobe,
    /// not a density, and `pdf(wi, wo)` does not contain it) — what a renderer's multiple
    /// importance sampling needs to tell the two apart.
    #[pyo3(signature = (wo, u, *, nm=None, delta=false))]
    fn sample(
        &self,
        py: Python<'_>,
        wo: &Bound<'_, PyAny>,
        u: &Bound<'_, PyAny>,
        nm: Option<&Bound<'_, PyAny>>,
        delta: bool,
    ) -> PyResult<Py<PyTuple>> {
        guard(|| match (nm, delta) {
            (None, false) => self.sample_pairs(py, wo, u),
            _ => self.sample_pairs_spectral(py, wo, u, nm, delta),
        })
    }

    /// Directional albedo ∫ f_r cos θo dωo at incidence angles θ′ (radians, in [0, π/2): light
    /// above the horizon; else ValueError naming theta) and azimuth `phi` (radians from the
    /// local x axis, along which an anisotropic model's α_x runs; default 0; not finite:
    /// ValueError naming phi):
    /// float64 of θ′'s shape and then c ((k, c) for k angles, (c,) for a scalar θ′). A closed form where the model has one, else
    /// adaptive quadrature: 1e-6 relative for models, 1e-4 for tables and measured data (a
    /// tenth of a second an angle for an RGL file; Ctrl-C stops the curve between angles).
    /// The azimuth matters for anisotropic sources only (GGX α = (0.01, 1) at θ′ = 89°: 0.517
    /// at phi = 0, 0.904 at phi = 0.3).
    #[pyo3(signature = (theta, phi=0.0))]
    fn albedo(&self, py: Python<'_>, theta: &Bound<'_, PyAny>, phi: f64) -> PyResult<Py<PyAny>> {
        guard(|| self.albedo_curve(py, theta, phi))
    }

    /// A table SOURCE's device layout for this BRDF's interpolation (`Table.device_layout`),
    /// without the copy `table().device_layout()` makes: the decoded table moves into it.
    /// Raises `brdftab.Error` for any other source (bake it: `table(...).device_layout()`).
    fn device_layout(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        guard(|| self.table_device_layout(py))
    }

    /// The node densities of the library's importance sampler (Rust
    /// `brdftab::table::SamplingNodes`): {"version": 3, "linear", "nx", "ny", "nt", "np",
    /// "isotropic", "data": float32 array (nt·np, ny, nx), "alias": {...}} — g(s, y) of f_r cos θ
    /// over the half-vector square (s → θh = (π/2)(a s + (1 − a) s²), a = "linear", y → φh =
    /// 2π y − π relative to the conditioning direction's azimuth) at nt conditioning nodes
    /// uniform in t = sqrt(1 − cos θ) (times np over φ for anisotropic sources), and the
    /// library's constant-time draw of them
    /// (Rust `brdftab::table::AliasTables`): {"other_bits", "pdf": float32 (nt·np, ny, nx)
    /// normalized, "strips": uint32 (nt·np, 2(ny − 1)), "cells": uint32 (nt·np, ny, nx − 1)}.
    /// `adjoint=True` conditions on wi and weights by cos θo (Mitsuba's convention: draw wo
    /// given wi). For hosts that sample on a device (the Mitsuba plugin). A negative count is
    /// a `ValueError` naming it.
    #[pyo3(signature = (adjoint=false, theta_h=64, phi_h=64, theta_o=32, phi_o=16))]
    fn sampling_nodes(
        &self,
        py: Python<'_>,
        adjoint: bool,
        theta_h: i64,
        phi_h: i64,
        theta_o: i64,
        phi_o: i64,
    ) -> PyResult<Py<PyAny>> {
        // Signed here: pyo3's refusal of a negative `usize` is an OverflowError that does not
        // name the argument.
        let count = |x: i64, name: &str| {
            usize::try_from(x).map_err(|_| {
                pyo3::exceptions::PyValueError::new_err(format!(
                    "{name}: {x} is not a node count (an integer >= 0)"
                ))
            })
        };
        let (th, ph) = (count(theta_h, "theta_h")?, count(phi_h, "phi_h")?);
        let (to, po) = (count(theta_o, "theta_o")?, count(phi_o, "phi_o")?);
        guard(|| self.sampling_nodes_dict(py, adjoint, th, ph, to, po))
    }

    /// The resolution the library samples this source at (Rust
    /// `brdftab::table::SamplingResolution::for_source`):
    /// {"theta_h", "phi_h", "theta_o", "phi_o"} for `sampling_nodes` — twice the θh nodes for
    /// a peak at normal incidence too sharp for 64, half again the views and φh nodes for a
    /// lobe that changes shape between the grazing views faster than they follow (the Phong
    /// family); `nearest=True` for a table read by cell (48 θ nodes); `adjoint=True` probes
    /// f_r with its directions exchanged. Decides by building a sampler (tens of ms).
    #[pyo3(signature = (adjoint=false, nearest=false))]
    fn sampling_resolution(
        &self,
        py: Python<'_>,
        adjoint: bool,
        nearest: bool,
    ) -> PyResult<Py<PyAny>> {
        guard(|| self.sampling_resolution_dict(py, adjoint, nearest))
    }

    /// The decoded table as a `brdftab.Table`: `values` (float32, shaped by the stored axes
    /// and the channels, λ innermost; flat for a packed `inout` reciprocal table) shares the
    /// table's memory, read-only; `grid` describes it. Unpacks as `values, grid = b.table()`.
    /// A table SOURCE gives its stored table; any other source is baked in memory with
    /// `options` (the keywords of `brdftab.bake`).
    #[pyo3(signature = (**options))]
    fn table(&self, py: Python<'_>, options: Option<&Bound<'_, PyDict>>) -> PyResult<PyTable> {
        guard(|| self.decoded_table(py, options))
    }

    /// The object itself: a `Brdf` is immutable (nothing is reopened from disk).
    fn __copy__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    /// The object itself (immutable, as `__copy__`).
    fn __deepcopy__(slf: Py<Self>, _memo: &Bound<'_, PyAny>) -> Py<Self> {
        slf
    }

    fn __reduce__(&self, py: Python<'_>) -> PyResult<Py<PyTuple>> {
        if self.in_memory {
            return Err(pyo3::exceptions::PyTypeError::new_err(format!(
                "cannot pickle {}: it has no SOURCE to reopen (Table.save it and \
                 brdftab.open the file)",
                self.source.to_string_lossy()
            )));
        }
        let module = py.import("brdftab._native")?;
        let f = module.getattr("_reopen")?;
        let args = (
            absolute_source(&self.source),
            self.interp.clone(),
            self.wavelengths.clone(),
            self.eager,
        )
            .into_pyobject(py)?;
        Ok(PyTuple::new(py, [f, args.into_any()])?.unbind())
    }
}

/// SOURCE with its file part made absolute (`DB#NAME`'s `#NAME` and inline specs as they are):
/// what a pickled `Brdf` reopens, so that a worker in another working directory (Dask, Ray, a
/// spawned process that changes directory) opens the same file. A name that cannot be made
/// absolute, or whose `#NAME` part is not UTF-8, stays as it is.
fn absolute_source(source: &std::ffi::OsStr) -> std::ffi::OsString {
    use brdftab::store::name;
    use std::path::Path;
    if source
        .as_encoded_bytes()
        .trim_ascii_start()
        .starts_with(b"{")
    {
        return source.to_owned();
    }
    let file = name::parse_input_os("source", source).map_or(Path::new(source), |(p, _)| p);
    if file.is_absolute() {
        return source.to_owned();
    }
    let rest = source
        .as_encoded_bytes()
        .get(file.as_os_str().len()..)
        .and_then(|b| std::str::from_utf8(b).ok());
    match (std::path::absolute(file), rest) {
        (Ok(abs), Some(rest)) => {
            let mut out = abs.into_os_string();
            out.push(rest);
            out
        }
        _ => source.to_owned(),
    }
}
