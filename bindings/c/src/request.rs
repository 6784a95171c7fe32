//! The library's request layer for C: opens, bakes, conversions and fits whose settings are a
//! JSON object with the field names of the CLI's flags and Python's keywords
//! ([`brdftab::request`]): `{"target_error": 0.005, "codec": "f16"}`. NULL or `""` settings are
//! the defaults; an unknown field is an error naming it.

use std::ffi::{CString, OsStr, c_char, c_int, c_void};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use brdftab::progress::{Progress, Silent};
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
    // SAFETY: the caller's contract; no monitor.
    unsafe { brdftab_bake_monitored(source, output, settings_json, None, std::ptr::null_mut()) }
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
    // SAFETY: the caller's contract; no monitor.
    unsafe { brdftab_convert_monitored(source, output, settings_json, None, std::ptr::null_mut()) }
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

/// A host's progress monitor (`brdftab_progress_fn` in the header, after Open Image Denoise's
/// `OIDNProgressMonitorFunction`): called with the host's `user` pointer and the fraction done
/// `n` in [0, 1]; returning 0 asks the operation to stop. NULL monitors nothing.
#[allow(non_camel_case_types)]
pub type brdftab_progress_fn = Option<unsafe extern "C" fn(user: *mut c_void, n: f64) -> c_int>;

/// How often a monitored call reports its fraction to the host's monitor (and so how soon a
/// stop is seen: the library then stops within a unit of work, ~0.3 s at most).
const MONITOR_INTERVAL: std::time::Duration = std::time::Duration::from_millis(50);

/// The largest fraction reported while the work runs: 1 is reported once, when it succeeded.
const RUNNING_MAX: f64 = 0.999;

/// What a monitored operation reports, read by the calling thread: the largest fraction any
/// stage has reached (f64 bits, non-negative, so their order is the numbers'), the current
/// stage's total, and the host's request to stop.
#[derive(Default)]
struct Monitor {
    fraction: AtomicU64,
    total: AtomicU64,
    stop: AtomicBool,
}

impl Progress for Monitor {
    fn begin(&self, _what: &str, total: u64) {
        self.total.store(total, Ordering::Relaxed);
    }
    fn set(&self, done: u64) {
        let total = self.total.load(Ordering::Relaxed);
        if total > 0 {
            let f = (done as f64 / total as f64).clamp(0.0, 1.0);
            self.fraction.fetch_max(f.to_bits(), Ordering::Relaxed);
        }
    }
    fn cancelled(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// Runs `work` with the host's monitor `f`: on a thread of its own, while this (the host's)
/// thread calls `f(user, n)` — first with 0 before any work, then every [`MONITOR_INTERVAL`]
/// with the fraction reached, and with 1 once the work succeeded — so the host's monitor is
/// never called from another thread nor concurrently. A 0 from it asks the work to stop (no
/// further calls); the work then returns `Error::Cancelled`, leaving its output as it was.
/// Without a monitor, `work` runs here with nothing to report.
fn monitored<T: Send>(
    f: brdftab_progress_fn,
    user: *mut c_void,
    work: impl FnOnce(&dyn Progress) -> brdftab::Result<T> + Send,
) -> Result<T, String> {
    let Some(f) = f else {
        return work(&Silent).map_err(|e| e.to_string());
    };
    // SAFETY: the caller's contract: `f` is callable with `user`, on this thread.
    let ask = |n: f64| unsafe { f(user, n) } != 0;
    if !ask(0.0) {
        return Err(brdftab::Error::Cancelled.to_string());
    }
    let m = Monitor::default();
    let m = &m;
    let r = std::thread::scope(|s| {
        let (tx, rx) = std::sync::mpsc::channel();
        s.spawn(move || {
            let _ = tx.send(brdftab::host::catch_quietly(|| work(m)));
        });
        let mut asking = true;
        loop {
            match rx.recv_timeout(MONITOR_INTERVAL) {
                Ok(r) => break r,
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                    // Below 1 while the work runs: a stage that finished (the source's albedo
                    // integrated) reached 1 with the bake still ahead, and a host reads 1 as done.
                    let n = f64::from_bits(m.fraction.load(Ordering::Relaxed)).min(RUNNING_MAX);
                    if asking && !ask(n) {
                        m.stop.store(true, Ordering::Relaxed);
                        asking = false;
                    }
                }
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                    break Err("the work's thread ended without a result".into());
                }
            }
        }
    });
    match r {
        Ok(Ok(v)) => {
            // Done: the monitor sees 1 (its answer no longer matters).
            let _ = ask(1.0);
            Ok(v)
        }
        Ok(Err(e)) => Err(e.to_string()),
        Err(p) => Err(format!("internal error (panic): {p}")),
    }
}

