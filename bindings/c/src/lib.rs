//! The C ABI of brdftab: `include/brdftab.h`.
//!
//! C and C++ renderers (pbrt, Cycles, Falcor, ...) link `libbrdftab_c.so` or `libbrdftab_c.a`
//! and call these functions; no Rust toolchain is needed in their build. Every function is a thin
//! shim over the library's one door, [`brdftab::open_with`], and the [`brdftab::Brdf`] trait, so
//! the C side sees exactly the conventions of the Rust side: the local frame has z as the
//! normal, `wi` (to the light) and `wo` (to the viewer) both point away from the surface,
//! `eval` returns f_r without a cosine, and `sample` draws `wi` for a given `wo` with
//! weight = f cos θi / pdf.
//!
//! Failure is `-1` (or `NULL` from the open functions) with the reason in
//! [`brdftab_last_error`], kept per thread. No panic crosses the boundary: every entry point runs
//! inside `catch_unwind`, and a caught panic becomes `-1` with its message, printing nothing on
//! the host's stderr. Every size computed from a caller's count (`n` pairs × 3 doubles, × the
//! channels) is checked for overflow and against `isize::MAX` bytes before a slice is made.
//!
//! **Corrupt tables.** A table opened lazily (the default) decodes a chunk the first time a
//! lookup needs it; a chunk that fails its checksum puts the handle in a sticky failed state
//! ([`brdftab::Brdf::health`]). `brdftab_eval`, `_pdf`, `_sample` and `_albedo` check it after
//! their batch: the call that met the bad chunk and every later call on that handle return -1
//! with the checksum error. Values written by a failed call are not to be used.
//!
//! **NaN.** A direction with a NaN or infinite component (or a zero vector) is not an error: its
//! f_r and pdf are 0 and it has no sample (wi = 0, pdf = 0, weight = 0), as in the library; a
//! `theta` outside [0, π/2) in `brdftab_albedo` (NaN included) is an error. Batch calls allocate
//! nothing beyond what the library's own `eval_batch` does: the caller's `double[n][3]` arrays
//! are read in place as `DVec3` slices.

#![deny(unsafe_op_in_unsafe_fn)]
// Every public item is documented (DESIGN.md); clippy -D warnings in CI holds it.
#![warn(missing_docs)]
// The C types keep the C names of brdftab.h.
#![allow(non_camel_case_types)]

use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char, c_int};

use brdftab::source::OpenOptions;
use brdftab::table::Interp;
use brdftab::{Brdf, Channels};
use glam::{DVec2, DVec3};

mod request;
pub use request::*;

// `double[n][3]` is read as `[DVec3; n]`: glam's DVec3 is `#[repr(C)] {x, y, z}` of f64.
const _: () = assert!(std::mem::size_of::<DVec3>() == 24 && std::mem::align_of::<DVec3>() == 8);
const _: () = assert!(std::mem::size_of::<DVec2>() == 16 && std::mem::align_of::<DVec2>() == 8);

/// An open BRDF. Opaque to C; every call but `brdftab_close` (the evaluations, samplers,
/// spectral calls, albedo and the queries) may run concurrently on one handle from any number
/// of threads.
pub struct brdftab_brdf {
    brdf: Box<dyn Brdf + Send + Sync>,
    names: Vec<CString>,
}

/// Options of [`brdftab_open_with`]. Zero-initialized means the defaults.
///
/// The struct can grow without breaking programs built against an older header: `size` says
/// how many bytes the caller's struct has (the extensible-struct rule of Linux's `openat2` and
/// `clone3`). 0 stands for this first layout, so a zero-initialized struct stays valid in every
/// later version, with any later field at its default. A caller larger than the library knows
/// is accepted when its extra bytes are all zero (fields it left at their defaults).
#[repr(C)]
pub struct brdftab_open_options {
    /// `sizeof(brdftab_open_options)` in the caller's header, or 0 for this first layout.
    pub size: usize,
    /// Table interpolation: 0 auto (default: nearest on tables of MERL cells, linear otherwise),
    /// 1 nearest, 2 linear.
    pub interp: c_int,
    /// Number of wavelengths in `wavelengths`; 0 keeps the source's own channels.
    pub n_wavelengths: usize,
    /// Wavelengths in nm, strictly increasing (model specs and RGL files).
    pub wavelengths: *const f64,
    /// Non-zero: decode every chunk of a table at open (a corrupt table fails the open).
    pub eager: c_int,
}

