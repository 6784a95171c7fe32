//! Off Unix a path is not bytes: the C ABI reads a SOURCE or OUTPUT as UTF-8 there and refuses
//! one that is not with -1 (NULL) and a message naming the argument, never a panic or a file
//! of a mangled name. (On Unix such a name is a file name like any other: `non_utf8.rs`.)
#![cfg(not(unix))]

use std::ffi::{CStr, CString};

use brdftab::testkit::TempDir;
use brdftab_c::*;

fn last_error() -> String {
    // SAFETY: a NUL-terminated string owned by this thread.
    unsafe { CStr::from_ptr(brdftab_last_error()) }
        .to_string_lossy()
        .into_owned()
}

#[test]
fn a_source_or_output_that_is_not_utf8_is_refused_with_a_message() {
    let d = TempDir::new("c-non-utf8-elsewhere");
    let mut b = d.path().join("caf").into_os_string().into_string().unwrap();
    b.push_str(".btdb");
    let mut b = b.into_bytes();
    b.insert(b.len() - 5, 0xe9); // `...\caf\xe9.btdb`: Latin-1, not UTF-8
    let bad = CString::new(b).unwrap();
    // SAFETY: valid NUL-terminated strings.
    unsafe {
        assert!(brdftab_open(bad.as_ptr()).is_null());
        let e = last_error();
        assert!(e.contains("`source` is not valid UTF-8"), "{e}");
        let spec = c"{\"model\": \"lambert\", \"kd\": 0.2}";
        assert_eq!(
            brdftab_bake(spec.as_ptr(), bad.as_ptr(), std::ptr::null()),
            -1
        );
        let e = last_error();
        assert!(e.contains("`output` is not valid UTF-8"), "{e}");
        assert_eq!(
            brdftab_bake(bad.as_ptr(), bad.as_ptr(), std::ptr::null()),
            -1
        );
    }
    assert_eq!(
        std::fs::read_dir(d.path()).unwrap().count(),
        0,
        "nothing written"
    );
}
