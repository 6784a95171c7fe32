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

mod arrays;

use std::sync::Arc;

use arrays::{Pairs, Rows};
use brdftab::batch::{BLOCK, SampleOut};

use brdftab::request::{
    self, BakeSettings, ConvertOutput, ConvertSettings, FitSettings, OpenSettings,
};
use brdftab::source::{self, OpenOptions, SourceKind};
use brdftab::table::device::DeviceLayout;
use brdftab::table::{Interp, TabulatedBrdf};
use brdftab::{Brdf, Channels};
use glam::{DVec2, DVec3};
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::{IntoPyArray, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyException, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyTuple};
use rayon::prelude::*;

pyo3::create_exception!(
    brdftab,
    Error,
    PyException,
    "An error reported by the brdftab library (missing file, unknown model, corrupt table, ...); \
     the message is the library's."
);

/// Maps a library error: argument errors are `ValueError`, everything else `brdftab.Error`.
fn lib_err(e: brdftab::Error) -> PyErr {
    match e {
        brdftab::Error::InvalidArgument { .. } => PyValueError::new_err(e.to_string()),
        e => Error::new_err(e.to_string()),
    }
}

/// Runs `f`, turning a panic into `brdftab.Error` (no unwinding across the FFI boundary, and
/// nothing printed on stderr: [`brdftab::host::catch_quietly`]).
fn guard<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    brdftab::host::catch_quietly(f).unwrap_or_else(|p| {
        Err(Error::new_err(format!(
            "internal error in brdftab (please report): {p}"
        )))
    })
}

/// Runs long work (a bake, a fit, an albedo curve) with the GIL released, on the library's
/// fork-safe pool ([`brdftab::par`]), a panic becoming `brdftab.Error`.
fn unlocked<T: Send>(py: Python<'_>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    py.detach(|| brdftab::host::catch_quietly(|| brdftab::par::install(f)))
        .map_err(panic_err)
}

/// Runs a batch call of `n` pairs: with the GIL released for the whole call unless it is one
/// pair (where releasing costs more than the lookup). The library's batch functions go to its
/// pool themselves.
fn batch<T: Send>(py: Python<'_>, n: usize, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    let r = match n > 1 {
        true => py.detach(|| brdftab::host::catch_quietly(f)),
        false => brdftab::host::catch_quietly(f),
    };
    r.map_err(panic_err)
}

/// One block of `sample`'s outputs, numbered: (block, ((wi, pdf), weights)).
type SampleBlock<'a> = (usize, ((&'a mut [DVec3], &'a mut [f64]), &'a mut [f32]));

fn panic_err(m: String) -> PyErr {
    Error::new_err(format!("internal error in brdftab (please report): {m}"))
}

/// `wavelengths=`: None, a comma-separated string, or a sequence of numbers (nm).
fn channels_of(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Channels>> {
    let Some(o) = obj else { return Ok(None) };
    if o.is_none() {
        return Ok(None);
    }
    if let Ok(s) = o.extract::<String>() {
        return source::parse_wavelengths(&s).map(Some).map_err(lib_err);
    }
    let nm: Vec<f64> = o.extract().map_err(|_| {
        PyTypeError::new_err("wavelengths: expected a sequence of numbers (nm) or a string")
    })?;
    Channels::wavelengths(nm).map(Some).map_err(lib_err)
}

fn wavelengths_of(c: &Option<Channels>) -> Option<Vec<f64>> {
    match c {
        Some(Channels::Wavelengths(w)) => Some(w.clone()),
        _ => None,
    }
}

/// A decoded table (`Brdf.table()`): its values as a numpy array sharing the table's memory,
/// and its grid.
#[pyclass(name = "Table", module = "brdftab", frozen)]
struct PyTable {
    table: brdftab::table::Table,
    grid: Py<PyAny>,
}

#[pymethods]
impl PyTable {
    /// float32 values shaped by the stored axes and the channels (`grid["stored_shape"] +
    /// [c]`, λ innermost), or flat for a packed layout; read-only, no copy (the array keeps
    /// this table alive).
    #[getter]
    fn values<'py>(slf: Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let t = &slf.get().table;
        let shape: Vec<usize> = match t.shape() {
            Some(s) => s.to_vec(),
            None => vec![t.values().len()],
        };
        let view = numpy::ndarray::ArrayViewD::from_shape(IxDyn(&shape), t.values())
            .map_err(|e| Error::new_err(e.to_string()))?;
        // SAFETY: the array borrows the values of `slf`'s table, which is frozen (never mutated)
        // and kept alive by the array's base object, `slf` itself.
        let arr = unsafe { PyArrayDyn::borrow_from_array(&view, slf.clone().into_any()) };
        let kw = PyDict::new(slf.py());
        kw.set_item("write", false)?;
        arr.call_method("setflags", (), Some(&kw))?;
        Ok(arr.into_any())
    }

    /// The grid: parameterization, full axes, symmetry, stored axes with their mappings and
    /// node placement, stored_shape, packed, channels, channel_names, quantity, calibration,
    /// description.
    #[getter]
    fn grid(&self, py: Python<'_>) -> Py<PyAny> {
        self.grid.clone_ref(py)
    }

    /// The table as a GPU or JIT host evaluates it, for lookups with `interp` ("linear",
    /// "nearest", or "auto": the table's default, nearest on a grid of MERL cells): the
    /// library's device layout (`brdftab::table::device`), a dict with
    /// "version" (refuse any other than the one you implement), "kind" ("kernel" or "grid"),
    /// "channels", "channel_names", "quantity", "calibration" (None or its factors), "kernel"
    /// and "grid" (None or dicts of the layout's fields, each with its float32 "values").
    #[pyo3(signature = (interp = "linear"))]
    fn device_layout(&self, py: Python<'_>, interp: &str) -> PyResult<Py<PyAny>> {
        guard(|| {
            let t = &self.table;
            let interp: Interp = if interp.trim().eq_ignore_ascii_case("auto") {
                Interp::default_for(t.grid())
            } else {
                interp.parse().map_err(lib_err)?
            };
            let d = unlocked(py, || DeviceLayout::new(t, interp))?.map_err(lib_err)?;
            layout_dict(py, d, t.grid().channels())
        })
    }

    /// `values, grid = table`.
    fn __iter__<'py>(slf: Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let grid = slf.get().grid.clone_ref(py);
        let pair = PyTuple::new(py, [PyTable::values(slf)?.unbind(), grid])?;
        pair.into_any().try_iter().map(Bound::into_any)
    }

    fn __len__(&self) -> usize {
        2
    }

    fn __repr__(&self) -> String {
        format!(
            "<brdftab.Table {}: {}>",
            self.table.grid().summary(),
            self.table.description()
        )
    }
}