thread_local! {
    /// This thread's last failure (`None`: the last call succeeded). Initialized by a constant,
    /// so that each call's access is a plain thread-local read with no lazy-initialization
    /// check (a successful one-pair call pays it on every call).
    static LAST_ERROR: RefCell<Option<CString>> = const { RefCell::new(None) };
}

/// What [`brdftab_last_error`] returns once this thread's [`LAST_ERROR`] is destroyed.
const NO_MESSAGE: &CStr =
    c"no message: called after this thread's storage was destroyed (an atexit handler, a static destructor or a thread-exit destructor)";

/// Keeps `msg` as this thread's last error. A call made after the thread's storage is destroyed
/// (from an `atexit` handler, a C++ static destructor, another library's thread-exit
/// destructor) has nowhere to keep it: its -1 stands alone ([`NO_MESSAGE`]) — `with` would
/// panic there, and a panic outside the guard aborts the host.
fn set_error(msg: &str) {
    let c = CString::new(msg.replace('\0', " ")).unwrap_or_default();
    let _ = LAST_ERROR.try_with(|e| *e.borrow_mut() = Some(c));
}

/// Empties the last error; allocates nothing, and writes nothing when it is already empty (the
/// common case). Nothing either once the thread's storage is destroyed ([`set_error`]).
fn clear_error() {
    let _ = LAST_ERROR.try_with(|e| {
        if e.borrow().is_some() {
            *e.borrow_mut() = None;
        }
    });
}

/// Runs `f`, turning an error or a panic into -1 and the thread's last error. A caught panic
/// prints nothing on the host's stderr ([`brdftab::host::catch_quietly`]).
fn guard(f: impl FnOnce() -> Result<(), String>) -> c_int {
    match brdftab::host::catch_quietly(f) {
        Ok(Ok(())) => {
            clear_error();
            0
        }
        Ok(Err(msg)) => {
            set_error(&msg);
            -1
        }
        Err(p) => {
            set_error(&format!("internal error (panic): {p}"));
            -1
        }
    }
}

/// Checks that `len` elements of `T` fit in one slice (at most `isize::MAX` bytes), before any
/// slice is made: a count near `SIZE_MAX` is an error, never a wrapped size.
fn check_len<T>(len: usize, what: &str) -> Result<(), String> {
    match len.checked_mul(std::mem::size_of::<T>()) {
        Some(bytes) if bytes <= isize::MAX as usize => Ok(()),
        _ => Err(format!(
            "`{what}`: {len} elements of {} bytes exceed the largest array (PTRDIFF_MAX bytes)",
            std::mem::size_of::<T>()
        )),
    }
}

/// `n · c` (pairs times channels), checked.
fn times(n: usize, c: usize, what: &str) -> Result<usize, String> {
    n.checked_mul(c)
        .ok_or_else(|| format!("`{what}`: n = {n} pairs × {c} channels overflows size_t"))
}

/// A table's sticky chunk failure ([`Brdf::health`]) as this call's error: the batch just
/// written came (partly) from a chunk that could not be read.
fn healthy(b: &brdftab_brdf) -> Result<(), String> {
    b.brdf.health().map_err(|e| e.to_string())
}

