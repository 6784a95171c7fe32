//! The encoder: a chunk's values quantized, filtered, shuffled and compressed behind its header.

use super::filter::Word;
use super::frame::compress;
use super::{
    CHUNK_HEADER_LEN, CHUNK_MAGIC, CHUNK_VERSION, Codec, Filter, Layout, Log16Params, Quant,
    Shuffle, choose, filter, log16, quantize,
};
use crate::error::Result;

/// Encodes `data` (laid out as `layout` describes) into one self-describing chunk.
pub fn encode(data: &[f32], layout: Layout, codec: &Codec) -> Result<Vec<u8>> {
    let mut escapes: Vec<(u32, f32)> = Vec::new();
    let mut params = None;
    let (filter, shuffle, body) = match codec.quant {
        Quant::F32 => {
            quantize::check_finite(data)?;
            let words: Vec<u32> = data.iter().map(|v| v.to_bits()).collect();
            filtered(&words, layout, codec)?
        }
        Quant::F16 => filtered(&quantize::to_f16(data)?, layout, codec)?,
        Quant::Log16 { tolerance, floor } => {
            let q = log16::encode(data, layout, tolerance, floor, codec.filter)?;
            params = Some(q.params);
            escapes = q.escapes;
            let mut tail = Vec::with_capacity(escapes.len() * 8 + q.anchors.len() * 8);
            let mut prev = 0u32;
            for &(i, _) in &escapes {
                tail.extend_from_slice(&(i - prev).to_le_bytes());
                prev = i;
            }
            for &(_, v) in &escapes {
                tail.extend_from_slice(&v.to_le_bytes());
            }
            debug_assert_eq!(q.anchors.len(), layout.channels.max(1));
            for a in &q.anchors {
                tail.extend_from_slice(&a.to_le_bytes());
            }
            let (sh, b) = pack(&q.codes, &tail, codec)?;
            (q.filter, sh, b)
        }
    };
    let mut out = Vec::with_capacity(CHUNK_HEADER_LEN + body.len());
    out.extend_from_slice(&CHUNK_MAGIC);
    out.push(CHUNK_VERSION);
    out.push(codec.quant.id());
    out.push(filter as u8);
    out.push(shuffle as u8);
    out.extend_from_slice(&0u16.to_le_bytes());
    out.extend_from_slice(&(data.len() as u64).to_le_bytes());
    for x in [layout.channels, layout.inner, layout.next] {
        out.extend_from_slice(&u32::try_from(x).unwrap_or(u32::MAX).to_le_bytes());
    }
    out.extend_from_slice(&(escapes.len() as u32).to_le_bytes());
    let p = params.unwrap_or(Log16Params {
        lo: 0.0,
        step: 0.0,
        floor: 0.0,
        grid: false,
    });
    for x in [p.lo, p.step, p.floor] {
        out.extend_from_slice(&x.to_le_bytes());
    }
    debug_assert_eq!(out.len(), CHUNK_HEADER_LEN);
    out.extend_from_slice(&body);
    Ok(out)
}

/// Shuffles words (byte or bit planes per `codec.shuffle`; unset: byte planes, or both with
/// `exhaustive`, keeping the smaller), appends `tail`, compresses.
fn pack<W: Word>(words: &[W], tail: &[u8], codec: &Codec) -> Result<(Shuffle, Vec<u8>)> {
    let modes: &[Shuffle] = match (codec.shuffle, codec.exhaustive) {
        (Some(Shuffle::Byte), _) | (None, false) => &[Shuffle::Byte],
        (Some(Shuffle::Bit), _) => &[Shuffle::Bit],
        (None, true) => &[Shuffle::Byte, Shuffle::Bit],
    };
    let mut best: Option<(Shuffle, Vec<u8>)> = None;
    for &m in modes {
        let mut b = Vec::with_capacity(words.len() * W::BYTES + tail.len());
        match m {
            Shuffle::Byte => filter::shuffle(words, &mut b),
            Shuffle::Bit => filter::bitshuffle(words, &mut b),
        }
        b.extend_from_slice(tail);
        let c = compress(&b, codec.level)?;
        if best.as_ref().is_none_or(|(_, x)| c.len() < x.len()) {
            best = Some((m, c));
        }
    }
    Ok(best.expect("at least one mode"))
}

/// Filters, shuffles and compresses words; returns the filter, shuffle and the zstd frame.
fn filtered<W: Word>(
    words: &[W],
    layout: Layout,
    codec: &Codec,
) -> Result<(Filter, Shuffle, Vec<u8>)> {
    if codec.exhaustive && codec.filter.is_none() {
        let mut best: Option<(Filter, Shuffle, Vec<u8>)> = None;
        for f in Filter::ALL {
            let (m, c) = pack(&filter::forward(words, layout, f), &[], codec)?;
            if best.as_ref().is_none_or(|(_, _, x)| c.len() < x.len()) {
                best = Some((f, m, c));
            }
        }
        return Ok(best.expect("at least one filter"));
    }
    let f = codec
        .filter
        .unwrap_or_else(|| choose::choose(words, layout));
    let (m, c) = pack(&filter::forward(words, layout, f), &[], codec)?;
    Ok((f, m, c))
}
