//! numpy arrays in and out of batch calls without copies (and in as a table's values,
//! `Table.with_values`).
//!
//! Why a module: a batch call's cost should be the library's. Directions arrive as `(..., 3)`
//! arrays (any leading shape, broadcast against each other by numpy's rules; results take the
//! broadcast shape); a C-contiguous, aligned float64 array is read in place as `[DVec3]` (glam's `DVec3`
//! is `#[repr(C)]` of three f64, as the C ABI reads `double[n][3]`); a C-contiguous, aligned float32
//! array — what Mitsuba, PyTorch and most renderers' buffers hold — is read in place too, each
//! block of rows widened to f64 as the block is evaluated (the same values numpy's `astype`
//! gives, without an n-sized float64 copy before the call); a float64 `(n, W)` array at other
//! strides — Fortran order (`np.array([x, y, z]).T`), reversed (`a[::-1]`), every other row, the
//! first columns of a wider array — is read in place too, each block of rows gathered as it is
//! evaluated; anything else — an N-d strided view, a misaligned buffer, integers, a list — is converted by numpy once. Results are written straight into the numpy
//! arrays returned, with the GIL released, so a large call's memory is its output.

use brdftab::batch::{BLOCK, blocks};
use glam::{DVec2, DVec3};
use numpy::{Element, PyArrayDyn, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyMemoryError, PyTypeError, PyValueError};
use pyo3::prelude::*;

// `[f64; 3k]` is read as `[DVec3; k]` and `[f64; 2k]` as `[DVec2; k]`.
const _: () = assert!(std::mem::size_of::<DVec3>() == 24 && std::mem::align_of::<DVec3>() == 8);
const _: () = assert!(std::mem::size_of::<DVec2>() == 16 && std::mem::align_of::<DVec2>() == 8);

/// A float64 view of an array-like (numpy array, list, tuple); non-numeric dtypes are a
/// `TypeError`, a masked array with masked entries a `ValueError` (below). A float64 array is
/// borrowed as it is; anything else is converted once.
pub(crate) fn f64_array<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<PyReadonlyArrayDyn<'py, f64>> {
    real_array(obj, name, "float64")
}

/// [`f64_array`] in float32 (`dtype`): a table's values. A float32 array is borrowed as it is
/// (any strides: read it in C order with `as_array().iter()`).
pub(crate) fn f32_array<'py>(
    obj: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<PyReadonlyArrayDyn<'py, f32>> {
    real_array(obj, name, "float32")
}

/// An array-like of real numbers as an array of `T`, whose numpy name is `dtype`.
fn real_array<'py, T: Element>(
    obj: &Bound<'py, PyAny>,
    name: &str,
    dtype: &str,
) -> PyResult<PyReadonlyArrayDyn<'py, T>> {
    refuse_masked(obj, name)?;
    if let Ok(a) = obj.extract::<PyReadonlyArrayDyn<'py, T>>() {
        return aligned(a, name, dtype);
    }
    let py = obj.py();
    if obj.is_none() || obj.is_instance_of::<pyo3::types::PyString>() {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected an array of real numbers, got {}",
            obj.get_type()
                .name()
                .map(|n| n.to_string())
                .unwrap_or_default()
        )));
    }
    let np = py.import("numpy")?;
    let not_real =
        |e: PyErr| PyTypeError::new_err(format!("{name}: not an array of real numbers ({e})"));
    let mut obj = obj.clone();
    if let Ok(dt) = obj.getattr("dtype") {
        if dt.getattr("kind").is_err() {
            // Another library's dtype (a torch tensor's `torch.float32` has no numpy `kind`,
            // and was refused as if not real): numpy's view of the object says what it holds.
            obj = np.call_method1("asarray", (&obj,)).map_err(not_real)?;
        }
        let dt = obj.getattr("dtype")?;
        let kind: String = dt
            .getattr("kind")
            .and_then(|k| k.extract())
            .unwrap_or_default();
        if !matches!(kind.as_str(), "b" | "i" | "u" | "f") {
            return Err(PyTypeError::new_err(format!(
                "{name}: expected real numbers, got an array of dtype {}",
                dt.str().map(|s| s.to_string()).unwrap_or_default()
            )));
        }
    }
    // In C order: what every caller reads (rows in place, values in C order); converting a
    // Fortran-order or strided array keeping its layout made `Rows` copy it a second time.
    let kw = pyo3::types::PyDict::new(py);
    kw.set_item("order", "C")?;
    let arr = np
        .call_method("asarray", (&obj, dtype), Some(&kw))
        .map_err(not_real)?;
    let arr = arr
        .extract::<PyReadonlyArrayDyn<'py, T>>()
        .map_err(|e| PyTypeError::new_err(format!("{name}: {e}")))?;
    aligned(arr, name, dtype)
}