/// # Safety
/// `p` is NULL or points to `len` readable `T`s.
unsafe fn slice<'a, T>(p: *const T, len: usize, what: &str) -> Result<&'a [T], String> {
    if p.is_null() {
        return Err(format!("`{what}` is NULL"));
    }
    if !(p as usize).is_multiple_of(std::mem::align_of::<T>()) {
        return Err(format!("`{what}` is not aligned for its type"));
    }
    check_len::<T>(len, what)?;
    // SAFETY: the caller promises `len` readable elements; NULL, alignment and the size
    // (at most isize::MAX bytes) are checked.
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// # Safety
/// `p` is NULL or points to `len` writable `T`s.
unsafe fn slice_mut<'a, T>(p: *mut T, len: usize, what: &str) -> Result<&'a mut [T], String> {
    if p.is_null() {
        return Err(format!("`{what}` is NULL"));
    }
    if !(p as usize).is_multiple_of(std::mem::align_of::<T>()) {
        return Err(format!("`{what}` is not aligned for its type"));
    }
    check_len::<T>(len, what)?;
    // SAFETY: the caller promises `len` writable elements; NULL, alignment and the size
    // (at most isize::MAX bytes) are checked.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

/// # Safety
/// `b` is NULL or a handle from `brdftab_open*` not yet closed.
unsafe fn handle<'a>(b: *const brdftab_brdf) -> Result<&'a brdftab_brdf, String> {
    // SAFETY: the caller promises a live handle or NULL.
    unsafe { b.as_ref() }.ok_or_else(|| "the brdftab_brdf handle is NULL".to_string())
}

/// The handle and the `wi`, `wo` arrays of a pair-wise call.
///
/// # Safety
/// `b` is NULL or a live handle; `wi` and `wo` are NULL or point to 3n doubles.
unsafe fn pair_args<'a>(
    b: *const brdftab_brdf,
    n: usize,
    wi: *const f64,
    wo: *const f64,
) -> Result<(&'a brdftab_brdf, &'a [DVec3], &'a [DVec3]), String> {
    // SAFETY (all three): the caller's contract; NULL and alignment are checked.
    let b = unsafe { handle(b) }?;
    let wi = unsafe { slice(wi as *const DVec3, n, "wi") }?;
    let wo = unsafe { slice(wo as *const DVec3, n, "wo") }?;
    Ok((b, wi, wo))
}

/// A caller's string argument as UTF-8 (`what` names it in errors).
///
/// # Safety
/// `p` is NULL or a NUL-terminated string.
unsafe fn text<'a>(p: *const c_char, what: &str) -> Result<&'a str, String> {
    if p.is_null() {
        return Err(format!("`{what}` is NULL"));
    }
    // SAFETY: a non-NULL pointer is a NUL-terminated string (the caller's contract).
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| format!("`{what}` is not valid UTF-8"))
}

/// A caller's SOURCE or OUTPUT argument with its bytes as they are (`what` names it in
/// errors): on Unix a file name is bytes, and one that is not UTF-8 is read or written as any
/// other (inline JSON must still be UTF-8, which the library checks). Elsewhere it must be
/// UTF-8.
///
/// # Safety
/// `p` is NULL or a NUL-terminated string.
unsafe fn source_text<'a>(p: *const c_char, what: &str) -> Result<&'a std::ffi::OsStr, String> {
    if p.is_null() {
        return Err(format!("`{what}` is NULL"));
    }
    // SAFETY: a non-NULL pointer is a NUL-terminated string (the caller's contract).
    let s = unsafe { CStr::from_ptr(p) };
    #[cfg(unix)]
    return Ok(std::os::unix::ffi::OsStrExt::from_bytes(s.to_bytes()));
    #[cfg(not(unix))]
    s.to_str()
        .map(std::ffi::OsStr::new)
        .map_err(|_| format!("`{what}` is not valid UTF-8"))
}

/// Checks the caller's `size` against this library's layout (see [`brdftab_open_options`]).
///
/// # Safety
/// `opts` points to a valid struct of at least `max(size, size_of::<brdftab_open_options>())`
/// readable bytes (the caller's contract).
unsafe fn check_size(opts: *const brdftab_open_options) -> Result<(), String> {
    let known = std::mem::size_of::<brdftab_open_options>();
    // SAFETY: `size` is the first field of a valid struct.
    let size = unsafe { (*opts).size };
    if size == 0 || size == known {
        return Ok(());
    }
    if size < known {
        return Err(format!(
            "options size {size}: expected 0 or sizeof(brdftab_open_options) ({known})"
        ));
    }
    // SAFETY: the caller's struct has `size` readable bytes; bytes past our layout are read.
    let extra = unsafe { std::slice::from_raw_parts(opts.cast::<u8>().add(known), size - known) };
    match extra.iter().position(|&b| b != 0) {
        None => Ok(()),
        Some(i) => Err(format!(
            "options size {size}: byte {} is set, a field this library ({}) does not know; \
             link the brdftab the program's header comes from",
            known + i,
            env!("CARGO_PKG_VERSION")
        )),
    }
}

