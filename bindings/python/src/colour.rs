//! `rgb_basis`: the library's RGB → spectrum rule ([`brdftab::colour`]) for code that reads RGB
//! data at wavelengths itself — the Mitsuba plugin's JIT path reads RGB tables in spectral
//! variants with it, so that they give what `Brdf.eval_spectral` gives.

use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::arrays::{f64_array, zeros};
use crate::errors::guard;

/// The weights of R, G and B at wavelengths `nm` (any shape; result: that shape + `(3,)`): RGB
/// data (r, g, b) at λ is `r w[0] + g w[1] + b w[2]`. The weights are ≥ 0, sum to 1, and the
/// spectrum they make projects (CIE 1931, D65, linear sRGB) to the RGB it came from.
#[pyfunction]
pub(crate) fn rgb_basis<'py>(
    py: Python<'py>,
    nm: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    guard(|| {
        let nm = f64_array(nm, "nm")?;
        // The rule of every host's wavelengths (`eval_spectral`, the C ABI).
        if let Some(x) = nm
            .as_array()
            .iter()
            .find(|&&x| !brdftab::spectrum::is_wavelength(x))
        {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "nm: {x} is not a wavelength (a finite number of nm > 0)"
            )));
        }
        let mut shape = nm.shape().to_vec();
        shape.push(3);
        let out = zeros::<f64>(py, &shape)?;
        {
            let mut w = out.readwrite();
            let flat = w
                .as_slice_mut()
                .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("rgb_basis: {e}")))?;
            for (o, &x) in flat.chunks_exact_mut(3).zip(nm.as_array().iter()) {
                o.copy_from_slice(&brdftab::colour::rgb_basis_at(x));
            }
        }
        Ok(out)
    })
}
