//! Any bytes as a database of many tables, through the paths the `reader` and `table` targets
//! do not take: each table's `info` summary (`store::info::table_summary`: header, index, grid
//! and the sampler's size, which probes the table's peak through a lazy load), then the eager
//! one-array load a host's `eager` open runs (`StoredTable::to_table`: `read_all` into one
//! reservation, then `Table::new`) as a `TabulatedBrdf::from_table`, evaluated and sampled.
//! On 1 input in 2 (by the input's hash) the store itself is opened eagerly
//! (`StoreOptions::eager`: every chunk of a table decoded when it is opened).
//!
//! The sampler is built at `SamplingResolution::coarse()` (its cost, not a different code
//! path; what `info`'s sizing starts from too in this `cfg(fuzzing)` build); tables over 2^22
//! values are skipped (the fuzzer's time).
#![no_main]

#[path = "common.rs"]
mod common;

use brdftab::Brdf;
use brdftab::store::{Store, StoreOptions, info};
use brdftab::table::{SamplingResolution, TabulatedBrdf};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let h = common::hash(data);
    let opts = StoreOptions { cache_bytes: 1 << 20, eager: h & 1 == 1 };
    let Ok(s) = Store::from_bytes("fuzz.btdb", data.to_vec(), opts) else { return };
    for e in s.tables().to_vec() {
        let _ = info::table_summary(&s, &e.name);
        let Ok(t) = s.table(&e.name) else { continue };
        let Ok(g) = t.grid() else { continue };
        if g.stored_values() > 1 << 22 {
            continue;
        }
        let Ok(table) = t.to_table() else { continue };
        let mut b = TabulatedBrdf::from_table(table);
        b.set_sampling_resolution(&SamplingResolution::coarse());
        common::exercise(&b);
        assert!(b.health().is_ok(), "a table decoded whole must stay healthy");
    }
});
