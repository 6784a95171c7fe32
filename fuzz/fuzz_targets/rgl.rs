//! Any bytes as an RGL-EPFL `.bsdf` SOURCE: parsed, opened, evaluated, sampled; on 1 input in
//! 16 (by the input's hash) its albedo integrated by the library's quadrature with coarse
//! options (`common::coarse_albedo`; the default `Brdf::albedo` of an RGL file, what
//! `brdftab_albedo` runs, at 1/4,000 of its worst-case work). The sampler behind `pdf` and
//! `sample` is `TableSampler::for_source`'s, which in this `cfg(fuzzing)` build starts from
//! `SamplingResolution::coarse()` (at the defaults each input took 6.2 s under load: the run
//! never got past its seeds).
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
    if common::hash(data) >> 60 == 0 {
        common::coarse_albedo(&b);
    }
});
