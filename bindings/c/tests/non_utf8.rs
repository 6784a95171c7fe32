//! The C ABI passes a SOURCE's bytes through unchanged (session 41): a file whose name is not
//! UTF-8 opens, bakes and converts (`brdftab_open`, `brdftab_bake`, `brdftab_convert`; they
//! returned NULL / -1 with "`source` is not valid UTF-8"), and a missing one is named lossily.
//! And an OUTPUT's (session 42): `brdftab_bake` and `brdftab_convert` write to a file or
//! `DB#NAME` whose path is not UTF-8 (they returned -1 with "`output` is not valid UTF-8").
#![cfg(all(unix, not(target_vendor = "apple")))]
// Apple's file systems refuse a file name that is not UTF-8 (APFS: EILSEQ), so these files
// cannot be made there; the byte handling itself is the other Unixes'.

use std::ffi::{CStr, CString, OsString};
use std::os::unix::ffi::{OsStrExt, OsStringExt};
use std::path::{Path, PathBuf};

use brdftab::testkit::TempDir;
use brdftab_c::*;

fn c_path(p: &Path) -> CString {
    CString::new(p.as_os_str().as_bytes()).unwrap()
}

fn last_error() -> String {
    // SAFETY: a NUL-terminated string owned by this thread.
    unsafe { CStr::from_ptr(brdftab_last_error()) }
        .to_string_lossy()
        .into_owned()
}

/// f_r at (wi, wo) = (0.6, 0, 0.8), z of SOURCE through the C ABI; `None` and the message on
/// failure.
fn eval(source: &CStr) -> Result<Vec<f32>, String> {
    // SAFETY: valid NUL-terminated strings and arrays of the sizes given.
    unsafe {
        let b = brdftab_open(source.as_ptr());
        if b.is_null() {
            return Err(last_error());
        }
        let c = brdftab_channels(b);
        let mut f = vec![0.0f32; c];
        let (wi, wo) = ([0.6, 0.0, 0.8], [0.0, 0.0, 1.0]);
        let r = brdftab_eval(b, 1, wi.as_ptr(), wo.as_ptr(), f.as_mut_ptr());
        brdftab_close(b);
        assert_eq!(r, 0, "{}", last_error());
        Ok(f)
    }
}

fn latin1(d: &TempDir, name: &str) -> PathBuf {
    let mut b = b"caf\xe9-".to_vec();
    b.extend_from_slice(name.as_bytes());
    d.path().join(OsString::from_vec(b))
}