/// Whether `a`'s data is aligned for `T`.
fn is_aligned<T: Element>(a: &PyReadonlyArrayDyn<'_, T>) -> bool {
    use numpy::PyArrayMethods;
    a.data().is_aligned()
}

/// `a` when its data is aligned for `T`, else an aligned C-ordered copy by numpy
/// (`numpy.require(a, dtype, "CA")`); no memory for the copy is a `MemoryError` naming `name`.
/// A numpy array can be misaligned (`np.frombuffer` at an odd offset); every reader of a
/// borrowed array — `as_slice`, `as_array`, rows read in place as `[DVec3]` — makes a `&[T]` or
/// an ndarray view of its data, which must be aligned: a misaligned one is undefined behaviour
/// (a build with debug assertions aborts on it: "slice::from_raw_parts requires the pointer to
/// be aligned"), even where x86 reads the numbers right.
fn aligned<'py, T: Element>(
    a: PyReadonlyArrayDyn<'py, T>,
    name: &str,
    dtype: &str,
) -> PyResult<PyReadonlyArrayDyn<'py, T>> {
    if is_aligned(&a) {
        return Ok(a);
    }
    let py = a.py();
    let kw = pyo3::types::PyDict::new(py);
    kw.set_item("requirements", "CA")?;
    let copy = py
        .import("numpy")?
        .call_method("require", (a.as_any(), dtype), Some(&kw))
        .map_err(|e| {
            if e.is_instance_of::<PyMemoryError>(py) {
                PyMemoryError::new_err(format!("{name}: no memory for an aligned copy ({e})"))
            } else {
                e
            }
        })?;
    copy.extract::<PyReadonlyArrayDyn<'py, T>>()
        .map_err(|e| PyTypeError::new_err(format!("{name}: {e}")))
}

