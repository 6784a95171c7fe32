//! Chunks written by earlier versions of the codec still decode to exactly the values they
//! decoded to when they were written.
//!
//! `tests/data/log16_v1_chunks.bin` holds log16 chunks of chunk version 1 (reconstructions
//! formed in f64, filters 0–4, tolerances 1e-3 and 1e-2, with escapes: a negative value, a zero,
//! a spike and values below the floor) as encoded by the build that introduced the file,
//! each followed by the f32 bits that build decoded. Records: `u32 chunk length, chunk bytes,
//! u32 n, n × u32 f32 bits`, little-endian.

use brdftab::codec;

fn u32_at(b: &[u8], at: usize) -> usize {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize
}

#[test]
fn log16_version_1_chunks_decode_bit_identically() {
    let b = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/log16_v1_chunks.bin"
    ))
    .unwrap();
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
        assert_eq!(chunk[2], 1, "chunk version");
        filters.push(info.filter as u8);
        let got: Vec<u32> = codec::decode(chunk, n)
            .unwrap()
            .iter()
            .map(|v| v.to_bits())
            .collect();
        assert_eq!(got, want, "filter {:?}", info.filter);
    }
    assert_eq!(filters, [0, 1, 2, 3, 4, 0, 1, 2, 3, 4]);
}
