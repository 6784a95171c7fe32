//! Values of f_r: `Brdf.eval` and `Brdf.eval_spectral` at direction pairs, written straight
//! into the numpy results with the GIL released, and `Brdf.albedo` (f_r cos θo integrated).
//!
//! Why a module: these are the BRDF's values, as opposed to its sampler (`sample.rs`) and the
//! tables a host takes away (`tables.rs`).

use glam::DVec3;
use numpy::{PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::PyBrdf;
use crate::arrays::{self, Pairs};
use crate::errors::{Error, batch, lib_err, unlocked};

impl PyBrdf {
    /// `Brdf.eval`'s body, run under `guard` (documented on the method, in `mod.rs`).
    pub(super) fn eval_pairs(
        &self,
        py: Python<'_>,
        wi: &Bound<'_, PyAny>,
        wo: &Bound<'_, PyAny>,
    ) -> PyResult<Py<PyAny>> {
        let (a, b) = arrays::pair_rows::<DVec3, DVec3>(wi, "wi", wo, "wo")?;
        let p = Pairs::new(&a, "wi", &b, "wo")?;
        let c = self.c();
        let out = arrays::zeros::<f32>(py, &p.shape(&[c]))?;
        let mut w = out.readwrite();
        let o = w
            .as_slice_mut()
            .map_err(|e| Error::new_err(e.to_string()))?;
        let brdf = &self.inner;
        batch(py, p.n, || p.run(o, c, |a, b, o| brdf.eval_batch(a, b, o)))?;
        drop(w);
        self.check_loaded()?;
        Ok(out.into_any().unbind())
    }

    /// `Brdf.eval_spectral`'s body, run under `guard` (documented on the method, in `mod.rs`).
    pub(super) fn eval_spectral_pairs(
        &self,
        py: Python<'_>,
        wi: &Bound<'_, PyAny>,
        wo: &Bound<'_, PyAny>,
        nm: &Bound<'_, PyAny>,
    ) -> PyResult<Py<PyAny>> {
        let (a, b) = arrays::pair_rows::<DVec3, DVec3>(wi, "wi", wo, "wo")?;
        let p = Pairs::new(&a, "wi", &b, "wo")?;
        let n = p.n;
        let (k, per_row, l) = arrays::wavelength_rows(arrays::f64_array(nm, "nm")?, &p.lead)?;
        // Read in place: a broadcast `nm` (numpy.broadcast_to) of any length is no copy,
        // and the output is allocated (or refused by numpy) before its entries are checked.
        let nm = l.as_array();
        let out = arrays::zeros::<f32>(py, &p.shape(&[k]))?;
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
                let mut scratch = arrays::Scratch::default();
                let (a, b) = p.block(s, o.len() / k.max(1), &mut scratch);
                for (r, o) in o.chunks_exact_mut(k.max(1)).enumerate() {
                    let l = match per_row {
                        true => nm.index_axis(numpy::ndarray::Axis(0), s + r),
                        false => nm.view(),
                    };
                    match l.as_slice() {
                        // One lookup for every wavelength where the source allows it.
                        Some(l) => brdf.eval_at_wavelengths(a[r], b[r], l, o),
                        None => {
                            for (o, &x) in o.iter_mut().zip(l.iter()) {
                                *o = brdf.eval_wavelength(a[r], b[r], x) as f32;
                            }
                        }
                    }
                }
            })
        })?;
        drop(w);
        self.check_loaded()?;
        Ok(out.into_any().unbind())
    }

    /// `Brdf.albedo`'s body, run under `guard` (documented on the method, in `mod.rs`).
    pub(super) fn albedo_curve(
        &self,
        py: Python<'_>,
        theta: &Bound<'_, PyAny>,
        phi: f64,
    ) -> PyResult<Py<PyAny>> {
        let a = arrays::f64_array(theta, "theta")?;
        // Read in place and written into the numpy result, allocated (or refused by numpy)
        // before the angles are checked: a broadcast `theta` of any length is no copy.
        let t = a.as_array();
        let c = self.c();
        // One row of c per angle, in the angles' shape (a number: (c,)).
        let out = arrays::zeros::<f64>(py, &[a.shape(), &[c]].concat())?;
        use brdftab::analysis::albedo::incidence_at;
        // The azimuth is checked even when there is no angle.
        incidence_at(0.0, phi).map_err(lib_err)?;
        for &x in t.iter() {
            incidence_at(x, phi).map_err(lib_err)?;
        }
        let mut w = out.readwrite();
        let o = w
            .as_slice_mut()
            .map_err(|e| Error::new_err(e.to_string()))?;
        let brdf = &self.inner;
        // What `albedo::albedo_curve` computes, angle by angle into the result, with the GIL
        // released for up to `SLICE` at a time and a pending signal handled between slices:
        // Ctrl-C stops a curve of many angles within a slice and an angle (it ran to the end:
        // 2,000 angles of an RGL file, 190 s), and a closed form's microsecond angles still run
        // a slice per release.
        use crate::errors::SLICE;
        let mut angles = o.chunks_exact_mut(c.max(1)).zip(t.iter()).peekable();
        while angles.peek().is_some() {
            unlocked(py, || {
                let start = std::time::Instant::now();
                for (row, &x) in angles.by_ref() {
                    if let Ok(wi) = incidence_at(x, phi) {
                        brdf.albedo(wi, row);
                    }
                    if start.elapsed() >= SLICE {
                        break;
                    }
                }
            })?;
            py.check_signals()?;
        }
        drop(w);
        self.check_loaded()?;
        Ok(out.into_any().unbind())
    }
}
