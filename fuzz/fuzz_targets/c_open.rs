//! Any bytes through the C ABI's `brdftab_open_with`: the first byte picks how — an inline
//! SOURCE string, or a file of each kind (`.btdb`, `.bsdf`, `.binary`, `.json`) holding the
//! rest, opened lazily or eagerly — then `brdftab_eval`/`_pdf`/`_sample`/`_albedo` on a few
//! pairs, including counts that overflow. Every call must return 0 or -1; -1 must leave a
//! message in `brdftab_last_error`.
//!
//! Cost: a real `brdftab_albedo` is the library's default quadrature (5,000 to 29 M
//! evaluations; 95 % of this target's time when run on every input: 6 exec/s), and the first
//! `brdftab_pdf`/`_sample` on a table builds its importance sampler (221,184 evaluations). So
//! every input goes through open, `brdftab_eval` (4 pairs and the overflowing counts), `_pdf`
//! and `_sample` with the overflowing counts (which must be refused before anything is read),
//! and `brdftab_albedo` with a NaN angle and with a NULL output (refused); `_pdf`/`_sample` on
//! 4 pairs run on 1 input in 2048 and a real albedo on 1 in 4096 (1 in 2^18 for RGL files),
//! chosen by the input's hash
//! (`common::hash`): on an RGL file the default quadrature takes 10–20 s in this instrumented
//! build, and at 1 in 256 it still took 95 % of the time (627 exec/s); the half-vector sampler
//! (131,072 evaluations to build, 0.5 s on a native RGL file in this build) at 1 in 32 held
//! the target at 20 exec/s; the sampler is now built from `SamplingResolution::coarse()`
//! (`TableSampler::for_source` in this `cfg(fuzzing)` build: at the defaults one input took
//! 14.3 s under load). The sampler and the quadrature themselves are exercised on every
//! kind by the `table`, `rgl` and `spec` targets.
#![no_main]

#[path = "common.rs"]
mod common;

use std::ffi::{CStr, CString};
use std::io::Write;

use brdftab_c::*;
use libfuzzer_sys::fuzz_target;

fn last_error() -> String {
    // SAFETY: a NUL-terminated string owned by this thread.
    unsafe { CStr::from_ptr(brdftab_last_error()) }.to_string_lossy().into_owned()
}

/// Removes the input's temp file when the input is done, however it ends (a NULL open
/// returns early), so a fuzzing run leaves nothing in the temp directory.
struct Removed(std::path::PathBuf);

impl Drop for Removed {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else { return };
    let ext = ["btdb", "bsdf", "binary", "json"];
    let file;
    let _removed;
    let source = if mode % 5 == 4 {
        match CString::new(rest) {
            Ok(s) => s,
            Err(_) => return,
        }
    } else {
        file = std::env::temp_dir().join(format!(
            "brdftab-fuzz-{}.{}",
            std::process::id(),
            ext[(mode % 5) as usize]
        ));
        _removed = Removed(file.clone());
        let mut f = std::fs::File::create(&file).expect("temp file");
        f.write_all(rest).expect("temp write");
        CString::new(file.to_str().expect("utf-8 temp path")).expect("no NUL")
    };
    let opts = brdftab_open_options {
        size: 0,
        interp: (mode >> 4 & 1) as i32,
        n_wavelengths: 0,
        wavelengths: std::ptr::null(),
        eager: (mode >> 5 & 1) as i32,
    };
    // SAFETY: a valid NUL-terminated string and a valid options struct.
    let b = unsafe { brdftab_open_with(source.as_ptr(), &opts) };
    if b.is_null() {
        assert!(!last_error().is_empty(), "NULL without a message");
        return;
    }
    // SAFETY (all calls): `b` is live; the arrays hold what n says (or n overflows and the
    // call must refuse before reading).
    unsafe {
        let c = brdftab_channels(b);
        assert!(c >= 1);
        let n = 4;
        let wi = [0.0, 0.0, 1.0, 0.6, 0.0, 0.8, f64::NAN, 0.0, 1.0, 0.1, 0.2, -0.9];
        let wo = [0.0, 0.0, 1.0, -0.3, 0.1, 0.9, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
        let u = [0.1, 0.2, 0.5, 0.5, 0.9, 0.01, 0.3, 0.3];
        let mut f = vec![0.0f32; n * c];
        let (mut pdf, mut swi, mut w) = ([0.0f64; 4], [0.0f64; 12], vec![0.0f32; n * c]);
        let h = common::hash(data);
        let sampling = h & 0x7ff == 0;
        // The default quadrature on an RGL file: 10–20 s here, so 1 in 2^18 (was 1 in 4096:
        // still 270 exec/s at most, 95 % of the time in `RglBrdf::albedo`).
        let rgl = mode % 5 == 1;
        let albedo = (h >> 8) & 0xfff == 0 && (!rgl || (h >> 20) & 0x3f == 0);
        for count in [n, usize::MAX / 3 + 1, usize::MAX / 24 + 1, usize::MAX / 2 + 1] {
            let r = brdftab_eval(b, count, wi.as_ptr(), wo.as_ptr(), f.as_mut_ptr());
            let mut r = vec![r];
            if count != n || sampling {
                r.push(brdftab_pdf(b, count, wi.as_ptr(), wo.as_ptr(), pdf.as_mut_ptr()));
                r.push(brdftab_sample(
                    b,
                    count,
                    wo.as_ptr(),
                    u.as_ptr(),
                    swi.as_mut_ptr(),
                    pdf.as_mut_ptr(),
                    w.as_mut_ptr(),
                ));
            }
            for r in r {
                assert!(r == 0 || r == -1);
                assert!(r == 0 || !last_error().is_empty());
                assert!(count == n || r == -1, "an overflowing count succeeded");
            }
        }
        let mut a = vec![0.0f64; c];
        for (theta, out) in [(f64::NAN, a.as_mut_ptr()), (0.5, std::ptr::null_mut())] {
            let r = brdftab_albedo(b, theta, out);
            assert!(r == -1 && !last_error().is_empty(), "albedo({theta}, {out:?}) = {r}");
        }
        if albedo {
            let r = brdftab_albedo(b, 0.5, a.as_mut_ptr());
            assert!(r == 0 || r == -1);
            assert!(r == 0 || !last_error().is_empty());
        }
        brdftab_close(b);
    }
});
