//! Chunks written by earlier versions of the codec still decode to exactly the values they
//! decoded to when they were written.
//!
//! `tests/data/log16_v1_chunks.bin` holds log16 chunks of chunk version 1 (reconstructions
//! formed in f64, filters 0–4, tolerances 1e-3 and 1e-2, with escapes: a negative value, a zero,
//! a spike and values below the floor) as encoded by the build that introduced the file,
//! each followed by the f32 bits that build decoded. Records: `u32 chunk length, chunk bytes,
//! u32 n, n × u32 f32 bits`, little-endian.
//!
//! `tests/data/log16_v2_chunks.bin`, in the same records, holds log16 chunks of chunk version 2
//! (reconstructions on the integer grid from 0; filters 0–7, tolerances 1e-3 and 1e-2, three
//! channels, with a zero, a negative, a spike, values below the floor and a constant run) as the
//! last version-2 build encoded and decoded them.

use brdftab::codec;

fn u32_at(b: &[u8], at: usize) -> usize {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize
}

/// Decodes every record of the fixture `name`, checks each against the bits stored with it and
/// its chunk version against `version`; returns the filter of each chunk.
fn decode_fixture(name: &str, version: u8) -> Vec<u8> {
    let b = std::fs::read(format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let mut at = 0;
    let mut filters = Vec::new();
    while at < b.len() {
        let len = u32_at(&b, at);
        let chunk = &b[at + 4..at + 4 + len];
        at += 4 + len;
        let n = u32_at(&b, at);
        let want: Vec<u32> = (0..n).map(|k| u32_at(&b, at + 4 + 4 * k) as u32).collect();
        at += 4 + 4 * n;
        let info = codec::chunk_info(chunk).unwrap();
        assert_eq!(info.quant, "log16");
        assert_eq!(chunk[2], version, "chunk version");
        filters.push(info.filter as u8);
        let got: Vec<u32> = codec::decode(chunk, n)
            .unwrap()
            .iter()
            .map(|v| v.to_bits())
            .collect();
        assert_eq!(got, want, "filter {:?}", info.filter);
    }
    filters
}

#[test]
fn log16_version_1_chunks_decode_bit_identically() {
    let filters = decode_fixture("log16_v1_chunks.bin", 1);
    assert_eq!(filters, [0, 1, 2, 3, 4, 0, 1, 2, 3, 4]);
}

#[test]
fn log16_version_2_chunks_decode_bit_identically() {
    let filters = decode_fixture("log16_v2_chunks.bin", 2);
    let each: Vec<u8> = (0..8).collect();
    assert_eq!(filters, [each.clone(), each].concat());
}
