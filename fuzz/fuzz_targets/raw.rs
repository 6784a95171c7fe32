//! Any bytes as a raw table file (`table::raw`: a JSON header, then f32 values — what
//! `convert` writes for an output named neither `.btdb` nor `DB#NAME`, and a SOURCE every
//! host opens): the header and grid checked against the values the file holds, then the table
//! evaluated and sampled (at `SamplingResolution::coarse()`, as the `db` target). A grid
//! larger than the file must be an error before anything of its size is allocated.
#![no_main]

#[path = "common.rs"]
mod common;

use brdftab::table::{SamplingResolution, TabulatedBrdf};
use brdftab::Table;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(t) = Table::from_raw_bytes("fuzz.raw", data) else { return };
    assert_eq!(t.values().len(), t.grid().stored_values());
    let mut b = TabulatedBrdf::from_table(t);
    b.set_sampling_resolution(&SamplingResolution::coarse());
    common::exercise(&b);
});