/// A `numpy.ma.MaskedArray` is an ndarray whose data under a masked entry is whatever was
/// there: read as an array it would be evaluated as if valid. One with masked entries is a
/// `ValueError` (the caller fills or drops them: the library has no "no value" for a pair);
/// one without is read as its data. A plain ndarray (the fast path) is not looked at.
fn refuse_masked(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<()> {
    use numpy::PyUntypedArray;
    if obj.is_exact_instance_of::<PyUntypedArray>() || !obj.is_instance_of::<PyUntypedArray>() {
        return Ok(());
    }
    let ma = obj.py().import("numpy.ma")?;
    if obj.is_instance(&ma.getattr("MaskedArray")?)?
        && ma.call_method1("is_masked", (obj,))?.is_truthy()?
    {
        return Err(PyValueError::new_err(format!(
            "{name}: a masked array with masked entries (numpy.ma): they have no value to \
             evaluate; fill them ({name}.filled(...)) or drop them first"
        )));
    }
    Ok(())
}

/// `(a,)` or `(a, b, ...)` as Python prints a shape.
pub(crate) fn shape_str(shape: &[usize]) -> String {
    match shape {
        [a] => format!("({a},)"),
        s => format!(
            "({})",
            s.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Rows of `W` numbers, `(..., W)` (one row: `(W,)`), as `T` (`T` = `DVec3` or `DVec2`):
/// float64 borrowed in place as `[T]` when C-contiguous and aligned, float32 borrowed in place
/// when C-contiguous (widened block by block: [`View::rows`]), 2-d float64 borrowed in place at
/// other strides (gathered block by block), anything else converted or copied once.
pub(crate) struct Rows<'py, T> {
    /// Keeps the numpy array (and its read borrow) alive while `ptr` or `narrow` is used.
    _array: Held<'py>,
    /// Rows in place as `T` (float64), or null.
    ptr: *const T,
    /// Rows in place as `W` f32 each (float32), or null.
    narrow: *const f32,
    /// Rows in place at any strides (a 2-d float64 array that is not C-contiguous), or `None`.
    strided: Option<Strided>,
    len: usize,
    /// The input's leading shape (its shape without the last axis; `[]` for one row `(W,)`).
    pub lead: Vec<usize>,
}

/// The numpy array a [`Rows`] reads.
enum Held<'py> {
    F64 { _a: PyReadonlyArrayDyn<'py, f64> },
    F32 { _a: PyReadonlyArrayDyn<'py, f32> },
}

/// Row types read from numpy arrays: `W` numbers, `#[repr(C)]` of f64.
pub(crate) trait Row: Copy + Send + Sync {
    /// Numbers per row.
    const W: usize;
    /// A row from its `W` numbers.
    fn from(s: &[f64]) -> Self;
    /// A row from its `W` numbers in f32 (widened exactly, as numpy's `astype` does).
    fn from_f32(s: &[f32]) -> Self;
}

impl Row for DVec3 {
    const W: usize = 3;
    fn from(s: &[f64]) -> Self {
        DVec3::new(s[0], s[1], s[2])
    }
    fn from_f32(s: &[f32]) -> Self {
        DVec3::new(s[0] as f64, s[1] as f64, s[2] as f64)
    }
}

impl Row for DVec2 {
    const W: usize = 2;
    fn from(s: &[f64]) -> Self {
        DVec2::new(s[0], s[1])
    }
    fn from_f32(s: &[f32]) -> Self {
        DVec2::new(s[0] as f64, s[1] as f64)
    }
}

/// Whether `obj` is a C-contiguous float32 ndarray of shape `(..., w)` (read in place).
fn narrow_rows<'py>(obj: &Bound<'py, PyAny>, w: usize) -> Option<PyReadonlyArrayDyn<'py, f32>> {
    use numpy::PyUntypedArray;
    // A subclass (a masked array) goes the general way, which looks at its mask.
    if !obj.is_exact_instance_of::<PyUntypedArray>() {
        return None;
    }
    let a = obj.extract::<PyReadonlyArrayDyn<'py, f32>>().ok()?;
    let shaped = a.shape().last() == Some(&w);
    // A misaligned one goes the general way too (converted to float64 by numpy: `aligned`).
    (shaped && a.is_c_contiguous() && is_aligned(&a)).then_some(a)
}

/// A 2-d float64 array's numbers where they are: entry (i, j) at `ptr + i·row + j·col` (strides
/// in elements, either sign).
#[derive(Clone, Copy)]
pub(crate) struct Strided {
    ptr: *const f64,
    row: isize,
    col: isize,
}

// SAFETY: a `Strided` only reads the numbers of a numpy array that its `Rows` keeps alive and
// read-borrowed, as the `&[f64]` and `&[f32]` views of the other layouts do.
unsafe impl Send for Strided {}
unsafe impl Sync for Strided {}

impl Strided {
    /// `a` (shape `(n, w)`, not C-contiguous) in place, or `None` where its strides are not
    /// whole float64 steps or its data is misaligned (then it is copied).
    fn of(a: &PyReadonlyArrayDyn<'_, f64>) -> Option<Strided> {
        use numpy::PyArrayMethods;
        let e = std::mem::size_of::<f64>() as isize;
        let (rs, cs) = match a.strides() {
            &[r, c] if r % e == 0 && c % e == 0 => (r / e, c / e),
            _ => return None,
        };
        let ptr = a.data() as *const f64;
        ptr.is_aligned().then_some(Strided {
            ptr,
            row: rs,
            col: cs,
        })
    }

    /// Row `i` as `T` (`i` below the array's row count).
    fn row<T: Row>(&self, i: usize) -> T {
        let mut x = [0.0; 4];
        for (j, x) in x.iter_mut().enumerate().take(T::W) {
            // SAFETY: (i, j) is within the array's shape, so its offset from `ptr` (numpy's
            // pointer to entry (0, 0)) is within its buffer, which `Rows` keeps alive.
            *x = unsafe {
                *self
                    .ptr
                    .offset(i as isize * self.row + j as isize * self.col)
            };
        }
        T::from(&x[..T::W])
    }
}

impl<'py, T: Row> Rows<'py, T> {
    /// Reads `obj` as rows of `T::W` numbers; wrong shapes are a `ValueError` naming `name`.
    pub(crate) fn new(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Self> {
        let w = T::W;
        if let Some(a) = narrow_rows(obj, w) {
            let flat = a
                .as_slice()
                .map_err(|e| PyValueError::new_err(format!("{name}: {e}")))?;
            return Ok(Rows {
                narrow: flat.as_ptr(),
                ptr: std::ptr::null(),
                strided: None,
                len: flat.len() / w,
                lead: a.shape()[..a.ndim() - 1].to_vec(),
                _array: Held::F32 { _a: a },
            });
        }
        let mut a = f64_array(obj, name)?;
        let lead = match a.shape().split_last() {
            Some((x, lead)) if *x == w => lead.to_vec(),
            _ => {
                return Err(PyValueError::new_err(format!(
                    "{name}: expected shape (..., {w}) ({w} numbers a row), got {}",
                    shape_str(a.shape())
                )));
            }
        };
        if !a.is_c_contiguous()
            && a.ndim() == 2
            && let Some(st) = Strided::of(&a)
        {
            // `(n, W)` at other strides: read in place, block by block.
            return Ok(Rows {
                len: a.shape()[0],
                lead,
                _array: Held::F64 { _a: a },
                ptr: std::ptr::null(),
                narrow: std::ptr::null(),
                strided: Some(st),
            });
        }
        if !a.is_c_contiguous() {
            // An N-d strided view: one copy, by numpy.
            let np = obj.py().import("numpy")?;
            a = np
                .call_method1("ascontiguousarray", (a.as_any(),))?
                .extract::<PyReadonlyArrayDyn<'py, f64>>()?;
        }
        let flat = a
            .as_slice()
            .map_err(|e| PyValueError::new_err(format!("{name}: {e}")))?;
        // `f64_array` gives aligned data (`aligned`), so the rows are read in place.
        let len = flat.len() / w;
        let ptr = flat.as_ptr() as *const T;
        Ok(Rows {
            _array: Held::F64 { _a: a },
            ptr,
            narrow: std::ptr::null(),
            strided: None,
            len,
            lead,
        })
    }

    /// Number of rows.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// The rows as they are held: `[T]`, float32 numbers or float64 at strides (shared across
    /// threads).
    pub(crate) fn view(&self) -> View<'_, T> {
        if let Some(s) = self.strided {
            return View::Strided(s, self.len);
        }
        if !self.narrow.is_null() {
            // SAFETY: `narrow` points to `len * W` f32 of the C-contiguous array kept alive
            // (and read-borrowed) by `_array`.
            return View::Narrow(unsafe {
                std::slice::from_raw_parts(self.narrow, self.len * T::W)
            });
        }
        if self.ptr.is_null() {
            return View::Wide(&[]);
        }
        // SAFETY: `ptr` points to `len * W` f64 of the C-contiguous, aligned array kept alive
        // (and read-borrowed) by `_array`; `T` is `#[repr(C)]` of `W` f64 (asserted above).
        View::Wide(unsafe { std::slice::from_raw_parts(self.ptr, self.len) })
    }

    /// Row `i` (< [`Rows::len`]).
    pub(crate) fn row(&self, i: usize) -> T {
        self.view().row(i)
    }
}

/// [`Rows`] as held: rows of `T` (float64 in place, or a copy), float32 numbers in place, or
/// `len` rows of float64 in place at strides.
#[derive(Clone, Copy)]
pub(crate) enum View<'a, T> {
    Wide(&'a [T]),
    Narrow(&'a [f32]),
    Strided(Strided, usize),
}

impl<'a, T: Row> View<'a, T> {
    /// Number of rows.
    pub(crate) fn len(&self) -> usize {
        match self {
            View::Wide(x) => x.len(),
            View::Narrow(x) => x.len() / T::W,
            View::Strided(_, n) => *n,
        }
    }

    /// Row `i` (< `len`).
    pub(crate) fn row(&self, i: usize) -> T {
        match self {
            View::Wide(x) => x[i],
            View::Narrow(x) => T::from_f32(&x[i * T::W..(i + 1) * T::W]),
            View::Strided(x, n) => {
                assert!(i < *n, "row {i} of {n}");
                x.row(i)
            }
        }
    }

    /// The `k` rows from `s` on: in place, or widened from float32 (gathered from strides)
    /// into `buf`.
    fn rows<'s>(&self, s: usize, k: usize, buf: &'s mut Vec<T>) -> &'s [T]
    where
        'a: 's,
    {
        match *self {
            View::Wide(x) => &x[s..s + k],
            View::Narrow(x) => {
                let w = T::W;
                buf.clear();
                buf.extend(x[s * w..(s + k) * w].chunks_exact(w).map(T::from_f32));
                buf
            }
            View::Strided(x, n) => {
                assert!(s + k <= n, "rows {s}..{} of {n}", s + k);
                buf.clear();
                buf.extend((s..s + k).map(|i| x.row::<T>(i)));
                buf
            }
        }
    }
}

/// numpy's broadcast of two leading shapes (aligned at their ends; an axis of 1 stretches),
/// or `None` where they do not broadcast.
pub(crate) fn broadcast(a: &[usize], b: &[usize]) -> Option<Vec<usize>> {
    let n = a.len().max(b.len());
    let at = |s: &[usize], i: usize| match (i + s.len()).checked_sub(n) {
        Some(j) => s[j],
        None => 1,
    };
    (0..n)
        .map(|i| match (at(a, i), at(b, i)) {
            (x, y) if x == y || y == 1 => Some(x),
            (1, y) => Some(y),
            _ => None,
        })
        .collect()
}

/// Reads `a` and `b` as rows for one call whose leading shapes broadcast (numpy's rule). A
/// side whose leading shape is the broadcast's (up to leading axes of 1) is read as it is, and
/// so is a single row (repeated block by block by [`Pairs`]); only a side that broadcasts
/// along some axes and not others — `(n, 1, 3)` against `(1, m, 3)` — is expanded by numpy
/// into a C-contiguous copy of the broadcast shape.
pub(crate) fn pair_rows<'py, A: Row, B: Row>(
    a: &Bound<'py, PyAny>,
    an: &str,
    b: &Bound<'py, PyAny>,
    bn: &str,
) -> PyResult<(Rows<'py, A>, Rows<'py, B>)> {
    let (mut ra, mut rb) = (Rows::<A>::new(a, an)?, Rows::<B>::new(b, bn)?);
    let lead = broadcast(&ra.lead, &rb.lead).ok_or_else(|| mismatch(&ra, an, &rb, bn))?;
    let n: usize = lead.iter().product();
    if ra.len() != n && ra.len() != 1 {
        ra = Rows::new(&expand(a, &lead, A::W)?, an)?;
    }
    if rb.len() != n && rb.len() != 1 {
        rb = Rows::new(&expand(b, &lead, B::W)?, bn)?;
    }
    Ok((ra, rb))
}

/// The refusal of two row sets whose leading shapes do not broadcast.
fn mismatch<A: Row, B: Row>(a: &Rows<'_, A>, an: &str, b: &Rows<'_, B>, bn: &str) -> PyErr {
    let full = |lead: &[usize], w: usize| shape_str(&[lead, &[w]].concat());
    PyValueError::new_err(format!(
        "{an} and {bn}: shapes {} and {} do not broadcast (numpy's rule, the last axis aside)",
        full(&a.lead, A::W),
        full(&b.lead, B::W)
    ))
}

/// `obj` broadcast to `lead + (w,)` as a C-contiguous array (numpy copies it).
fn expand<'py>(obj: &Bound<'py, PyAny>, lead: &[usize], w: usize) -> PyResult<Bound<'py, PyAny>> {
    let np = obj.py().import("numpy")?;
    let shape = pyo3::types::PyTuple::new(obj.py(), [lead, &[w]].concat())?;
    let b = np.call_method1("broadcast_to", (np.call_method1("asarray", (obj,))?, shape))?;
    np.call_method1("ascontiguousarray", (b,))
}

