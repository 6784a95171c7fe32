//! Any bytes as a MERL `.binary` SOURCE: header and size checks, then (for the rare input of
//! the right size) the measurement evaluated.
#![no_main]

#[path = "common.rs"]
mod common;

use brdftab::measured::MerlBrdf;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(b) = MerlBrdf::from_bytes("fuzz.binary", data) else { return };
    common::exercise(&b);
});