/// The library's open options of a C options struct.
fn open_options(opts: &brdftab_open_options) -> Result<OpenOptions, String> {
    let interp = match opts.interp {
        0 => None,
        1 => Some(Interp::Nearest),
        2 => Some(Interp::Linear),
        i => {
            return Err(format!(
                "interp {i}: expected 0 (auto), 1 (nearest) or 2 (linear)"
            ));
        }
    };
    let channels = if opts.n_wavelengths > 0 {
        // SAFETY: the caller promises `n_wavelengths` readable doubles.
        let nm = unsafe { slice(opts.wavelengths, opts.n_wavelengths, "wavelengths") }?;
        Some(Channels::wavelengths(nm.to_vec()).map_err(|e| e.to_string())?)
    } else {
        None
    };
    Ok(OpenOptions {
        interp,
        channels,
        eager: opts.eager != 0,
    })
}

/// Opens `source` with the options `opts` makes, as a new handle (NULL on failure).
fn open_impl(
    source: *const c_char,
    opts: impl FnOnce() -> Result<OpenOptions, String>,
) -> *mut brdftab_brdf {
    let mut out = std::ptr::null_mut();
    guard(|| {
        // SAFETY: the header's contract: NULL or a NUL-terminated string.
        let source = unsafe { source_text(source, "source") }?;
        let brdf = brdftab::open_with(source, &opts()?).map_err(|e| e.to_string())?;
        let names = brdf
            .channels()
            .names()
            .into_iter()
            .map(|n| CString::new(n).unwrap_or_default())
            .collect();
        out = Box::into_raw(Box::new(brdftab_brdf { brdf, names }));
        Ok(())
    });
    out
}

/// Opens any SOURCE the CLI takes (model spec JSON, `.json` file, table, `DB#NAME`, MERL
/// `.binary`, RGL `.bsdf`) with the default options. NULL on failure (see
/// [`brdftab_last_error`]).
///
/// # Safety
/// `source` is NULL or a NUL-terminated string.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_open(source: *const c_char) -> *mut brdftab_brdf {
    open_impl(source, || Ok(OpenOptions::default()))
}

/// Opens SOURCE with options (`opts` NULL = defaults). NULL on failure.
///
/// # Safety
/// `source` is NULL or a NUL-terminated string; `opts` is NULL or points to a valid struct
/// whose `size` bytes (this layout's when 0) are readable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_open_with(
    source: *const c_char,
    opts: *const brdftab_open_options,
) -> *mut brdftab_brdf {
    open_impl(source, || {
        if opts.is_null() {
            return Ok(OpenOptions::default());
        }
        // SAFETY: the caller promises a valid struct of `size` bytes (or this layout's).
        unsafe { check_size(opts) }?;
        // SAFETY: as above; the first layout's fields are all there.
        open_options(unsafe { &*opts })
    })
}

/// This thread's last failure, `""` if the last call succeeded. Valid until this thread's next
/// brdftab call. After the thread's storage is destroyed (calls from exit handlers), a fixed
/// note saying so.
#[unsafe(no_mangle)]
pub extern "C" fn brdftab_last_error() -> *const c_char {
    LAST_ERROR
        .try_with(|e| e.borrow().as_deref().unwrap_or(c"").as_ptr())
        .unwrap_or(NO_MESSAGE.as_ptr())
}

/// Closes a handle; NULL is a no-op.
///
/// # Safety
/// `b` is NULL or a handle from `brdftab_open*`, not used again.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_close(b: *mut brdftab_brdf) {
    if !b.is_null() {
        // SAFETY: the handle came from Box::into_raw in `open_impl` and is closed once.
        let _ = brdftab::host::catch_quietly(|| drop(unsafe { Box::from_raw(b) }));
    }
}

