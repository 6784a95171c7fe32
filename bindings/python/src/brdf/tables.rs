//! The tables a host takes away from a `Brdf`: `Brdf.table` (the decoded table, or the source
//! baked in memory) and `Brdf.device_layout` (a table source's layout for GPU and JIT hosts,
//! without a copy).
//!
//! Why a module: these hand over whole tables, where `eval.rs` and `sample.rs` answer per
//! direction; the `Table` class they feed is `crate::table`.

use brdftab::Channels;
use brdftab::request::BakeSettings;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::PyBrdf;
use crate::errors::{Error, lib_err, unlocked};
use crate::table::{PyTable, layout_dict};
use crate::values::settings_of;

impl PyBrdf {
    /// `Brdf.table`'s body, run under `guard` (documented on the method, in `mod.rs`).
    pub(super) fn decoded_table(
        &self,
        py: Python<'_>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyTable> {
        let table = match (&self.table, options.is_some_and(|o| !o.is_empty())) {
            (Some(t), false) => {
                let t = t.clone();
                unlocked(py, move || t.to_table())?.map_err(lib_err)?
            }
            _ if self.in_memory => {
                return Err(Error::new_err(format!(
                    "{}: an in-memory table has no SOURCE to bake with options (Table.save it \
                     and brdftab.open the file)",
                    self.source.to_string_lossy()
                )));
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
        PyTable::new(py, table)
    }

    /// `Brdf.device_layout`'s body, run under `guard` (documented on the method, in `mod.rs`).
    pub(super) fn table_device_layout(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let Some(t) = &self.table else {
            return Err(Error::new_err(format!(
                "{}: not a table (use Brdf.table(...).device_layout())",
                self.source.to_string_lossy()
            )));
        };
        let t = t.clone();
        let d = unlocked(py, move || t.device_layout())?.map_err(lib_err)?;
        layout_dict(py, d, self.inner.channels())
    }
}