/// A device layout as the dict `Table.device_layout` and `Brdf.device_layout` return: its
/// fields as JSON values, "channel_names", and each value array moved into numpy (no copy).
fn layout_dict(py: Python<'_>, d: DeviceLayout, channels: &Channels) -> PyResult<Py<PyAny>> {
    let v = serde_json::to_value(&d).map_err(|e| Error::new_err(e.to_string()))?;
    let out = to_py(py, &v)?;
    let dict = out.bind(py).cast::<PyDict>()?;
    dict.set_item("channel_names", channels.names())?;
    if let (Some(k), Some(kd)) = (d.kernel, dict.get_item("kernel")?) {
        kd.set_item("values", k.values.into_pyarray(py))?;
    }
    if let (Some(g), Some(gd)) = (d.grid, dict.get_item("grid")?) {
        gd.set_item("values", g.values.into_pyarray(py))?;
    }
    Ok(out)
}

/// A serde_json value as a Python object (through `json.loads`: dicts, lists, floats, ...).
fn to_py(py: Python<'_>, v: &serde_json::Value) -> PyResult<Py<PyAny>> {
    let s = serde_json::to_string(v).map_err(|e| Error::new_err(e.to_string()))?;
    Ok(py.import("json")?.call_method1("loads", (s,))?.unbind())
}

fn ser<T: serde::Serialize>(py: Python<'_>, x: &T) -> PyResult<Py<PyAny>> {
    let v = serde_json::to_value(x).map_err(|e| Error::new_err(e.to_string()))?;
    to_py(py, &v)
}

/// A BRDF opened from a SOURCE: an analytic model spec, a table (`FILE`, `DB#NAME`), a MERL
/// `.binary` or an RGL `.bsdf` file. Directions are in the local frame (z = normal), both
/// pointing away from the surface; `wi` is the direction to the light, `wo` to the viewer.
/// Array arguments are anything numpy reads as real numbers; a `numpy.ma` masked array with
/// masked entries is a `ValueError` (fill or drop them first). Pickles by its source and
/// options.
#[pyclass(name = "Brdf", module = "brdftab", frozen)]
struct PyBrdf {
    inner: Arc<dyn Brdf + Send + Sync>,
    table: Option<Arc<TabulatedBrdf>>,
    source: String,
    /// The interpolation asked for: auto, nearest or linear.
    interp: String,
    wavelengths: Option<Vec<f64>>,
    eager: bool,
}

impl PyBrdf {
    fn open(
        source: &str,
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
        let (inner, table): (Arc<dyn Brdf + Send + Sync>, _) =
            if source::classify(source) == SourceKind::Table && channels.is_none() {
                let t = Arc::new(source::open_table(source, &opts).map_err(lib_err)?);
                (t.clone(), Some(t))
            } else {
                (
                    Arc::from(brdftab::open_with(source, &opts).map_err(lib_err)?),
                    None,
                )
            };
        Ok(PyBrdf {
            inner,
            table,
            source: source.to_owned(),
            interp: interp.trim().to_ascii_lowercase(),
            wavelengths: wavelengths_of(&channels),
            eager,
        })
    }

    fn c(&self) -> usize {
        self.inner.channels().len()
    }