/// The number of channels (3 for RGB); 0 for a NULL handle.
///
/// # Safety
/// `b` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_channels(b: *const brdftab_brdf) -> usize {
    // SAFETY: the caller promises NULL or a live handle.
    unsafe { b.as_ref() }.map_or(0, |b| b.names.len())
}

/// What the BRDF declares, as a bit set: lobes diffuse 1, glossy 2, delta 4 (`BRDFTAB_DIFFUSE`,
/// `_GLOSSY`, `_DELTA`), then transmission 8, reciprocal 16, isotropic 32, bilateral 64; 0 for
/// a NULL handle. A renderer maps the lobes to its own flags (pbrt's `BxDFFlags`).
///
/// # Safety
/// `b` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_flags(b: *const brdftab_brdf) -> std::ffi::c_uint {
    // SAFETY: the caller promises NULL or a live handle.
    let Some(b) = (unsafe { b.as_ref() }) else {
        return 0;
    };
    let f = b.brdf.flags();
    [
        f.lobes.diffuse,
        f.lobes.glossy,
        f.lobes.delta,
        f.transmission,
        f.reciprocal,
        f.isotropic,
        f.bilateral,
    ]
    .iter()
    .enumerate()
    .fold(0, |acc, (i, &on)| acc | (std::ffi::c_uint::from(on) << i))
}

/// The name of channel `i` ("R", "G", "B", or e.g. "550nm"); NULL when `i` is out of range or
/// the handle is NULL. Valid while the handle is open.
///
/// # Safety
/// `b` is NULL or a live handle.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_channel_name(b: *const brdftab_brdf, i: usize) -> *const c_char {
    // SAFETY: the caller promises NULL or a live handle.
    unsafe { b.as_ref() }
        .and_then(|b| b.names.get(i))
        .map_or(std::ptr::null(), |n| n.as_ptr())
}

/// f_r for `n` pairs into `f` (n × channels floats, pair-major). 0 on success, -1 on failure.
///
/// # Safety
/// With n > 0: `wi`, `wo` point to 3n doubles, `f` to n·channels floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_eval(
    b: *const brdftab_brdf,
    n: usize,
    wi: *const f64,
    wo: *const f64,
    f: *mut f32,
) -> c_int {
    guard(|| {
        if n == 0 {
            return Ok(());
        }
        // SAFETY (both): the header's contract on sizes; NULL and alignment are checked.
        let (b, wi, wo) = unsafe { pair_args(b, n, wi, wo) }?;
        let f = unsafe { slice_mut(f, times(n, b.names.len(), "f")?, "f") }?;
        match n {
            // A renderer's call per shading point: the lookup itself, not the batch's dispatch.
            1 => b.brdf.eval(wi[0], wo[0], f),
            _ => b.brdf.eval_batch(wi, wo, f),
        }
        healthy(b)
    })
}

/// pdf(wi | wo) of the sampler for `n` pairs into `pdf`. 0 on success, -1 on failure.
///
/// # Safety
/// With n > 0: `wi`, `wo` point to 3n doubles, `pdf` to n doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_pdf(
    b: *const brdftab_brdf,
    n: usize,
    wi: *const f64,
    wo: *const f64,
    pdf: *mut f64,
) -> c_int {
    guard(|| {
        if n == 0 {
            return Ok(());
        }
        // SAFETY (both): the header's contract on sizes; NULL and alignment are checked.
        let (b, wi, wo) = unsafe { pair_args(b, n, wi, wo) }?;
        let pdf = unsafe { slice_mut(pdf, n, "pdf") }?;
        match n {
            1 => pdf[0] = b.brdf.pdf(wi[0], wo[0]),
            _ => b.brdf.pdf_batch(wi, wo, pdf),
        }
        healthy(b)
    })
}