/// Wavelengths for pairs of leading shape `lead` (`n` pairs): one set `(k,)` for every pair,
/// or one set per pair, `lead + (k,)`. Returns `k`, whether the sets are per pair, and the
/// array as `(k,)` or `(n, k)` (numpy reshapes an N-d one, a view where its strides allow).
pub(crate) fn wavelength_rows<'py>(
    nm: PyReadonlyArrayDyn<'py, f64>,
    lead: &[usize],
) -> PyResult<(usize, bool, PyReadonlyArrayDyn<'py, f64>)> {
    let n: usize = lead.iter().product();
    match nm.shape().split_last() {
        Some((&k, [])) => Ok((k, false, nm)),
        Some((&k, l)) if l == lead && l.len() == 1 => Ok((k, true, nm)),
        Some((&k, l)) if l == lead => {
            let flat = nm.as_any().call_method1("reshape", ((n, k),))?;
            Ok((k, true, flat.extract()?))
        }
        _ if lead.is_empty() => Err(PyValueError::new_err(format!(
            "nm: expected shape (k,) (the k wavelengths of the one pair), got {}",
            shape_str(nm.shape())
        ))),
        _ => {
            let per_pair: Vec<String> = lead.iter().map(|d| d.to_string()).collect();
            Err(PyValueError::new_err(format!(
                "nm: expected shape (k,) or ({}, k) (one set of k per pair), got {}",
                per_pair.join(", "),
                shape_str(nm.shape())
            )))
        }
    }
}