    /// A lazily decoded chunk that failed (corrupt data) is an error, not silent zeros
    /// ([`Brdf::health`], sticky: the object stays failed).
    fn check_loaded(&self) -> PyResult<()> {
        self.inner
            .health()
            .map_err(|e| Error::new_err(format!("{}: {e}", self.source)))
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

    /// The SOURCE string this BRDF was opened from.
    #[getter]
    fn source(&self) -> String {
        self.source.clone()
    }

    /// The interpolation of a table ("linear" or "nearest"; with `interp="auto"`, the one the
    /// table's grid chose), or the interpolation asked for when the source is no table.
    #[getter]
    fn interp(&self) -> String {
        match &self.table {
            Some(t) => format!("{:?}", t.interp()).to_ascii_lowercase(),
            None => self.interp.clone(),
        }
    }

    /// A one-line description (model and parameters, or table and source).
    fn describe(&self) -> String {
        self.inner.describe()
    }

    fn __repr__(&self) -> String {
        format!(
            "<brdftab.Brdf {:?}: {}>",
            self.source,
            self.inner.describe()
        )
    }

    /// f_r(wi, wo) in 1/sr (not times a cosine) as float32 of shape (n, c), or (c,) when both
    /// wi and wo have shape (3,). Directions need not be normalized; below the horizon, and
    /// for a direction with a NaN or infinite component or a zero vector, f_r = 0 (as in the
    /// library and the C ABI). A lazily opened table (`eager=False`) whose chunk fails its
    /// checksum raises `brdftab.Error`, then and on every later call.
    fn eval(
        &self,
        py: Python<'_>,
        wi: &Bound<'_, PyAny>,
        wo: &Bound<'_, PyAny>,
    ) -> PyResult<Py<PyAny>> {
        guard(|| {
            let (a, b) = (Rows::<DVec3>::new(wi, "wi")?, Rows::<DVec3>::new(wo, "wo")?);
            let p = Pairs::new(&a, "wi", &b, "wo")?;
            let c = self.c();
            let shape: &[usize] = if p.single { &[c] } else { &[p.n, c] };
            let out = arrays::zeros::<f32>(py, shape)?;
            let mut w = out.readwrite();
            let o = w
                .as_slice_mut()
                .map_err(|e| Error::new_err(e.to_string()))?;
            let brdf = &self.inner;
            batch(py, p.n, || p.run(o, c, |a, b, o| brdf.eval_batch(a, b, o)))?;
            drop(w);
            self.check_loaded()?;
            Ok(out.into_any().unbind())
        })
    }

    /// f_r(wi, wo) at wavelengths `nm` (shape (k,) for every pair, or (n, k)): float32 (n, k).
    /// Spectral channels are interpolated; analytic models use their spectral data. A
    /// wavelength must be finite and > 0 (the library's rule, as for `wavelengths=`): any
    /// other is a `ValueError`.
    fn eval_spectral(
        &self,
        py: Python<'_>,
        wi: &Bound<'_, PyAny>,
        wo: &Bound<'_, PyAny>,
        nm: &Bound<'_, PyAny>,
    ) -> PyResult<Py<PyAny>> {
        guard(|| {
            let (a, b) = (Rows::<DVec3>::new(wi, "wi")?, Rows::<DVec3>::new(wo, "wo")?);
            let p = Pairs::new(&a, "wi", &b, "wo")?;
            let n = p.n;
            let l = arrays::f64_array(nm, "nm")?;
            let (k, per_row) = match l.shape() {
                [k] => (*k, false),
                [m, k] if *m == n => (*k, true),
                s => {
                    return Err(PyValueError::new_err(format!(
                        "nm: expected shape (k,) or ({n}, k), got {}",
                        arrays::shape_str(s)
                    )));
                }
            };
            // Read in place: a broadcast `nm` (numpy.broadcast_to) of any length is no copy,
            // and the output is allocated (or refused by numpy) before its entries are checked.
            let nm = l.as_array();
            let shape: &[usize] = if p.single { &[k] } else { &[n, k] };
            let out = arrays::zeros::<f32>(py, shape)?;
            if n > 0
                && let Some(x) = nm.iter().find(|&&x| !brdftab::spectrum::is_wavelength(x))
            {
                return Err(PyValueError::new_err(format!(
                    "nm: {x} is not a wavelength (a finite number of nm > 0)"
                )));
            }
            let mut w = out.readwrite();
            let o = w
                .as_slice_mut()
                .map_err(|e| Error::new_err(e.to_string()))?;
            let brdf = &self.inner;
            batch(py, n * k, || {
                brdftab::batch::blocks(o, k, |s, o| {
                    let (a, b) = p.block(s, o.len() / k.max(1));
                    for (r, o) in o.chunks_exact_mut(k.max(1)).enumerate() {
                        let l = match per_row {
                            true => nm.index_axis(numpy::ndarray::Axis(0), s + r),
                            false => nm.view(),
                        };
                        for (o, &x) in o.iter_mut().zip(l.iter()) {
                            *o = brdf.eval_wavelength(a[r], b[r], x) as f32;
                        }
                    }
                })
            })?;
            drop(w);
            self.check_loaded()?;
            Ok(out.into_any().unbind())
        })
    }

    /// The density (1/sr, solid angle) with which `sample(wo, u)` draws wi: float64 (n,).
    fn pdf(
        &self,
        py: Python<'_>,
        wi: &Bound<'_, PyAny>,
        wo: &Bound<'_, PyAny>,
    ) -> PyResult<Py<PyAny>> {
        guard(|| {
            let (a, b) = (Rows::<DVec3>::new(wi, "wi")?, Rows::<DVec3>::new(wo, "wo")?);
            let p = Pairs::new(&a, "wi", &b, "wo")?;
            let shape: &[usize] = if p.single { &[] } else { &[p.n] };
            let out = arrays::zeros::<f64>(py, shape)?;
            let mut w = out.readwrite();
            let o = w
                .as_slice_mut()
                .map_err(|e| Error::new_err(e.to_string()))?;
            let brdf = &self.inner;
            batch(py, p.n, || p.run(o, 1, |a, b, o| brdf.pdf_batch(a, b, o)))?;
            drop(w);
            self.check_loaded()?;
            Ok(out.into_any().unbind())
        })
    }

    /// Draws wi for each wo from uniform numbers u in [0, 1)² (shape (n, 2)); returns
    /// (wi (n, 3) float64, pdf (n,) float64, weight (n, c) float32) with
    /// weight = f_r cos θi / pdf (`brdftab sample`'s conventions). Where no direction can be
    /// drawn (wo below the horizon, NaN, infinite or zero) wi, pdf and weight are 0; `u`
    /// outside [0, 1) (NaN included) is a `ValueError`.
    fn sample(
        &self,
        py: Python<'_>,
        wo: &Bound<'_, PyAny>,
        u: &Bound<'_, PyAny>,
    ) -> PyResult<Py<PyTuple>> {
        guard(|| {
            let (a, b) = (Rows::<DVec3>::new(wo, "wo")?, Rows::<DVec2>::new(u, "u")?);
            let uu = b.as_slice();
            for (k, u) in uu.iter().enumerate() {
                if let Some(x) = [u.x, u.y].into_iter().find(|x| !(0.0..1.0).contains(x)) {
                    return Err(PyValueError::new_err(format!(
                        "u: row {k}: {x} is outside [0, 1)"
                    )));
                }
            }
            let p = Pairs::new(&a, "wo", &b, "u")?;
            let (n, c) = (p.n, self.c());
            let (s3, s1, sc): (&[usize], &[usize], &[usize]) = match p.single {
                true => (&[3], &[], &[c]),
                false => (&[n, 3], &[n], &[n, c]),
            };
            let (wi, pdf, weight) = (
                arrays::zeros::<f64>(py, s3)?,
                arrays::zeros::<f64>(py, s1)?,
                arrays::zeros::<f32>(py, sc)?,
            );
            let (mut wi_w, mut pdf_w, mut w_w) =
                (wi.readwrite(), pdf.readwrite(), weight.readwrite());
            let slice_err = |e: numpy::NotContiguousError| Error::new_err(e.to_string());
            let wi_s = wi_w.as_slice_mut().map_err(slice_err)?;
            let pdf_s = pdf_w.as_slice_mut().map_err(slice_err)?;
            let w_s = w_w.as_slice_mut().map_err(slice_err)?;
            // wi as rows: a fresh C-contiguous float64 array, aligned by numpy's allocator.
            let wi_s = arrays::as_rows_mut(wi_s)?;
            let brdf = &self.inner;
            batch(py, n, || match p.whole() {
                Some((a, b)) => brdf.sample_batch(
                    a,
                    b,
                    SampleOut {
                        wi: wi_s,
                        pdf: pdf_s,
                        weight: w_s,
                    },
                ),
                None => {
                    let cw = c.max(1);
                    let go = |(k, ((wi, pd), w)): SampleBlock<'_>| {
                        let (a, b) = p.block(k * BLOCK, pd.len());
                        brdf.sample_batch(
                            a,
                            b,
                            SampleOut {
                                wi,
                                pdf: pd,
                                weight: w,
                            },
                        )
                    };
                    if n >= brdftab::batch::PARALLEL {
                        brdftab::par::install(|| {
                            wi_s.par_chunks_mut(BLOCK)
                                .zip(pdf_s.par_chunks_mut(BLOCK))
                                .zip(w_s.par_chunks_mut(BLOCK * cw))
                                .enumerate()
                                .for_each(go)
                        })
                    } else {
                        wi_s.chunks_mut(BLOCK)
                            .zip(pdf_s.chunks_mut(BLOCK))
                            .zip(w_s.chunks_mut(BLOCK * cw))
                            .enumerate()
                            .for_each(go)
                    }
                }
            })?;
            drop((wi_w, pdf_w, w_w));
            self.check_loaded()?;
            Ok(PyTuple::new(py, [wi.into_any(), pdf.into_any(), weight.into_any()])?.unbind())
        })
    }

