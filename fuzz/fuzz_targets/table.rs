//! Any bytes as a table SOURCE: the store opened lazily (the default of every host), the table
//! as a `TabulatedBrdf`, evaluated; a corrupt chunk must end in `health()` = Err, never a
//! panic.
#![no_main]

#[path = "common.rs"]
mod common;

use brdftab::store::{StoreOptions, Store};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let opts = StoreOptions { cache_bytes: 1 << 20, eager: false };
    let Ok(s) = Store::from_bytes("fuzz.btdb", data.to_vec(), opts) else { return };
    let Ok(t) = s.single() else { return };
    let Ok(b) = t.brdf() else { return };
    // Refuse tables too large to evaluate quickly (the fuzzer's time, not a bug).
    if b.grid().stored_values() > 1 << 22 {
        return;
    }
    common::exercise(&b);
    // Every chunk: an error (checksum, size) is fine, a panic is not.
    let _ = b.load_all();
});