/// f_r and pdf(wi | wo) of the same `n` pairs in one call, what multiple importance sampling
/// asks at every light sample (`f` as [`brdftab_eval`] writes it, `pdf` as [`brdftab_pdf`]);
/// for one pair the source's `eval_pdf`, which shares the work where the model can (a
/// microfacet model's half vector and D). 0 on success, -1 on failure.
///
/// # Safety
/// With n > 0: `wi`, `wo` point to 3n doubles, `f` to n·channels floats, `pdf` to n doubles,
/// neither output overlapping another array.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_eval_pdf(
    b: *const brdftab_brdf,
    n: usize,
    wi: *const f64,
    wo: *const f64,
    f: *mut f32,
    pdf: *mut f64,
) -> c_int {
    guard(|| {
        if n == 0 {
            return Ok(());
        }
        // SAFETY (all): the header's contract on sizes; NULL and alignment are checked.
        let (b, wi, wo) = unsafe { pair_args(b, n, wi, wo) }?;
        let f = unsafe { slice_mut(f, times(n, b.names.len(), "f")?, "f") }?;
        let pdf = unsafe { slice_mut(pdf, n, "pdf") }?;
        match n {
            1 => pdf[0] = b.brdf.eval_pdf(wi[0], wo[0], f),
            _ => {
                b.brdf.eval_batch(wi, wo, f);
                b.brdf.pdf_batch(wi, wo, pdf);
            }
        }
        healthy(b)
    })
}

/// Draws `wi` for each of `n` given `wo` from uniforms `u` (n × 2 in [0, 1)²): `wi` (n × 3),
/// `pdf` (n) and `weight` (n × channels, f cos θi / pdf). A pair with no sample (wo below the
/// horizon, a zero lobe) gets wi = (0, 0, 0), pdf = 0 and weight 0. For a delta source (mirror,
/// refractor) pdf is the library's convention for deltas and the weight is the reflectance.
///
/// # Safety
/// With n > 0: `wo` and `wi` point to 3n doubles, `u` to 2n, `pdf` to n, `weight` to
/// n·channels floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_sample(
    b: *const brdftab_brdf,
    n: usize,
    wo: *const f64,
    u: *const f64,
    wi: *mut f64,
    pdf: *mut f64,
    weight: *mut f32,
) -> c_int {
    guard(|| {
        if n == 0 {
            return Ok(());
        }
        // SAFETY (all six): the header's contract on sizes; NULL and alignment are checked.
        let b = unsafe { handle(b) }?;
        let c = b.names.len();
        let wo = unsafe { slice(wo as *const DVec3, n, "wo") }?;
        let u = unsafe { slice(u as *const DVec2, n, "u") }?;
        let wi = unsafe { slice_mut(wi as *mut DVec3, n, "wi") }?;
        let pdf = unsafe { slice_mut(pdf, n, "pdf") }?;
        let weight = unsafe { slice_mut(weight, times(n, c, "weight")?, "weight") }?;
        // Non-finite input has no sample (the NaN rule of the header): `sample_batch`'s rule.
        let out = brdftab::batch::SampleOut { wi, pdf, weight };
        b.brdf.sample_batch(wo, u, out);
        healthy(b)
    })
}

/// The arguments of a sampling call with delta flags, checked: the handle, `wo` and `u`, the
/// outputs (`width` weights a pair; `None`: the handle's channels) and the flags as `bool`s.
struct Flagged<'a> {
    b: &'a brdftab_brdf,
    wo: &'a [DVec3],
    u: &'a [DVec2],
    out: brdftab::batch::SampleOut<'a>,
    flags: &'a mut [bool],
}

/// # Safety
/// `b` is NULL or a live handle; with n > 0, `wo` and `wi` point to 3n doubles, `u` to 2n,
/// `pdf` to n, `weight` to n·width floats and `delta` to n bytes (NULL and alignment checked).
#[allow(clippy::too_many_arguments)]
unsafe fn flagged_args<'a>(
    b: *const brdftab_brdf,
    n: usize,
    wo: *const f64,
    u: *const f64,
    wi: *mut f64,
    pdf: *mut f64,
    weight: *mut f32,
    width: Option<usize>,
    delta: *mut u8,
) -> Result<Flagged<'a>, String> {
    // SAFETY (all seven): the caller's contract on sizes; NULL and alignment are checked.
    let b = unsafe { handle(b) }?;
    let width = width.unwrap_or(b.names.len());
    let wo = unsafe { slice(wo as *const DVec3, n, "wo") }?;
    let u = unsafe { slice(u as *const DVec2, n, "u") }?;
    let wi = unsafe { slice_mut(wi as *mut DVec3, n, "wi") }?;
    let pdf = unsafe { slice_mut(pdf, n, "pdf") }?;
    // No wavelengths (brdftab_sample_spectral with k = 0), no weights: `weight` may be NULL, as
    // `nm` may and as brdftab_eval_spectral's `f` may.
    let weight = match width {
        0 => &mut [][..],
        _ => unsafe { slice_mut(weight, times(n, width, "weight")?, "weight") }?,
    };
    let flags = unsafe { slice_mut(delta, n, "delta") }?;
    // Zeroed first, the bytes are valid `bool`s (false); the library writes 0 or 1.
    flags.fill(0);
    // SAFETY: u8 and bool have one size and alignment, and every byte is now 0.
    let flags = unsafe { std::slice::from_raw_parts_mut(flags.as_mut_ptr() as *mut bool, n) };
    let out = brdftab::batch::SampleOut { wi, pdf, weight };
    Ok(Flagged {
        b,
        wo,
        u,
        out,
        flags,
    })
}