/// Two row sets paired for a call (read by [`pair_rows`]): the same count, or one row against
/// many (broadcast, the single row repeated into a block-sized buffer: no n-sized copy).
pub(crate) struct Pairs<'a, A, B> {
    a: View<'a, A>,
    b: View<'a, B>,
    /// `a`'s single row repeated `min(n, BLOCK)` times when it broadcasts, else empty.
    ra: Vec<A>,
    /// The same for `b`.
    rb: Vec<B>,
    /// Number of pairs.
    pub n: usize,
    /// The pairs' leading shape (numpy's broadcast of the inputs'; `[]` for one pair of single
    /// rows): results have this shape, then their own axes.
    pub lead: Vec<usize>,
}

/// Per-block room for rows widened from float32 ([`Pairs::block`]).
pub(crate) type Scratch<A, B> = (Vec<A>, Vec<B>);

impl<'a, A: Row, B: Row> Pairs<'a, A, B> {
    /// Pairs `a` (named `an`) with `b` (named `bn`).
    pub(crate) fn new(
        a: &'a Rows<'_, A>,
        an: &str,
        b: &'a Rows<'_, B>,
        bn: &str,
    ) -> PyResult<Self> {
        let (na, nb) = (a.len(), b.len());
        // numpy's rule; a side that broadcasts along some axes only was expanded by
        // `pair_rows`, so each side here is whole or one row.
        let lead = broadcast(&a.lead, &b.lead).ok_or_else(|| mismatch(a, an, b, bn))?;
        let n: usize = lead.iter().product();
        if !(na == n || na == 1) || !(nb == n || nb == 1) {
            return Err(mismatch(a, an, b, bn));
        }
        let m = n.min(BLOCK);
        Ok(Pairs {
            ra: if na == n {
                Vec::new()
            } else {
                vec![a.row(0); m]
            },
            rb: if nb == n {
                Vec::new()
            } else {
                vec![b.row(0); m]
            },
            a: a.view(),
            b: b.view(),
            n,
            lead,
        })
    }

