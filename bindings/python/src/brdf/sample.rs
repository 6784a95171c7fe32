//! The library's importance sampler: `Brdf.sample` (directions drawn from uniform numbers),
//! `Brdf.pdf` (the density of those draws) and `Brdf.sampling_nodes` (the sampler's node
//! densities and alias tables, for hosts that draw on a device).
//!
//! Why a module: everything about drawing directions is here, apart from f_r's values
//! (`eval.rs`).

use brdftab::Brdf;
use brdftab::batch::{BLOCK, SampleOut};
use glam::{DVec2, DVec3};
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::{IntoPyArray, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use rayon::prelude::*;

use super::PyBrdf;
use crate::arrays::{self, Pairs, Rows};
use crate::errors::{Error, batch, unlocked};

/// One block of `sample`'s outputs, numbered: (block, ((wi, pdf), weights)).
type SampleBlock<'a> = (usize, ((&'a mut [DVec3], &'a mut [f64]), &'a mut [f32]));

/// The same with the draws' delta flags: (block, (((wi, pdf), weights), flags)).
type FlaggedBlock<'a> = (
    usize,
    (
        ((&'a mut [DVec3], &'a mut [f64]), &'a mut [f32]),
        &'a mut [bool],
    ),
);

/// `u` in [0, 1)², row by row: anything else (NaN included) is a `ValueError` naming the row.
/// The rows are read with the GIL released (as `batch` runs a call): 10^7 rows held it for
/// tens of milliseconds, every other Python thread waiting.
fn check_u(py: Python<'_>, u: &Rows<'_, DVec2>) -> PyResult<()> {
    let v = u.view();
    let bad = batch(py, v.len(), || {
        (0..v.len()).find_map(|k| {
            let u = v.row(k);
            [u.x, u.y]
                .into_iter()
                .find(|x| !(0.0..1.0).contains(x))
                .map(|x| (k, x))
        })
    })?;
    match bad {
        Some((k, x)) => Err(PyValueError::new_err(format!(
            "u: row {k}: {x} is outside [0, 1)"
        ))),
        None => Ok(()),
    }
}

impl PyBrdf {
    /// `Brdf.pdf`'s body, run under `guard` (documented on the method, in `mod.rs`).
    pub(super) fn pdf_pairs(
        &self,
        py: Python<'_>,
        wi: &Bound<'_, PyAny>,
        wo: &Bound<'_, PyAny>,
    ) -> PyResult<Py<PyAny>> {
        let (a, b) = arrays::pair_rows::<DVec3, DVec3>(wi, "wi", wo, "wo")?;
        let p = Pairs::new(&a, "wi", &b, "wo")?;
        let out = arrays::zeros::<f64>(py, &p.shape(&[]))?;
        let mut w = out.readwrite();
        let o = w
            .as_slice_mut()
            .map_err(|e| Error::new_err(e.to_string()))?;
        let brdf = &self.inner;
        batch(py, p.n, || p.run(o, 1, |a, b, o| brdf.pdf_batch(a, b, o)))?;
        drop(w);
        self.check_loaded()?;
        Ok(out.into_any().unbind())
    }

    /// `Brdf.sample`'s body, run under `guard` (documented on the method, in `mod.rs`).
    pub(super) fn sample_pairs(
        &self,
        py: Python<'_>,
        wo: &Bound<'_, PyAny>,
        u: &Bound<'_, PyAny>,
    ) -> PyResult<Py<PyTuple>> {
        let (a, b) = arrays::pair_rows::<DVec3, DVec2>(wo, "wo", u, "u")?;
        check_u(py, &b)?;
        let p = Pairs::new(&a, "wo", &b, "u")?;
        let (n, c) = (p.n, self.c());
        let (wi, pdf, weight) = (
            arrays::zeros::<f64>(py, &p.shape(&[3]))?,
            arrays::zeros::<f64>(py, &p.shape(&[]))?,
            arrays::zeros::<f32>(py, &p.shape(&[c]))?,
        );
        let (mut wi_w, mut pdf_w, mut w_w) = (wi.readwrite(), pdf.readwrite(), weight.readwrite());
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
                    let mut scratch = arrays::Scratch::default();
                    let (a, b) = p.block(k * BLOCK, pd.len(), &mut scratch);
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
    }

