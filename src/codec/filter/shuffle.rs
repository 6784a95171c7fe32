//! Byte and bit shuffling of filtered words, and their inverses: the last step before the
//! entropy coder, separate from the prediction.

use super::Word;

/// Splits words into byte planes (all low bytes, then the next, ...), appending to `out`.
pub fn shuffle<W: Word>(words: &[W], out: &mut Vec<u8>) {
    let n = words.len();
    let base = out.len();
    out.resize(base + n * W::BYTES, 0);
    let dst = &mut out[base..];
    for k in 0..W::BYTES {
        let plane = &mut dst[k * n..(k + 1) * n];
        for (d, w) in plane.iter_mut().zip(words) {
            *d = w.byte(k);
        }
    }
}

/// Splits words into bit planes (bit 0 of every word, then bit 1, ...), appending to `out`.
pub fn bitshuffle<W: Word>(words: &[W], out: &mut Vec<u8>) {
    let n = words.len();
    let pb = n.div_ceil(8);
    let base = out.len();
    out.resize(base + pb * W::BYTES * 8, 0);
    let dst = &mut out[base..];
    for (g, ws) in words.chunks(8).enumerate() {
        for k in 0..W::BYTES {
            let bytes: [u8; 8] = std::array::from_fn(|t| ws.get(t).map_or(0, |w| w.byte(k)));
            for bit in 0..8 {
                let mut b = 0u8;
                for (t, &x) in bytes.iter().enumerate() {
                    b |= ((x >> bit) & 1) << t;
                }
                dst[(k * 8 + bit) * pb + g] = b;
            }
        }
    }
}

/// Inverse of [`bitshuffle`]: `bytes` must hold exactly `out.len().div_ceil(8) * W::BYTES * 8`.
pub fn unbitshuffle<W: Word>(bytes: &[u8], out: &mut [W]) {
    let n = out.len();
    let pb = n.div_ceil(8);
    out.fill(W::default());
    for k in 0..W::BYTES {
        for (g, ws) in out.chunks_mut(8).enumerate() {
            let mut acc = [0u8; 8];
            for bit in 0..8 {
                let b = bytes[(k * 8 + bit) * pb + g];
                for (t, a) in acc.iter_mut().enumerate() {
                    *a |= ((b >> t) & 1) << bit;
                }
            }
            for (t, w) in ws.iter_mut().enumerate() {
                *w = w.with_byte(k, acc[t]);
            }
        }
    }
}

/// Inverse of [`shuffle`]: `bytes` must hold exactly `out.len() * W::BYTES` bytes.
pub fn unshuffle<W: Word>(bytes: &[u8], out: &mut [W]) {
    let n = out.len();
    debug_assert_eq!(bytes.len(), n * W::BYTES);
    out.fill(W::default());
    for k in 0..W::BYTES {
        let plane = &bytes[k * n..(k + 1) * n];
        for (w, &b) in out.iter_mut().zip(plane) {
            *w = w.with_byte(k, b);
        }
    }
}
