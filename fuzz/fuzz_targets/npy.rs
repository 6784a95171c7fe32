//! Any bytes as a `.npy` array (`brdftab import`, `store::npy`): the header read and checked
//! against the input's size, then the data — must return errors, never panic, never allocate
//! beyond what the input holds.
#![no_main]

use brdftab::store::npy::NpyReader;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(r) = NpyReader::new("fuzz.npy", data, data.len() as u64) else { return };
    let n = r.header().elements();
    if let Ok(v) = r.read_f32() {
        assert_eq!(v.len(), n);
    }
});