    /// The shape of a result with `tail` axes per pair: the pairs' leading shape, then `tail`.
    pub(crate) fn shape(&self, tail: &[usize]) -> Vec<usize> {
        [&self.lead[..], tail].concat()
    }

    /// Both sides whole (no broadcast) and in place as float64: the arrays as they are.
    pub(crate) fn whole(&self) -> Option<(&[A], &[B])> {
        match (self.a, self.b) {
            (View::Wide(a), View::Wide(b)) if a.len() == self.n && b.len() == self.n => {
                Some((a, b))
            }
            _ => None,
        }
    }

    /// The `k` pairs from `s` on (`k` ≤ [`BLOCK`] when a side broadcasts); float32 rows are
    /// widened into `scratch`.
    pub(crate) fn block<'s>(
        &'s self,
        s: usize,
        k: usize,
        scratch: &'s mut Scratch<A, B>,
    ) -> (&'s [A], &'s [B]) {
        let (sa, sb) = (&mut scratch.0, &mut scratch.1);
        let a = match self.a.len() == self.n {
            true => self.a.rows(s, k, sa),
            false => &self.ra[..k],
        };
        let b = match self.b.len() == self.n {
            true => self.b.rows(s, k, sb),
            false => &self.rb[..k],
        };
        (a, b)
    }

    /// Runs `f(a, b, out)` over all pairs: once on the whole arrays (the library
    /// parallelizes), or block by block on the library's pool when a side broadcasts or is
    /// float32. `width` = outputs per pair.
    pub(crate) fn run<T: Send>(
        &self,
        out: &mut [T],
        width: usize,
        f: impl Fn(&[A], &[B], &mut [T]) + Sync + Send,
    ) {
        if let Some((a, b)) = self.whole() {
            return f(a, b, out);
        }
        blocks(out, width, |s, o| {
            let mut scratch = Scratch::default();
            let (a, b) = self.block(s, o.len() / width.max(1), &mut scratch);
            f(a, b, o)
        });
    }
}

