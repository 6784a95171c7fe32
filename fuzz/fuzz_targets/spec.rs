//! Any bytes as an inline model spec SOURCE: `brdftab::open` (JSON parse, validation, build),
//! then the model evaluated and its albedo integrated at one angle.
#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if !text.trim_start().starts_with('{') {
        return; // a path, not a spec: the file targets cover those
    }
    let Ok(b) = brdftab::open(text) else { return };
    common::exercise(b.as_ref());
    let mut a = vec![0.0; b.channels().len()];
    b.albedo(glam::DVec3::new(0.5, 0.0, 0.866), &mut a);
});