/// [`brdftab_sample`] and each draw's delta flag: `delta[k]` = 1 where pair `k` drew a delta
/// lobe (a mirror, or a sum's mirror term — its pdf is then the probability of choosing that
/// lobe, not a density, and `brdftab_pdf` does not contain it; its weight is the lobe's
/// reflectance over that probability), else 0 ([`brdftab::brdf::sample_flagged`]). What a
/// renderer needs to give such draws its specular path (no MIS with light sampling).
///
/// # Safety
/// With n > 0: as [`brdftab_sample`], and `delta` points to n bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_sample_delta(
    b: *const brdftab_brdf,
    n: usize,
    wo: *const f64,
    u: *const f64,
    wi: *mut f64,
    pdf: *mut f64,
    weight: *mut f32,
    delta: *mut u8,
) -> c_int {
    guard(|| {
        if n == 0 {
            return Ok(());
        }
        // SAFETY: the header's contract on sizes; NULL and alignment are checked.
        let a = unsafe { flagged_args(b, n, wo, u, wi, pdf, weight, None, delta) }?;
        brdftab::brdf::sample_flagged(&a.b.brdf, a.wo, a.u, a.out, a.flags);
        let b = a.b;
        healthy(b)
    })
}

/// The `k` wavelengths of a spectral call: NULL is an error unless `k` = 0, and every entry must
/// be a wavelength (finite, > 0 nm).
///
/// # Safety
/// With k > 0, `nm` points to k doubles.
unsafe fn wavelengths<'a>(k: usize, nm: *const f64) -> Result<&'a [f64], String> {
    if k == 0 {
        return Ok(&[]);
    }
    // SAFETY: the caller's contract; NULL and alignment are checked.
    let nm = unsafe { slice(nm, k, "nm") }?;
    match nm.iter().find(|&&x| !brdftab::spectrum::is_wavelength(x)) {
        Some(x) => Err(format!(
            "`nm`: {x} is not a wavelength (a finite number of nm > 0)"
        )),
        None => Ok(nm),
    }
}

/// f_r of `n` pairs at the `k` wavelengths `nm` into `f` (n × k): a source's own spectral data
/// where it has them (models, spectral RGL files), its channels otherwise (wavelength channels
/// interpolated; RGB through the colour-preserving basis of [`brdftab::colour`], whose
/// spectrum renders as the RGB) — [`brdftab::brdf::eval_wavelengths`]. For renderers that draw their
/// wavelengths per path (pbrt-v4), where a handle opened at fixed wavelengths does not serve.
///
/// # Safety
/// With n > 0: `wi`, `wo` point to 3n doubles, `f` to n·k floats; with k > 0, `nm` to k doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_eval_spectral(
    b: *const brdftab_brdf,
    n: usize,
    wi: *const f64,
    wo: *const f64,
    k: usize,
    nm: *const f64,
    f: *mut f32,
) -> c_int {
    guard(|| {
        if n == 0 {
            return Ok(());
        }
        // SAFETY (all four): the header's contract on sizes; NULL and alignment are checked.
        let (b, wi, wo) = unsafe { pair_args(b, n, wi, wo) }?;
        let nm = unsafe { wavelengths(k, nm) }?;
        // No wavelengths, no values: `f` may be NULL, as `nm` may (and as
        // brdftab_sample_spectral's `weight` may).
        let f = match k {
            0 => &mut [][..],
            _ => unsafe { slice_mut(f, times(n, k, "f")?, "f") }?,
        };
        brdftab::brdf::eval_wavelengths(&b.brdf, wi, wo, nm, f);
        healthy(b)
    })
}

