//! Any bytes as an RGL-EPFL `.bsdf` SOURCE: parsed, opened, evaluated.
#![no_main]

#[path = "common.rs"]
mod common;

use brdftab::measured::RglBrdf;
use brdftab::measured::tensor::TensorFile;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(t) = TensorFile::from_bytes("fuzz.bsdf", data.to_vec()) else { return };
    let Ok(b) = RglBrdf::from_tensor(&t, None) else { return };
    common::exercise(&b);
});