    /// Directional albedo ∫ f_r cos θo dωo at incidence angles θ′ (radians, in [0, π/2): light
    /// above the horizon; else ValueError naming theta):
    /// float64 (k, c) (or (c,) for a scalar θ′). A closed form where the model has one, else
    /// adaptive quadrature: 1e-6 relative for models, 1e-4 for tables and measured data.
    fn albedo(&self, py: Python<'_>, theta: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        guard(|| {
            let a = arrays::f64_array(theta, "theta")?;
            let single = a.ndim() == 0;
            if a.ndim() > 1 {
                return Err(PyValueError::new_err(format!(
                    "theta: expected a number or a 1-d array, got shape {}",
                    arrays::shape_str(a.shape())
                )));
            }
            // Read in place and written into the numpy result, allocated (or refused by numpy)
            // before the angles are checked: a broadcast `theta` of any length is no copy.
            let t = a.as_array();
            let (k, c) = (t.len(), self.c());
            let shape: &[usize] = if single { &[c] } else { &[k, c] };
            let out = arrays::zeros::<f64>(py, shape)?;
            use brdftab::analysis::albedo::incidence;
            for &x in t.iter() {
                incidence(x).map_err(lib_err)?;
            }
            let mut w = out.readwrite();
            let o = w
                .as_slice_mut()
                .map_err(|e| Error::new_err(e.to_string()))?;
            let brdf = &self.inner;
            // What `albedo::albedo_curve` computes, angle by angle into the result.
            unlocked(py, || {
                for (row, &x) in o.chunks_exact_mut(c.max(1)).zip(t.iter()) {
                    if let Ok(wi) = incidence(x) {
                        brdf.albedo(wi, row);
                    }
                }
            })?;
            drop(w);
            self.check_loaded()?;
            Ok(out.into_any().unbind())
        })
    }

    /// A table SOURCE's device layout for this BRDF's interpolation (`Table.device_layout`),
    /// without the copy `table().device_layout()` makes: the decoded table moves into it.
    /// Raises `brdftab.Error` for any other source (bake it: `table(...).device_layout()`).
    fn device_layout(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        guard(|| {
            let Some(t) = &self.table else {
                return Err(Error::new_err(format!(
                    "{}: not a table (use Brdf.table(...).device_layout())",
                    self.source
                )));
            };
            let t = t.clone();
            let d = unlocked(py, move || t.device_layout())?.map_err(lib_err)?;
            layout_dict(py, d, self.inner.channels())
        })
    }

    /// The node densities of the library's importance sampler (`brdftab.table.SamplingNodes`
    /// in Rust): {"version": 2, "nx", "ny", "nt", "np", "isotropic", "data": float32 array
    /// (nt·np, ny, nx), "alias": {...}} — g(s, y) of f_r cos θ over the half-vector square
    /// (s → θh = (π/2)(0.1 s + 0.9 s²), y → φh = 2π y − π relative to the conditioning
    /// direction's azimuth) at nt conditioning nodes uniform in t = sqrt(1 − cos θ) (times np
    /// over φ for anisotropic sources), and the library's constant-time draw of them
    /// (`brdftab.table.AliasTables`): {"other_bits", "pdf": float32 (nt·np, ny, nx)
    /// normalized, "strips": uint32 (nt·np, 2(ny − 1)), "cells": uint32 (nt·np, ny, nx − 1)}.
    /// `adjoint=True` conditions on wi and weights by cos θo (Mitsuba's convention: draw wo
    /// given wi). For hosts that sample on a device (the Mitsuba plugin).
    #[pyo3(signature = (adjoint=false, theta_h=64, phi_h=64, theta_o=32, phi_o=16))]
    fn sampling_nodes(
        &self,
        py: Python<'_>,
        adjoint: bool,
        theta_h: usize,
        phi_h: usize,
        theta_o: usize,
        phi_o: usize,
    ) -> PyResult<Py<PyAny>> {
        guard(|| {
            use brdftab::table::{Adjoint, SamplingNodes, SamplingResolution};
            let nodes = [theta_h, phi_h, theta_o, phi_o]
                .iter()
                .try_fold(1usize, |a, &x| a.checked_mul(x.max(1)));
            if nodes.is_none_or(|n| n > 1 << 26) {
                return Err(PyValueError::new_err(
                    "theta_h·phi_h·theta_o·phi_o: at most 2^26 nodes",
                ));
            }
            let res = SamplingResolution {
                theta_h,
                phi_h,
                theta_o,
                phi_o,
                ..SamplingResolution::default()
            };
            let iso = self.inner.flags().isotropic;
            let brdf: &dyn Brdf = self.inner.as_ref();
            let n = unlocked(py, || match adjoint {
                true => SamplingNodes::build_par(&Adjoint(brdf), iso, &res),
                false => SamplingNodes::build_par(brdf, iso, &res),
            })?;
            self.check_loaded()?;
            let a = unlocked(py, || n.alias())?;
            let slices = n.nt * n.np;
            let shape = [slices, n.ny, n.nx];
            let array = |shape: &[usize], v: Vec<f32>| {
                ArrayD::from_shape_vec(IxDyn(shape), v).map_err(|e| Error::new_err(e.to_string()))
            };
            let entries = |shape: &[usize], v: Vec<u32>| {
                ArrayD::from_shape_vec(IxDyn(shape), v).map_err(|e| Error::new_err(e.to_string()))
            };
            let alias = PyDict::new(py);
            alias.set_item("other_bits", a.other_bits)?;
            alias.set_item("pdf", array(&shape, a.pdf)?.into_pyarray(py))?;
            let strips = entries(&[slices, 2 * (n.ny - 1)], a.strips)?;
            alias.set_item("strips", strips.into_pyarray(py))?;
            let cells = entries(&[slices, n.ny, n.nx - 1], a.cells)?;
            alias.set_item("cells", cells.into_pyarray(py))?;
            let data = array(&shape, n.data)?.into_pyarray(py);
            let d = PyDict::new(py);
            d.set_item("version", 2)?;
            d.set_item("nx", n.nx)?;
            d.set_item("ny", n.ny)?;
            d.set_item("nt", n.nt)?;
            d.set_item("np", n.np)?;
            d.set_item("isotropic", n.isotropic)?;
            d.set_item("data", data)?;
            d.set_item("alias", alias)?;
            Ok(d.into_any().unbind())
        })
    }

    /// The decoded table as a `brdftab.Table`: `values` (float32, shaped by the stored axes
    /// and the channels, λ innermost; flat for a packed `inout` reciprocal table) shares the
    /// table's memory, read-only; `grid` describes it. Unpacks as `values, grid = b.table()`.
    /// A table SOURCE gives its stored table; any other source is baked in memory with
    /// `options` (the keywords of `brdftab.bake`).
    #[pyo3(signature = (**options))]
    fn table(&self, py: Python<'_>, options: Option<&Bound<'_, PyDict>>) -> PyResult<PyTable> {
        guard(|| {
            let table = match (&self.table, options.is_some_and(|o| !o.is_empty())) {
                (Some(t), false) => {
                    let t = t.clone();
                    unlocked(py, move || t.to_table())?.map_err(lib_err)?
                }
                _ => {
                    let settings: BakeSettings = settings_of(options)?;
                    let mut req = settings.request(&self.source).map_err(lib_err)?;
                    if let (Some(w), None) = (&self.wavelengths, &settings.wavelengths) {
                        req.channels = Some(Channels::wavelengths(w.clone()).map_err(lib_err)?);
                    }
                    unlocked(py, || req.table(&brdftab::progress::Silent))?
                        .map_err(lib_err)?
                        .0
                }
            };
            let grid = table.grid().clone();
            let mut g = serde_json::to_value(&grid).map_err(|e| Error::new_err(e.to_string()))?;
            g["stored_axes"] = serde_json::to_value(grid.stored_axes())
                .map_err(|e| Error::new_err(e.to_string()))?;
            g["stored_shape"] = serde_json::json!(grid.stored_shape());
            g["packed"] = serde_json::json!(grid.layout().packed);
            g["channel_names"] = serde_json::json!(grid.channels().names());
            g["description"] = serde_json::json!(table.description());
            Ok(PyTable {
                grid: to_py(py, &g)?,
                table,
            })
        })
    }

    fn __reduce__(&self, py: Python<'_>) -> PyResult<Py<PyTuple>> {
        let module = py.import("brdftab._native")?;
        let f = module.getattr("_reopen")?;
        let args = (
            self.source.clone(),
            self.interp.clone(),
            self.wavelengths.clone(),
            self.eager,
        )
            .into_pyobject(py)?;
        Ok(PyTuple::new(py, [f, args.into_any()])?.unbind())
    }
}