/// [`brdftab_sample_delta`] with the weights at the `k` wavelengths `nm` (`weight`: n × k) —
/// a mirror's reflectance at each of them for its draws ([`brdftab::brdf::sample_flagged_at`]).
///
/// # Safety
/// With n > 0: as [`brdftab_sample_delta`], with `weight` of n·k floats; with k > 0, `nm`
/// points to k doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_sample_spectral(
    b: *const brdftab_brdf,
    n: usize,
    wo: *const f64,
    u: *const f64,
    k: usize,
    nm: *const f64,
    wi: *mut f64,
    pdf: *mut f64,
    weight: *mut f32,
    delta: *mut u8,
) -> c_int {
    guard(|| {
        if n == 0 {
            return Ok(());
        }
        // SAFETY: the header's contract on sizes; NULL and alignment are checked.
        let nm = unsafe { wavelengths(k, nm) }?;
        let a = unsafe { flagged_args(b, n, wo, u, wi, pdf, weight, Some(k), delta) }?;
        brdftab::brdf::sample_flagged_at(&a.b.brdf, a.wo, a.u, nm, a.out, a.flags);
        let b = a.b;
        healthy(b)
    })
}

/// Directional albedo a(θ′) = ∫ f_r cos θ dω for light incident at polar angle `theta` (radians,
/// azimuth 0), one double per channel into `albedo`. 0 on success, -1 on failure (a `theta`
/// outside [0, π/2), light at or below the horizon: [`brdftab::analysis::albedo::incidence`]).
///
/// # Safety
/// `albedo` points to `brdftab_channels(b)` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_albedo(
    b: *const brdftab_brdf,
    theta: f64,
    albedo: *mut f64,
) -> c_int {
    guard(|| {
        // SAFETY (both): the header's contract; NULL and alignment are checked.
        let b = unsafe { handle(b) }?;
        let out = unsafe { slice_mut(albedo, b.names.len(), "albedo") }?;
        let wi = brdftab::analysis::albedo::incidence(theta).map_err(|e| e.to_string())?;
        b.brdf.albedo(wi, out);
        healthy(b)
    })
}

/// [`brdftab_albedo`] for light at polar angle `theta` and azimuth `phi` (radians, from the local
/// x axis, α_x's direction): an anisotropic source reflects a different share of light from each
/// azimuth. A non-finite `phi` is -1, as a `theta` outside [0, π/2) is
/// ([`brdftab::analysis::albedo::incidence_at`]).
///
/// # Safety
/// `albedo` points to `brdftab_channels(b)` doubles.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_albedo_at(
    b: *const brdftab_brdf,
    theta: f64,
    phi: f64,
    albedo: *mut f64,
) -> c_int {
    guard(|| {
        // SAFETY (both): the header's contract; NULL and alignment are checked.
        let b = unsafe { handle(b) }?;
        let out = unsafe { slice_mut(albedo, b.names.len(), "albedo") }?;
        let wi = brdftab::analysis::albedo::incidence_at(theta, phi).map_err(|e| e.to_string())?;
        b.brdf.albedo(wi, out);
        healthy(b)
    })
}

/// Panics inside the boundary's guard and returns its result (-1): what a bug in the library
/// would do. For the tests of the quiet panic hook only; not part of the C ABI (not exported).
#[doc(hidden)]
pub fn panic_for_tests() -> c_int {
    guard(|| panic!("a deliberate panic (test)"))
}

/// The version of this ABI's crate (e.g. "0.1.0"), a static string.
#[unsafe(no_mangle)]
pub extern "C" fn brdftab_version() -> *const c_char {
    concat!(env!("CARGO_PKG_VERSION"), "\0").as_ptr().cast()
}
