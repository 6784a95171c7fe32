//! The library's request layer for C: opens, bakes, conversions and fits whose settings are a
//! JSON object with the field names of the CLI's flags and Python's keywords
//! ([`brdftab::request`]): `{"target_error": 0.005, "codec": "f16"}`. NULL or `""` settings are
//! the defaults; an unknown field is an error naming it.

use std::ffi::{CString, c_char, c_int};

use brdftab::progress::Silent;
use brdftab::request::{self, BakeSettings, ConvertSettings, FitSettings, OpenSettings};

use crate::{brdftab_brdf, guard, open_impl, source_text, text};

/// Settings from a nullable JSON string.
///
/// # Safety
/// `json` is NULL or a NUL-terminated string.
unsafe fn settings<T>(json: *const c_char) -> Result<T, String>
where
    T: serde::de::DeserializeOwned + serde::Serialize + Default,
{
    if json.is_null() {
        return Ok(T::default());
    }
    // SAFETY: the caller's contract.
    let s = unsafe { text(json, "settings") }?;
    request::from_json(s).map_err(|e| e.to_string())
}

/// Opens SOURCE with settings as JSON (`interp`: "auto", "nearest" or "linear"; `wavelengths`;
/// `eager`). NULL on failure.
///
/// # Safety
/// `source` and `settings_json` are NULL or NUL-terminated strings.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_open_json(
    source: *const c_char,
    settings_json: *const c_char,
) -> *mut brdftab_brdf {
    open_impl(source, || {
        // SAFETY: the caller's contract.
        let s: OpenSettings = unsafe { settings(settings_json) }?;
        s.options().map_err(|e| e.to_string())
    })
}

/// Bakes SOURCE into OUTPUT (`DB#NAME`, or a brdftab `.btdb` file under any other name) with
/// bake settings as JSON (the fields of `brdftab bake`'s flags). 0 on success, -1 on failure.
///
/// # Safety
/// The three arguments are NULL or NUL-terminated strings (`source` and `output` must not be
/// NULL).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_bake(
    source: *const c_char,
    output: *const c_char,
    settings_json: *const c_char,
) -> c_int {
    guard(|| {
        // SAFETY (all three): the caller's contract.
        let (source, output) = unsafe {
            (
                source_text(source, "source")?,
                source_text(output, "output")?,
            )
        };
        let s: BakeSettings = unsafe { settings(settings_json) }?;
        request::bake(source, output, &s, &Silent)
            .map(drop)
            .map_err(|e| e.to_string())
    })
}

/// Converts SOURCE into OUTPUT like `brdftab convert` (a `.bsdf`, a MERL `.binary`, `DB#NAME`,
/// a `.btdb` or a raw table, by OUTPUT's name) with convert settings as JSON. 0 or -1.
///
/// # Safety
/// As [`brdftab_bake`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_convert(
    source: *const c_char,
    output: *const c_char,
    settings_json: *const c_char,
) -> c_int {
    guard(|| {
        // SAFETY (all three): the caller's contract.
        let (source, output) = unsafe {
            (
                source_text(source, "source")?,
                source_text(output, "output")?,
            )
        };
        let s: ConvertSettings = unsafe { settings(settings_json) }?;
        request::convert(source, output, &s, &Silent)
            .map(drop)
            .map_err(|e| e.to_string())
    })
}

/// Fits MODEL (`"ggx"`, `"lambert+ggx"` or a JSON spec) to SOURCE with fit settings as JSON;
/// returns the result as JSON (`{"spec": .., "rmse": .., ...}`, as `brdftab fit --json`), to
/// be freed with [`brdftab_free_string`]; NULL on failure.
///
/// # Safety
/// The three arguments are NULL or NUL-terminated strings.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_fit(
    source: *const c_char,
    model: *const c_char,
    settings_json: *const c_char,
) -> *mut c_char {
    let mut out = std::ptr::null_mut();
    guard(|| {
        // SAFETY (all three): the caller's contract.
        let (source, model) = unsafe { (source_text(source, "source")?, text(model, "model")?) };
        let s: FitSettings = unsafe { settings(settings_json) }?;
        let r = request::fit(source, model, &s, &Silent).map_err(|e| e.to_string())?;
        let json = serde_json::to_string(&r).map_err(|e| e.to_string())?;
        out = CString::new(json).map_err(|e| e.to_string())?.into_raw();
        Ok(())
    });
    out
}

/// Frees a string returned by brdftab (`brdftab_fit`); NULL is a no-op.
///
/// # Safety
/// `s` is NULL or a string from a brdftab function, not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_free_string(s: *mut c_char) {
    if !s.is_null() {
        // SAFETY: the caller's contract: a CString brdftab made with `into_raw`.
        drop(unsafe { CString::from_raw(s) });
    }
}
