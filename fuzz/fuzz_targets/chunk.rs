//! Any bytes decoded as a codec chunk of up to 4096 values: errors, never panics.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if data.len() < 2 {
        return;
    }
    let n = u16::from_le_bytes([data[0], data[1]]) as usize % 4097;
    let _ = brdftab::codec::decode(&data[2..], n);
});
