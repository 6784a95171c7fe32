//! Any bytes as a table SOURCE: the store opened lazily (the default of every host), the table
//! as a `TabulatedBrdf`, evaluated, sampled, its albedo integrated; a corrupt chunk must end
//! in `health()` = Err, never a panic.
//!
//! Cost: the importance sampler behind `pdf`/`sample` evaluates the table at a fixed grid of
//! points whatever the table's size (64 × 64 half-vector nodes at 32 θo nodes, and 16 φo
//! nodes when anisotropic) — most of this target's time when built on every input. So the
//! sampler is built at a small resolution picked by the input's hash (0–8 nodes over θh and
//! 1–8 over φh, which `build` raises to 2; 0–3 θo and 1–3 φo nodes; floors 0.005, 0.05, 0, 1
//! and NaN: the same `TableSampler::build`, `sample` and `pdf` code, resolutions and floors
//! the library's defaults never reach included), and on 1 input in 256 lazily as hosts build
//! it (`TableSampler::for_source`, which in this `cfg(fuzzing)` build starts from
//! `SamplingResolution::coarse()` rather than the defaults: 6.9 s per input under load, over
//! the timeout). The albedo is
//! integrated on 1 input in 16 (coarse options, `common::coarse_albedo`).
#![no_main]

#[path = "common.rs"]
mod common;

use brdftab::store::{Store, StoreOptions};
use brdftab::table::SamplingResolution;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let opts = StoreOptions { cache_bytes: 1 << 20, eager: false };
    let Ok(s) = Store::from_bytes("fuzz.btdb", data.to_vec(), opts) else { return };
    let Ok(t) = s.single() else { return };
    let Ok(mut b) = t.brdf() else { return };
    // Refuse tables too large to evaluate quickly (the fuzzer's time, not a bug).
    if b.grid().stored_values() > 1 << 22 {
        return;
    }
    let h = common::hash(data);
    if h & 0xff != 0 {
        let pick = |shift: u32, n: u64| ((h >> shift) % n) as usize;
        b.set_sampling_resolution(&SamplingResolution {
            theta_h: [0, 2, 3, 5, 8][pick(8, 5)],
            phi_h: [1, 2, 3, 5, 8][pick(12, 5)],
            theta_o: pick(16, 4),
            phi_o: 1 + pick(24, 3),
            floor: [0.005, 0.05, 0.0, 1.0, f64::NAN][pick(40, 5)],
        });
    }
    common::exercise(&b);
    if (h >> 48) & 0xf == 0 {
        common::coarse_albedo(&b);
    }
    // Every chunk: an error (checksum, size) is fine, a panic is not.
    let _ = b.load_all();
});