    /// `Brdf.sample`'s body with `nm` (weights at wavelengths) or `delta` (the draws' delta
    /// flags) asked for: pair by pair through `Brdf::sample_wavelengths` / `Brdf::sample`
    /// (documented on the method, in `mod.rs`).
    pub(super) fn sample_pairs_spectral(
        &self,
        py: Python<'_>,
        wo: &Bound<'_, PyAny>,
        u: &Bound<'_, PyAny>,
        nm: Option<&Bound<'_, PyAny>>,
        want_delta: bool,
    ) -> PyResult<Py<PyTuple>> {
        let (a, b) = arrays::pair_rows::<DVec3, DVec2>(wo, "wo", u, "u")?;
        check_u(py, &b)?;
        let p = Pairs::new(&a, "wo", &b, "u")?;
        let (n, c) = (p.n, self.c());
        let (k, per_row, l) = match nm {
            None => (c, false, None),
            Some(x) => {
                let (k, per_row, l) =
                    arrays::wavelength_rows(arrays::f64_array(x, "nm")?, &p.lead)?;
                (k, per_row, Some(l))
            }
        };
        let lv = l.as_ref().map(|l| l.as_array());
        if n > 0
            && let Some(x) = lv
                .as_ref()
                .and_then(|v| v.iter().find(|&&x| !brdftab::spectrum::is_wavelength(x)))
        {
            return Err(PyValueError::new_err(format!(
                "nm: {x} is not a wavelength (a finite number of nm > 0)"
            )));
        }
        let (wi, pdf, weight, delta) = (
            arrays::zeros::<f64>(py, &p.shape(&[3]))?,
            arrays::zeros::<f64>(py, &p.shape(&[]))?,
            arrays::zeros::<f32>(py, &p.shape(&[k]))?,
            arrays::zeros::<bool>(py, &p.shape(&[]))?,
        );
        let (mut wi_w, mut pdf_w, mut w_w, mut d_w) = (
            wi.readwrite(),
            pdf.readwrite(),
            weight.readwrite(),
            delta.readwrite(),
        );
        let slice_err = |e: numpy::NotContiguousError| Error::new_err(e.to_string());
        let wi_s = arrays::as_rows_mut(wi_w.as_slice_mut().map_err(slice_err)?)?;
        let pdf_s = pdf_w.as_slice_mut().map_err(slice_err)?;
        let w_s = w_w.as_slice_mut().map_err(slice_err)?;
        let d_s = d_w.as_slice_mut().map_err(slice_err)?;
        let brdf = &self.inner;
        batch(py, n, || {
            // A batch with no broadcast row and one set of wavelengths (or none) is the
            // library's (without nm, a table's batch path).
            if let (Some((a, b)), false) = (p.whole(), per_row) {
                let out = brdftab::batch::SampleOut {
                    wi: wi_s,
                    pdf: pdf_s,
                    weight: w_s,
                };
                return match lv.as_ref().map(|l| l.as_slice()) {
                    None => brdftab::brdf::sample_flagged(brdf, a, b, out, d_s),
                    Some(Some(nm)) => brdftab::brdf::sample_flagged_at(brdf, a, b, nm, out, d_s),
                    Some(None) => {
                        let nm: Vec<f64> = lv
                            .as_ref()
                            .map_or(Vec::new(), |l| l.iter().copied().collect());
                        brdftab::brdf::sample_flagged_at(brdf, a, b, &nm, out, d_s)
                    }
                };
            }
            let go = |(s, (((wi, pd), w), d)): FlaggedBlock<'_>| {
                let mut scratch = arrays::Scratch::default();
                let (a, b) = p.block(s * BLOCK, pd.len(), &mut scratch);
                let mut nm = [0.0f64; brdftab::spectrum::MAX_CHANNELS];
                for r in 0..pd.len() {
                    let w = &mut w[r * k..(r + 1) * k];
                    let drawn = match (brdftab::batch::drawable(a[r], b[r]), &lv) {
                        (false, _) => None,
                        (true, None) => brdf.sample(a[r], b[r], w),
                        (true, Some(l)) => {
                            let row = match per_row {
                                true => l.index_axis(numpy::ndarray::Axis(0), s * BLOCK + r),
                                false => l.view(),
                            };
                            // nm.len() = k ≤ the weights' row; beyond MAX_CHANNELS a copy.
                            match row.len() <= nm.len() {
                                true => {
                                    for (o, &x) in nm.iter_mut().zip(row.iter()) {
                                        *o = x;
                                    }
                                    brdf.sample_wavelengths(a[r], b[r], &nm[..k], w)
                                }
                                false => {
                                    let nm: Vec<f64> = row.iter().copied().collect();
                                    brdf.sample_wavelengths(a[r], b[r], &nm, w)
                                }
                            }
                        }
                    };
                    match drawn {
                        Some(x) => (wi[r], pd[r], d[r]) = (x.wi, x.pdf, x.delta),
                        None => {
                            brdftab::batch::no_sample(&mut wi[r], &mut pd[r], w);
                            d[r] = false;
                        }
                    }
                }
            };
            // With no wavelengths the weights are empty, yet every block must still draw: its
            // weight chunks come from a stand-in of one (unused) value a pair.
            let kw = k.max(1);
            let mut stand_in = Vec::new();
            let w_s = match k {
                0 => {
                    stand_in.resize(n, 0.0f32);
                    stand_in.as_mut_slice()
                }
                _ => w_s,
            };
            if n >= brdftab::batch::PARALLEL {
                brdftab::par::install(|| {
                    wi_s.par_chunks_mut(BLOCK)
                        .zip(pdf_s.par_chunks_mut(BLOCK))
                        .zip(w_s.par_chunks_mut(BLOCK * kw))
                        .zip(d_s.par_chunks_mut(BLOCK))
                        .enumerate()
                        .for_each(go)
                })
            } else {
                wi_s.chunks_mut(BLOCK)
                    .zip(pdf_s.chunks_mut(BLOCK))
                    .zip(w_s.chunks_mut(BLOCK * kw))
                    .zip(d_s.chunks_mut(BLOCK))
                    .enumerate()
                    .for_each(go)
            }
        })?;
        drop((wi_w, pdf_w, w_w, d_w));
        self.check_loaded()?;
        let mut parts = vec![wi.into_any(), pdf.into_any(), weight.into_any()];
        if want_delta {
            parts.push(delta.into_any());
        }
        Ok(PyTuple::new(py, parts)?.unbind())
    }

    /// `Brdf.sampling_nodes`'s body, run under `guard` (documented on the method, in `mod.rs`).
    pub(super) fn sampling_resolution_dict(
        &self,
        py: Python<'_>,
        adjoint: bool,
        nearest: bool,
    ) -> PyResult<Py<PyAny>> {
        use brdftab::table::{Adjoint, SamplingResolution};
        let iso = self.inner.flags().isotropic;
        let brdf: &dyn Brdf = self.inner.as_ref();
        let r = unlocked(py, || match adjoint {
            true => SamplingResolution::for_source(&Adjoint(brdf), iso, nearest),
            false => SamplingResolution::for_source(brdf, iso, nearest),
        })?;
        self.check_loaded()?;
        let d = PyDict::new(py);
        d.set_item("theta_h", r.theta_h)?;
        d.set_item("phi_h", r.phi_h)?;
        d.set_item("theta_o", r.theta_o)?;
        d.set_item("phi_o", r.phi_o)?;
        Ok(d.into_any().unbind())
    }

    pub(super) fn sampling_nodes_dict(
        &self,
        py: Python<'_>,
        adjoint: bool,
        theta_h: usize,
        phi_h: usize,
        theta_o: usize,
        phi_o: usize,
    ) -> PyResult<Py<PyAny>> {
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
        d.set_item("version", 3)?;
        d.set_item("linear", brdftab::table::HALF_MAP_LINEAR)?;
        d.set_item("nx", n.nx)?;
        d.set_item("ny", n.ny)?;
        d.set_item("nt", n.nt)?;
        d.set_item("np", n.np)?;
        d.set_item("isotropic", n.isotropic)?;
        d.set_item("data", data)?;
        d.set_item("alias", alias)?;
        Ok(d.into_any().unbind())
    }
}