/// A Python value as JSON for the request layer: None, bools, ints, floats, strings, and lists,
/// tuples, dicts and numpy arrays or scalars of those (through `tolist`).
fn json_of(key: &str, v: &Bound<'_, PyAny>) -> PyResult<serde_json::Value> {
    use pyo3::types::{PyBool, PyFloat, PyInt, PyList, PyString};
    use serde_json::Value;
    if v.is_none() {
        return Ok(Value::Null);
    }
    if v.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return match v.extract::<i64>() {
            Ok(i) => Ok(Value::from(i)),
            Err(_) => Ok(Value::from(v.extract::<u64>().map_err(|_| {
                PyValueError::new_err(format!("{key}: integer out of range"))
            })?)),
        };
    }
    if v.is_instance_of::<PyFloat>() {
        let x: f64 = v.extract()?;
        return serde_json::Number::from_f64(x)
            .map(Value::Number)
            .ok_or_else(|| PyValueError::new_err(format!("{key}: {x}: expected a finite number")));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut m = serde_json::Map::new();
        for (k, x) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| PyTypeError::new_err(format!("{key}: keys must be strings")))?;
            let inner = json_of(&format!("{key}.{k}"), &x)?;
            m.insert(k, inner);
        }
        return Ok(Value::Object(m));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        return v
            .try_iter()?
            .enumerate()
            .map(|(i, x)| json_of(&format!("{key}[{i}]"), &x?))
            .collect::<PyResult<Vec<_>>>()
            .map(Value::Array);
    }
    if v.hasattr("tolist")? {
        let t = v.call_method0("tolist")?;
        if !t.is(v) {
            return json_of(key, &t);
        }
    }
    Err(PyTypeError::new_err(format!(
        "{key}: unsupported type {}",
        v.get_type().name()?
    )))
}