/// A new zero-filled numpy array of `shape` (numpy's `zeros`: calloc'ed pages). A shape
/// beyond memory is numpy's `MemoryError` (beyond the address space its `ValueError`), not a
/// panic: `PyArray::zeros` panics when numpy fails.
pub(crate) fn zeros<'py, T: Element>(
    py: Python<'py>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<T>>> {
    use numpy::npyffi::{PY_ARRAY_API, npy_intp};
    use numpy::{PyArrayDescrMethods, dtype};
    let mut dims = shape
        .iter()
        .map(|&d| npy_intp::try_from(d))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|_| PyValueError::new_err(format!("shape {} is too large", shape_str(shape))))?;
    // SAFETY: `dims` holds `dims.len()` dimensions; the dtype reference is stolen by numpy;
    // the result is a new reference to a C-ordered array of `T` (or NULL with an exception
    // set, turned into the `PyErr`).
    unsafe {
        let ptr = PY_ARRAY_API.PyArray_Zeros(
            py,
            dims.len() as std::ffi::c_int,
            dims.as_mut_ptr(),
            dtype::<T>(py).into_dtype_ptr(),
            0,
        );
        Ok(Bound::from_owned_ptr_or_err(py, ptr)?.cast_into_unchecked())
    }
}

/// A fresh `(n, 3)` float64 output array's numbers as `[DVec3]` (numpy's allocations are
/// aligned; a misaligned one is an error, not undefined behaviour).
pub(crate) fn as_rows_mut(flat: &mut [f64]) -> PyResult<&mut [DVec3]> {
    if !(flat.as_ptr() as usize).is_multiple_of(std::mem::align_of::<DVec3>())
        || !flat.len().is_multiple_of(3)
    {
        return Err(PyValueError::new_err("internal: misaligned output array"));
    }
    // SAFETY: aligned (checked), `len / 3` rows of three f64 = `DVec3` (`#[repr(C)]`, asserted
    // above); the borrow of `flat` is moved into the result.
    Ok(unsafe { std::slice::from_raw_parts_mut(flat.as_mut_ptr() as *mut DVec3, flat.len() / 3) })
}