/// A bake or conversion of SOURCE into OUTPUT (their bytes as they are) with settings as JSON,
/// run under the host's monitor: 0, or -1 with the reason.
///
/// # Safety
/// As [`brdftab_bake_monitored`].
unsafe fn write_request<S, R>(
    source: *const c_char,
    output: *const c_char,
    settings_json: *const c_char,
    progress: brdftab_progress_fn,
    user: *mut c_void,
    run: impl FnOnce(&OsStr, &OsStr, &S, &dyn Progress) -> brdftab::Result<R> + Send,
) -> c_int
where
    S: serde::de::DeserializeOwned + serde::Serialize + Default + Sync,
    R: Send,
{
    guard(|| {
        // SAFETY (all three): the caller's contract.
        let (source, output) = unsafe {
            (
                source_text(source, "source")?,
                source_text(output, "output")?,
            )
        };
        let s: S = unsafe { settings(settings_json) }?;
        monitored(progress, user, |p| run(source, output, &s, p).map(drop))
    })
}

/// [`brdftab_bake`] reporting to, and stoppable by, the host's monitor `progress` (called on
/// this thread only: see the header). A stopped bake returns -1 with "cancelled" and leaves
/// OUTPUT as it was. NULL `progress` is [`brdftab_bake`].
///
/// # Safety
/// As [`brdftab_bake`]; `progress`, when not NULL, is callable with `user`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_bake_monitored(
    source: *const c_char,
    output: *const c_char,
    settings_json: *const c_char,
    progress: brdftab_progress_fn,
    user: *mut c_void,
) -> c_int {
    // SAFETY: the caller's contract.
    unsafe {
        write_request(
            source,
            output,
            settings_json,
            progress,
            user,
            |s, o, x: &BakeSettings, p| request::bake(s, o, x, p),
        )
    }
}

/// [`brdftab_convert`] with the host's monitor, as [`brdftab_bake_monitored`].
///
/// # Safety
/// As [`brdftab_bake_monitored`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_convert_monitored(
    source: *const c_char,
    output: *const c_char,
    settings_json: *const c_char,
    progress: brdftab_progress_fn,
    user: *mut c_void,
) -> c_int {
    // SAFETY: the caller's contract.
    unsafe {
        write_request(
            source,
            output,
            settings_json,
            progress,
            user,
            |s, o, x: &ConvertSettings, p| request::convert(s, o, x, p),
        )
    }
}

/// [`brdftab_fit`] with the host's monitor, as [`brdftab_bake_monitored`]: NULL with
/// "cancelled" when stopped.
///
/// # Safety
/// As [`brdftab_fit`]; `progress`, when not NULL, is callable with `user`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn brdftab_fit_monitored(
    source: *const c_char,
    model: *const c_char,
    settings_json: *const c_char,
    progress: brdftab_progress_fn,
    user: *mut c_void,
) -> *mut c_char {
    let mut out = std::ptr::null_mut();
    guard(|| {
        // SAFETY (all three): the caller's contract.
        let (source, model) = unsafe { (source_text(source, "source")?, text(model, "model")?) };
        let s: FitSettings = unsafe { settings(settings_json) }?;
        let r = monitored(progress, user, |p| request::fit(source, model, &s, p))?;
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