/// Keyword arguments as settings of the request layer ([`brdftab::request`]): the same field
/// names and the same validation as the CLI's flags and the C ABI's JSON. An unknown keyword is
/// a `TypeError`, as Python's own; a value of the wrong type a `TypeError` naming the field,
/// any other bad value a `ValueError` naming it.
fn settings_of<T>(options: Option<&Bound<'_, PyDict>>) -> PyResult<T>
where
    T: serde::de::DeserializeOwned + serde::Serialize + Default,
{
    let Some(opts) = options else {
        return Ok(T::default());
    };
    let known = brdftab::request::field_names::<T>();
    let mut map = serde_json::Map::new();
    for (k, v) in opts.iter() {
        let key: String = k.extract()?;
        if !known.contains(&key) {
            return Err(PyTypeError::new_err(format!(
                "unexpected keyword argument '{key}'"
            )));
        }
        map.insert(key.clone(), json_of(&key, &v)?);
    }
    brdftab::request::from_value(serde_json::Value::Object(map)).map_err(|e| match e {
        brdftab::Error::InvalidArgument { ref msg, .. } if msg.starts_with("invalid type") => {
            PyTypeError::new_err(e.to_string())
        }
        e => lib_err(e),
    })
}

/// A SOURCE or OUTPUT argument: a `str` (a spec, a path, `DB#NAME`) or an `os.PathLike`
/// whose `os.fspath` is a `str` (a `pathlib.Path`); anything else is a `TypeError`.
fn text_arg(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<String> {
    use pyo3::types::PyString;
    if obj.is_instance_of::<PyString>() {
        return obj.extract::<String>();
    }
    if obj.hasattr("__fspath__")? {
        let p = obj.py().import("os")?.call_method1("fspath", (obj,))?;
        return p.extract::<String>().map_err(|_| {
            PyTypeError::new_err(format!("{what}: a bytes path is not supported; pass a str"))
        });
    }
    Err(PyTypeError::new_err(format!(
        "{what}: expected a str or an os.PathLike, got {}",
        obj.get_type().name()?
    )))
}

/// Opens SOURCE (a spec, table, `DB#NAME`, MERL `.binary` or RGL `.bsdf`) as a `Brdf`.
#[pyfunction]
#[pyo3(signature = (source, *, interp = "auto", wavelengths = None, eager = true))]
fn open(
    source: &Bound<'_, PyAny>,
    interp: &str,
    wavelengths: Option<&Bound<'_, PyAny>>,
    eager: bool,
) -> PyResult<PyBrdf> {
    guard(|| {
        let source = text_arg(source, "source")?;
        PyBrdf::open(&source, interp, channels_of(wavelengths)?, eager)
    })
}

/// Unpickling: reopens a `Brdf` from its source and options.
#[pyfunction]
#[pyo3(signature = (source, interp, wavelengths, eager = true))]
fn _reopen(
    source: &str,
    interp: &str,
    wavelengths: Option<Vec<f64>>,
    eager: bool,
) -> PyResult<PyBrdf> {
    guard(|| {
        let ch = wavelengths
            .map(Channels::wavelengths)
            .transpose()
            .map_err(lib_err)?;
        PyBrdf::open(source, interp, ch, eager)
    })
}

/// The plausibility report of SOURCE as a dict with the keys of `brdftab check --json`.
#[pyfunction]
#[pyo3(signature = (source, *, wavelengths = None))]
fn check(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    wavelengths: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyAny>> {
    guard(|| {
        let source = text_arg(source, "source")?;
        let source = source.as_str();
        let opts = OpenOptions {
            channels: channels_of(wavelengths)?,
            ..OpenOptions::default()
        };
        let brdf = brdftab::open_with(source, &opts).map_err(lib_err)?;
        let report = unlocked(py, || {
            brdftab::analysis::plausibility::check(
                brdf.as_ref(),
                &brdftab::analysis::plausibility::Options::default(),
            )
        })?
        .map_err(lib_err)?;
        ser(py, &report)
    })
}

/// What `brdftab info --json` reports of a brdftab file (`FILE`) or one table (`DB#NAME`).
#[pyfunction]
fn info(py: Python<'_>, source: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
    guard(|| {
        let source = text_arg(source, "source")?;
        let source = source.as_str();
        to_py(
            py,
            &brdftab::store::info::file_info(source).map_err(lib_err)?,
        )
    })
}

/// The names of the tables of database `path`, in file order.
#[pyfunction]
fn db_names(path: &str) -> PyResult<Vec<String>> {
    guard(|| {
        Ok(brdftab::store::db::list(path)
            .map_err(lib_err)?
            .into_iter()
            .map(|(e, _)| e.name)
            .collect())
    })
}

/// Checks a table name against the library's rule ([`brdftab::store::name::check`]):
/// `ValueError` naming `name` for an empty name or one with `#`, `/` or a control character.
#[pyfunction]
fn _check_table_name(name: &str) -> PyResult<()> {
    guard(|| brdftab::store::name::check("name", name).map_err(lib_err))
}

/// Removes table `name` from database `path`.
#[pyfunction]
fn db_remove(path: &str, name: &str) -> PyResult<()> {
    guard(|| brdftab::store::db::remove(path, name).map_err(lib_err))
}

/// Adds the table of a single-table file's bytes (what `bake` writes to a `.btdb` path) to
/// database `path` as `name`, copying its encoded chunks (no re-encoding; checksums checked).
///
/// `data` is read where it is: a `bytes` object is immutable, and the `PyBackedBytes` keeps it
/// alive while the store reads it. (It was extracted into a `Vec<u8>`, a copy whose allocation
/// failure aborts the process rather than raising MemoryError: a table near the size of memory
/// killed the interpreter.) Anything else is the wrapper's to turn into `bytes`.
#[pyfunction]
#[pyo3(signature = (path, name, data, replace=false))]
fn db_import(
    py: Python<'_>,
    path: &str,
    name: &str,
    data: Bound<'_, PyBytes>,
    replace: bool,
) -> PyResult<()> {
    guard(|| {
        let opts = brdftab::store::StoreOptions {
            eager: false,
            ..Default::default()
        };
        let data = pyo3::pybacked::PyBackedBytes::from(data);
        unlocked(py, || {
            let s = brdftab::store::Store::from_bytes("<bytes>", data, opts)?;
            let from = s.single()?.header().name.clone();
            brdftab::store::db::import(path, &s, &from, name, replace)
        })?
        .map_err(lib_err)
    })
}

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
    to_py(py, &info)
}

/// Bakes SOURCE into OUTPUT: a `.btdb` file, or `DB#NAME` (a table of a database). The
/// keywords are the fields of [`BakeSettings`] (the CLI's `bake` flags, snake_cased). Returns
/// what `brdftab info --json OUTPUT` reports.
#[pyfunction]
#[pyo3(signature = (source, output, **options))]
fn bake(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    output: &Bound<'_, PyAny>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    guard(|| {
        let (source, output) = (text_arg(source, "source")?, text_arg(output, "output")?);
        let (source, output) = (source.as_str(), output.as_str());
        let settings: BakeSettings = settings_of(options)?;
        let r = unlocked(py, || {
            request::bake(source, output, &settings, &brdftab::progress::Silent)
        })?
        .map_err(lib_err)?;
        report_dict(py, &r)
    })
}

