//! The decoder: a chunk's header read and checked, its payload decompressed to exactly the size
//! the header implies, and the stages undone.

use super::filter::Word;
use super::frame::zstd_decompress;
use super::{
    CHUNK_HEADER_LEN, CHUNK_MAGIC, CHUNK_VERSION, CHUNK_VERSION_MIN, ChunkInfo, Filter, Layout,
    Log16Params, Shuffle, filter, log16, quantize,
};
use crate::error::{Error, Result};

fn bad(field: &str, offset: u64, msg: impl Into<String>) -> Error {
    Error::format("<chunk>", Some(field), Some(offset), msg)
}

fn le_u32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}
fn le_u64(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}
fn le_f64(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

/// Reads and validates a chunk header (does not decompress).
pub fn chunk_info(bytes: &[u8]) -> Result<ChunkInfo> {
    if bytes.len() < CHUNK_HEADER_LEN {
        return Err(bad(
            "chunk header",
            bytes.len() as u64,
            format!(
                "truncated: {} bytes, the header alone is {CHUNK_HEADER_LEN}",
                bytes.len()
            ),
        ));
    }
    if bytes[0..2] != CHUNK_MAGIC {
        return Err(bad("magic", 0, "not a brdftab chunk (bad magic)"));
    }
    let version = bytes[2];
    if !(CHUNK_VERSION_MIN..=CHUNK_VERSION).contains(&version) {
        return Err(bad(
            "version",
            2,
            format!(
                "chunk version {version} (this build reads {CHUNK_VERSION_MIN} to {CHUNK_VERSION})"
            ),
        ));
    }
    let quant = match bytes[3] {
        0 => "f32",
        1 => "f16",
        2 => "log16",
        q => return Err(bad("quant", 3, format!("unknown quantizer {q}"))),
    };
    let filter = Filter::from_u8(bytes[4])
        .ok_or_else(|| bad("filter", 4, format!("unknown filter {}", bytes[4])))?;
    let shuffle = match bytes[5] {
        1 => Shuffle::Byte,
        2 => Shuffle::Bit,
        m => return Err(bad("shuffle", 5, format!("unknown shuffle mode {m}"))),
    };
    let len =
        usize::try_from(le_u64(bytes, 8)).map_err(|_| bad("len", 8, "value count too large"))?;
    let layout = Layout {
        channels: le_u32(bytes, 16) as usize,
        inner: le_u32(bytes, 20) as usize,
        next: le_u32(bytes, 24) as usize,
    };
    if layout.channels == 0 || layout.inner == 0 || layout.next == 0 {
        return Err(bad("layout", 16, "zero channels, inner or next"));
    }
    let escapes = le_u32(bytes, 28) as usize;
    let log16 = if quant == "log16" {
        let p = Log16Params {
            lo: le_f64(bytes, 32),
            step: le_f64(bytes, 40),
            floor: le_f64(bytes, 48),
            grid: version >= 2,
        };
        if !p.valid() {
            return Err(bad("log16", 32, format!("invalid log16 parameters {p:?}")));
        }
        Some(p)
    } else {
        if escapes != 0 {
            return Err(bad("escapes", 28, "escapes in a non-log16 chunk"));
        }
        None
    };
    if escapes > len {
        return Err(bad(
            "escapes",
            28,
            format!("{escapes} escapes for {len} values"),
        ));
    }
    Ok(ChunkInfo {
        version,
        quant,
        filter,
        shuffle,
        len,
        layout,
        escapes,
        log16,
    })
}

/// Decodes a chunk that must hold exactly `expected` values.
///
/// Memory follows what the data actually decompress to: the output is allocated only after the
/// payload has decompressed to exactly the size the header implies, so a small hostile chunk
/// cannot make the decoder allocate more than zstd's maximum expansion of its bytes.
pub fn decode(bytes: &[u8], expected: usize) -> Result<Vec<f32>> {
    let info = chunk_info(bytes)?;
    if info.len != expected {
        return Err(bad(
            "len",
            8,
            format!("chunk holds {} values, expected {expected}", info.len),
        ));
    }
    let raw = payload(bytes, &info)?;
    let mut out = vec![0.0f32; expected];
    finish(&info, &raw, &mut out)?;
    Ok(out)
}

/// Decodes a chunk into `out`, which must have exactly the chunk's length.
pub fn decode_into(bytes: &[u8], out: &mut [f32]) -> Result<()> {
    let info = chunk_info(bytes)?;
    if info.len != out.len() {
        return Err(bad(
            "len",
            8,
            format!("chunk holds {} values, expected {}", info.len, out.len()),
        ));
    }
    let raw = payload(bytes, &info)?;
    finish(&info, &raw, out)
}

/// Decompresses the payload, checking it has exactly the size the header implies. Up to 16 MiB
/// decompress in one call into a buffer of that size; beyond, the buffer grows with the actual
/// output.
fn payload(bytes: &[u8], info: &ChunkInfo) -> Result<Vec<u8>> {
    let n = info.len;
    let wbytes = if info.quant == "f32" { 4 } else { 2 };
    let words_len = match info.shuffle {
        Shuffle::Byte => n.checked_mul(wbytes),
        Shuffle::Bit => n.div_ceil(8).checked_mul(wbytes * 8),
    }
    .ok_or_else(|| bad("len", 8, "size overflows"))?;
    let raw_len = Some(words_len)
        .and_then(|x| x.checked_add(info.escapes.checked_mul(8)?))
        .and_then(|x| x.checked_add(anchor_count(info).checked_mul(8)?))
        .ok_or_else(|| bad("len", 8, "size overflows"))?;
    let frame = &bytes[CHUNK_HEADER_LEN..];
    let zerr = |e: std::io::Error| bad("payload", CHUNK_HEADER_LEN as u64, format!("zstd: {e}"));
    let raw = if raw_len <= 16 << 20 {
        zstd_decompress(frame, raw_len).map_err(zerr)?
    } else {
        use std::io::Read;
        let mut raw = Vec::new();
        zstd::stream::read::Decoder::with_buffer(frame)
            .map_err(zerr)?
            .take(raw_len as u64 + 1)
            .read_to_end(&mut raw)
            .map_err(zerr)?;
        raw
    };
    if raw.len() != raw_len {
        return Err(bad(
            "payload",
            CHUNK_HEADER_LEN as u64,
            format!("decompressed {} bytes, expected {raw_len}", raw.len()),
        ));
    }
    Ok(raw)
}

/// Number of per-channel grid origins a chunk's payload ends with (log16 from version 3).
fn anchor_count(info: &ChunkInfo) -> usize {
    if info.quant == "log16" && info.version >= 3 {
        info.layout.channels
    } else {
        0
    }
}

/// Undoes shuffle, prediction and quantization of a decompressed payload.
fn finish(info: &ChunkInfo, raw: &[u8], out: &mut [f32]) -> Result<()> {
    let n = info.len;
    let wbytes = if info.quant == "f32" { 4 } else { 2 };
    let words_len = n * wbytes
        + if info.shuffle == Shuffle::Bit {
            n.div_ceil(8) * 8 * wbytes - n * wbytes
        } else {
            0
        };
    match info.quant {
        "f32" => {
            let mut w = vec![0u32; n];
            unpack(&raw[..words_len], info.shuffle, &mut w);
            filter::inverse(&mut w, info.layout, info.filter);
            for (o, w) in out.iter_mut().zip(&w) {
                *o = f32::from_bits(*w);
            }
        }
        q => {
            let mut w = vec![0u16; n];
            unpack(&raw[..words_len], info.shuffle, &mut w);
            if q == "f16" {
                filter::inverse(&mut w, info.layout, info.filter);
                quantize::from_f16(&w, out);
            } else {
                let p = info.log16.expect("log16 params validated");
                let e = info.escapes;
                let idx = &raw[words_len..words_len + 4 * e];
                let val = &raw[words_len + 4 * e..words_len + 8 * e];
                let anchors: Vec<f64> = raw[words_len + 8 * e..]
                    .chunks_exact(8)
                    .map(|b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
                    .collect();
                if let Some(a) = anchors
                    .iter()
                    .find(|a| !(a.is_finite() && a.abs() <= p.step))
                {
                    return Err(bad(
                        "anchors",
                        CHUNK_HEADER_LEN as u64,
                        format!("log16 grid origin {a} is not within one step of 0"),
                    ));
                }
                let mut esc = Vec::with_capacity(e);
                let mut pos = 0u64;
                for k in 0..e {
                    let d = le_u32(idx, 4 * k) as u64;
                    pos = if k == 0 { d } else { pos + d };
                    let v = f32::from_bits(le_u32(val, 4 * k));
                    if (k > 0 && d == 0) || pos >= n as u64 || !v.is_finite() {
                        return Err(bad(
                            "escapes",
                            CHUNK_HEADER_LEN as u64,
                            format!(
                                "escape {k} at index {pos} is out of order or range, or not finite"
                            ),
                        ));
                    }
                    esc.push((pos as u32, v));
                }
                log16::decode(&w, &p, info.layout, info.filter, &esc, &anchors, out);
            }
        }
    }
    Ok(())
}

fn unpack<W: Word>(bytes: &[u8], shuffle: Shuffle, out: &mut [W]) {
    match shuffle {
        Shuffle::Byte => filter::unshuffle(bytes, out),
        Shuffle::Bit => filter::unbitshuffle(bytes, out),
    }
}
