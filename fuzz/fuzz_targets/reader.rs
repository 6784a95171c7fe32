//! Any bytes opened as a brdftab file: open, list, open every table, verify, decode, export a
//! slice — must return errors, never panic, never allocate beyond what the input justifies.
#![no_main]

use brdftab::store::{StoreOptions, Store};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let opts = StoreOptions { cache_bytes: 1 << 20, eager: false };
    let Ok(s) = Store::from_bytes("fuzz", data.to_vec(), opts) else { return };
    for e in s.tables().to_vec() {
        let Ok(t) = s.table(&e.name) else { continue };
        let _ = t.grid();
        for i in 0..t.chunk_count() {
            let _ = t.chunk(i);
        }
        let _ = t.read_all();
    }
    let _ = s.verify();
});