/// The table of SOURCE baked with `options` (the keywords of `bake`), from the cache of baked
/// tables or baked into it now ([`brdftab::cache`]): keyed by the source's content, the
/// settings and the library's version, in `cache_dir` (default `$BRDFTAB_CACHE_DIR`, else
/// `$XDG_CACHE_HOME/brdftab`, else `~/.cache/brdftab`). Safe under concurrent calls from many
/// processes. `refresh=True` bakes again (for a cached file that failed to open). Returns
/// `{"path": str, "hit": bool}`; open the table with `brdftab.open(path)`.
#[pyfunction]
#[pyo3(signature = (source, cache_dir=None, refresh=false, **options))]
fn bake_cached(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    cache_dir: Option<std::path::PathBuf>,
    refresh: bool,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    guard(|| {
        let source = text_arg(source, "source")?;
        let source = source.as_str();
        let settings: BakeSettings = settings_of(options)?;
        let c = unlocked(py, || {
            brdftab::cache::bake_cached(source, &settings, cache_dir.as_deref(), refresh)
        })?
        .map_err(lib_err)?;
        let v = serde_json::json!({"path": c.path.to_string_lossy(), "hit": c.hit});
        to_py(py, &v)
    })
}

/// Converts SOURCE into OUTPUT as `brdftab convert` does ([`request::convert`]): an RGL
/// `.bsdf`, a MERL `.binary`, `DB#NAME`, a `.btdb` file (a table named after the input) or a raw
/// table. The keywords are the fields of [`ConvertSettings`].
#[pyfunction]
#[pyo3(signature = (source, output, **options))]
fn convert(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    output: &Bound<'_, PyAny>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    guard(|| {
        let (source, output) = (text_arg(source, "source")?, text_arg(output, "output")?);
        let (source, output) = (source.as_str(), output.as_str());
        let settings: ConvertSettings = settings_of(options)?;
        let out = unlocked(py, || {
            request::convert(source, output, &settings, &brdftab::progress::Silent)
        })?
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
                    "output": output,
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
                return Ok(d);
            }
        };
        to_py(py, &d)
    })
}

