//! The `brdftab.Table` class (a decoded table: its values shared with numpy, its grid as a
//! dict; edited values back in with `with_values`, written with `save`, looked up with `open`)
//! and the dict of a device layout, which both `Table.device_layout` and `Brdf.device_layout`
//! return.
//!
//! Why a module: these are what a host takes away to evaluate a table elsewhere (a GPU, a JIT)
//! or to edit it (numpy, an optimizer): values, grid and layout, held apart from the `Brdf`
//! that made them.

use brdftab::Channels;
use brdftab::request::{self, SaveSettings};
use brdftab::store::Source;
use brdftab::table::device::DeviceLayout;
use brdftab::table::{Interp, Table};
use numpy::ndarray::IxDyn;
use numpy::{IntoPyArray, PyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::arrays::f32_array;
use crate::brdf::PyBrdf;
use crate::errors::{Error, guard, interruptible, lib_err, unlocked};
use crate::values::{exact_path, file_part, path_arg, settings_of, to_py};

/// A decoded table (`Brdf.table()`): its values as a numpy array sharing the table's memory,
/// and its grid.
#[pyclass(name = "Table", module = "brdftab", frozen)]
pub(crate) struct PyTable {
    table: Table,
    grid: Py<PyAny>,
}

impl PyTable {
    /// `Brdf.table`'s result: `table` and its grid as the dict `grid` returns.
    pub(crate) fn new(py: Python<'_>, table: Table) -> PyResult<PyTable> {
        let grid = table.grid().clone();
        let mut g = serde_json::to_value(&grid).map_err(|e| Error::new_err(e.to_string()))?;
        g["stored_axes"] =
            serde_json::to_value(grid.stored_axes()).map_err(|e| Error::new_err(e.to_string()))?;
        g["stored_shape"] = serde_json::json!(grid.stored_shape());
        // The grid's serialization leaves out defaults (an f_r table, no calibration); the
        // dict names them, as its docs list them.
        g["quantity"] =
            serde_json::to_value(grid.quantity()).map_err(|e| Error::new_err(e.to_string()))?;
        if g.get("calibration").is_none() {
            g["calibration"] = serde_json::Value::Null;
        }
        g["packed"] = serde_json::json!(grid.layout().packed);
        g["channel_names"] = serde_json::json!(grid.channels().names());
        g["description"] = serde_json::json!(table.description());
        Ok(PyTable {
            grid: to_py(py, &g)?,
            table,
        })
    }
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
    /// library's device layout (Rust `brdftab::table::device`), a dict with
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

    /// The same table — grid (stored layout, symmetry, quantity, albedo calibration) — holding
    /// `values`: any array-like of real numbers shaped as `values` is (the stored axes and
    /// channels; for a packed table the flat values, or the rectangle `brdftab export --npy`
    /// writes, whose unstored nodes are ignored), flat, or (nodes, c) — a row per stored node,
    /// as `eval(*node_directions())` gives for a packed table — converted to float32 in C
    /// order.
    /// The values are the stored quantity before the albedo calibration, as `values` gives
    /// them; negative values mark unmeasured nodes in a table of f_r (lookups read 0 there).
    /// `calibration=False` drops the grid's albedo calibration (for another material's values
    /// on this grid: its factors pinned the first material's albedo). A wrong size or shape, or
    /// a NaN or infinite stored value, is a `ValueError` naming `values` and the index.
    #[pyo3(signature = (values, *, calibration = true))]
    fn with_values(
        &self,
        py: Python<'_>,
        values: &Bound<'_, PyAny>,
        calibration: bool,
    ) -> PyResult<PyTable> {
        guard(|| {
            let a = f32_array(values, "values")?;
            let shape = a.shape().to_vec();
            // In C order: a Fortran-order or strided array by its indices, not its memory.
            let data: Vec<f32> = match a.as_slice() {
                Ok(s) if a.is_c_contiguous() => s.to_vec(),
                _ => a.as_array().iter().copied().collect(),
            };
            drop(a);
            let old = &self.table;
            let description = format!("values from Python on the grid of {}", old.description());
            let t = unlocked(py, || old.with_array(&shape, data))?
                .map_err(lib_err)?
                .with_description(description);
            let t = match calibration {
                true => t,
                false => {
                    let (grid, values, description) = t.into_parts();
                    Table::new(grid.without_calibration(), values, description).map_err(lib_err)?
                }
            };
            PyTable::new(py, t)
        })
    }

    /// Writes the table to `output` (a `str`, `bytes` or `os.PathLike`; the name need not be
    /// UTF-8): a `.btdb` file (replaced atomically) or "DB#NAME" (a table of a database,
    /// created if absent; an existing name needs `replace=True`). The
    /// keywords are those of `brdftab.bake` that say how a table is stored: `codec` ("f32"
    /// keeps the values bit for bit; default "log16", 1e-3 relative), `codec_tolerance`,
    /// `floor`, `level`, `exhaustive`, `name` (a `.btdb` file's table, default the file's
    /// stem; beside "DB#NAME" it may only repeat NAME, another is a `ValueError`) and
    /// `replace`. The provenance is the table's description. Returns what `brdftab info --json
    /// OUTPUT` reports.
    #[pyo3(signature = (output, **options))]
    fn save(
        &self,
        py: Python<'_>,
        output: &Bound<'_, PyAny>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Py<PyAny>> {
        guard(|| {
            let output = path_arg(output, "output")?;
            let settings: SaveSettings = settings_of(options)?;
            let source = Source::Other {
                description: self.table.description().to_owned(),
            };
            let t = &self.table;
            let info = interruptible(py, |p| {
                request::save_table_with(t, &output, source, &settings, p)
            })?
            .map_err(lib_err)?;
            let d = to_py(py, &info)?;
            exact_path(d.bind(py), "file", &[file_part(&output)])?;
            Ok(d)
        })
    }

    /// The table as a `brdftab.Brdf` (in memory: a copy of its values), looked up with
    /// `interp` ("auto": nearest on a grid of MERL cells, linear otherwise; "nearest";
    /// "linear"), as `brdftab.open` of the saved table would. It has no SOURCE to reopen:
    /// it does not pickle, and `table(**options)` does not bake it again. Like the node
    /// methods below, it runs with the GIL released (a large table: a quarter of a second).
    #[pyo3(signature = (interp = "auto"))]
    fn open(&self, py: Python<'_>, interp: &str) -> PyResult<PyBrdf> {
        guard(|| {
            let t = &self.table;
            unlocked(py, || PyBrdf::from_table(t.clone(), interp))?
        })
    }

    /// The coordinates of every stored node, in radians: float64 shaped like `values` with
    /// the channels replaced by the parameterization's four angles (`grid["param"]`:
    /// "halfdiff" θh, φh, θd, φd; "inout" θi, φi, θo, φo — an isotropic table's φi is 0 and its
    /// φo the azimuth difference), flat (nodes × 4) for a packed table.
    fn node_angles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        guard(|| {
            let grid = self.table.grid();
            let angles = unlocked(py, || {
                let a = grid.stored_node_angles();
                a.into_iter().flatten().collect()
            })?;
            node_array(py, &self.table, angles, 4)
        })
    }

    /// The direction pair of every stored node: `(wi, wo)`, unit float64 vectors shaped like
    /// `node_angles` with 3 components, as `Brdf.eval(wi, wo)` takes them — so a source can be
    /// evaluated at a table's nodes in numpy. Nodes outside the physical domain (kept for
    /// interpolation next to the horizon) have a direction at or below it (z ≤ 0), where
    /// `eval` gives 0.
    fn node_directions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        guard(|| {
            let grid = self.table.grid();
            let (wi, wo) = unlocked(py, || {
                let (mut wi, mut wo) = (Vec::new(), Vec::new());
                for c in grid.stored_node_angles() {
                    let (i, o) = brdftab::table::node_pair(grid.param(), c);
                    wi.extend(i.to_array());
                    wo.extend(o.to_array());
                }
                (wi, wo)
            })?;
            let wi = node_array(py, &self.table, wi, 3)?;
            let wo = node_array(py, &self.table, wo, 3)?;
            PyTuple::new(py, [wi, wo])
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

    /// The object itself: a `Table` is immutable.
    fn __copy__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    /// The object itself (immutable, as `__copy__`).
    fn __deepcopy__(slf: Py<Self>, _memo: &Bound<'_, PyAny>) -> Py<Self> {
        slf
    }

    fn __repr__(&self) -> String {
        format!(
            "<brdftab.Table {}: {}>",
            self.table.grid().summary(),
            self.table.description()
        )
    }
}

/// `data` (`k` numbers per stored node, in the stored order) as a numpy array shaped like the
/// table's values with the channels replaced by `k`, flat (nodes × k) for a packed layout.
fn node_array<'py>(
    py: Python<'py>,
    table: &Table,
    data: Vec<f64>,
    k: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let mut shape: Vec<usize> = match table.shape() {
        Some(s) => s[..4].to_vec(),
        None => vec![data.len() / k],
    };
    shape.push(k);
    let arr = numpy::ndarray::ArrayD::from_shape_vec(IxDyn(&shape), data)
        .map_err(|e| Error::new_err(e.to_string()))?;
    Ok(arr.into_pyarray(py).into_any())
}

/// A device layout as the dict `Table.device_layout` and `Brdf.device_layout` return: its
/// fields as JSON values, "channel_names", and each value array moved into numpy (no copy).
pub(crate) fn layout_dict(
    py: Python<'_>,
    d: DeviceLayout,
    channels: &Channels,
) -> PyResult<Py<PyAny>> {
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