#[test]
fn a_source_whose_name_is_not_utf8_opens_bakes_and_converts() {
    let d = TempDir::new("c-non-utf8");
    let spec = latin1(&d, "matte.json");
    let json = r#"{"model": "lambert", "kd": [0.1, 0.2, 0.3]}"#;
    std::fs::write(&spec, json).unwrap();
    let want = eval(&CString::new(json).unwrap()).unwrap();
    assert_eq!(eval(&c_path(&spec)).unwrap(), want);

    let out = d.path().join("t.btdb");
    let settings = CString::new(r#"{"preset": "small"}"#).unwrap();
    // SAFETY: valid NUL-terminated strings.
    let r = unsafe {
        brdftab_bake(
            c_path(&spec).as_ptr(),
            c_path(&out).as_ptr(),
            settings.as_ptr(),
        )
    };
    assert_eq!(r, 0, "{}", last_error());
    let table = latin1(&d, "t.btdb");
    std::fs::rename(&out, &table).unwrap();
    let from_table = eval(&c_path(&table)).unwrap();
    // A constant: the log16 table holds it within 1e-3.
    for (a, b) in from_table.iter().zip(&want) {
        assert!((a - b).abs() <= 1e-3 * b, "{a} vs {b}");
    }
    let lib = d.path().join("lib.btdb");
    let entry = CString::new(format!("{}#m", lib.display())).unwrap();
    let pairs = CString::new(r#"{"pairs": 0}"#).unwrap();
    // SAFETY: valid NUL-terminated strings.
    let r = unsafe { brdftab_convert(c_path(&table).as_ptr(), entry.as_ptr(), pairs.as_ptr()) };
    assert_eq!(r, 0, "{}", last_error());
    assert!(eval(&entry).is_ok());

    let e = eval(&c_path(&latin1(&d, "missing.btdb"))).unwrap_err();
    assert!(e.contains("caf\u{FFFD}-missing.btdb"), "{e}");
}

/// `path` + `#name`, as bytes.
fn c_entry(path: &Path, name: &str) -> CString {
    let mut b = path.as_os_str().as_bytes().to_vec();
    b.extend_from_slice(format!("#{name}").as_bytes());
    CString::new(b).unwrap()
}

/// A host's monitor that never stops the work.
unsafe extern "C" fn go_on(_user: *mut std::ffi::c_void, _n: f64) -> std::ffi::c_int {
    1
}

#[test]
fn bake_and_convert_write_to_outputs_whose_names_are_not_utf8() {
    let d = TempDir::new("c-non-utf8-out");
    let json = r#"{"model": "lambert", "kd": [0.1, 0.2, 0.3]}"#;
    let spec = CString::new(json).unwrap();
    let want = eval(&spec).unwrap();
    let (table, lib, bsdf) = (
        latin1(&d, "t.btdb"),
        latin1(&d, "lib.btdb"),
        latin1(&d, "t.bsdf"),
    );
    let monitored = latin1(&d, "m.btdb");
    let settings = CString::new(r#"{"preset": "small"}"#).unwrap();
    let pairs = CString::new(r#"{"pairs": 0}"#).unwrap();
    let small_rgl = CString::new(r#"{"pairs": 0, "resolution": 8, "theta_i": 3, "phi_i": 1}"#);
    let small_rgl = small_rgl.unwrap();
    // SAFETY (each call): valid NUL-terminated strings.
    let runs = [
        unsafe { brdftab_bake(spec.as_ptr(), c_path(&table).as_ptr(), settings.as_ptr()) },
        unsafe {
            brdftab_bake(
                spec.as_ptr(),
                c_entry(&lib, "b").as_ptr(),
                settings.as_ptr(),
            )
        },
        unsafe {
            brdftab_convert(
                c_path(&table).as_ptr(),
                c_entry(&lib, "c").as_ptr(),
                pairs.as_ptr(),
            )
        },
        unsafe { brdftab_convert(spec.as_ptr(), c_path(&bsdf).as_ptr(), small_rgl.as_ptr()) },
        // The monitored calls too (they required a UTF-8 OUTPUT when first merged).
        unsafe {
            brdftab_bake_monitored(
                spec.as_ptr(),
                c_path(&monitored).as_ptr(),
                settings.as_ptr(),
                Some(go_on),
                std::ptr::null_mut(),
            )
        },
        unsafe {
            brdftab_convert_monitored(
                c_path(&table).as_ptr(),
                c_entry(&lib, "m").as_ptr(),
                pairs.as_ptr(),
                Some(go_on),
                std::ptr::null_mut(),
            )
        },
    ];
    assert_eq!(runs, [0; 6], "{}", last_error());
    // The constant within log16's 1e-3, twice over for the table converted from a table.
    for source in [
        c_path(&table),
        c_entry(&lib, "b"),
        c_entry(&lib, "c"),
        c_path(&monitored),
        c_entry(&lib, "m"),
    ] {
        for (a, b) in eval(&source).unwrap().iter().zip(&want) {
            assert!((a - b).abs() <= 2.1e-3 * b, "{source:?}: {a} vs {b}");
        }
    }
    assert!(eval(&c_path(&bsdf)).is_ok());
    // A directory that does not exist: -1, named lossily.
    let missing = latin1(&d, "none").join("t.btdb");
    // SAFETY: valid NUL-terminated strings.
    let r = unsafe { brdftab_bake(spec.as_ptr(), c_path(&missing).as_ptr(), settings.as_ptr()) };
    assert_eq!(r, -1);
    let e = last_error();
    assert!(e.contains("caf\u{FFFD}-none"), "{e}");
}