/// Fits `model` (a name such as "ggx", a sum "lambert+ggx", or a JSON spec) to SOURCE; returns
/// the dict of `brdftab fit --json`. The keywords are the fields of [`FitSettings`].
#[pyfunction]
#[pyo3(signature = (source, model, **options))]
fn fit(
    py: Python<'_>,
    source: &Bound<'_, PyAny>,
    model: &str,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<Py<PyAny>> {
    guard(|| {
        let source = text_arg(source, "source")?;
        let source = source.as_str();
        let settings: FitSettings = settings_of(options)?;
        let result = unlocked(py, || {
            request::fit(source, model, &settings, &brdftab::progress::Silent)
        })?
        .map_err(lib_err)?;
        ser(py, &result)
    })
}

/// The extension module.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("Error", m.py().get_type::<Error>())?;
    m.add_class::<PyBrdf>()?;
    m.add_class::<PyTable>()?;
    m.add_function(wrap_pyfunction!(open, m)?)?;
    m.add_function(wrap_pyfunction!(_reopen, m)?)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(info, m)?)?;
    m.add_function(wrap_pyfunction!(db_names, m)?)?;
    m.add_function(wrap_pyfunction!(db_remove, m)?)?;
    m.add_function(wrap_pyfunction!(_check_table_name, m)?)?;
    m.add_function(wrap_pyfunction!(db_import, m)?)?;
    m.add_function(wrap_pyfunction!(bake, m)?)?;
    m.add_function(wrap_pyfunction!(bake_cached, m)?)?;
    m.add_function(wrap_pyfunction!(convert, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
