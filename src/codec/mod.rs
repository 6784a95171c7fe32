//! Compression codecs: f32 arrays in, bytes out. Knows nothing about BRDFs.
//!
//! One chunk of values goes through a pipeline, each stage exactly invertible except the first:
//!
//! 1. **quantize** ([`quantize`]): f32 bits (lossless), f16, or log16 (error-bounded 16-bit log
//!    codes, with an exact escape list for negatives and anything the bound would miss);
//! 2. **predict** ([`filter`]): integer residuals against the previous point along the innermost
//!    angular axis, the linear extrapolation from the two previous points, or a planar predictor
//!    over the two innermost axes, optionally minus the previous channel's residual;
//!    zigzag-mapped. The caller describes the array with a
//!    [`Layout`] (plain numbers: channels, inner, next). The encoder picks a filter per chunk
//!    ([`choose`]) unless one is forced, and records it in the chunk header;
//! 3. **shuffle**: split words into byte planes (high bytes of small residuals are all zero);
//! 4. **zstd** at a configurable level, multithreaded for large chunks.
//!
//! A chunk is self-describing (see [`CHUNK_HEADER_LEN`] for the layout), so the decoder needs only
//! the bytes and the number of values it expects — which is also what bounds every allocation
//! when the bytes come from a damaged or hostile file.
//!
//! ```
//! use brdftab::codec::{self, Codec, Layout, Quant};
//! let data: Vec<f32> = (0..3000).map(|i| (i as f32 * 0.01).sin().abs()).collect();
//! let codec = Codec { quant: Quant::Log16 { tolerance: 1e-3, floor: None }, ..Codec::default() };
//! let bytes = codec::encode(&data, Layout::new(3, 100, 10), &codec)?;
//! let back = codec::decode(&bytes, data.len())?;
//! for (a, b) in data.iter().zip(&back) {
//!     assert!((a - b).abs() <= 1e-3 * a.max(bytes_floor(&bytes)));
//! }
//! # fn bytes_floor(b: &[u8]) -> f32 { codec::chunk_info(b).unwrap().log16.unwrap().floor as f32 }
//! # Ok::<(), brdftab::Error>(())
//! ```

pub mod choose;
pub mod filter;
pub mod log16;
pub mod quantize;

use serde::{Deserialize, Serialize};

use filter::Word;
pub use filter::{Filter, Layout};
pub use log16::Log16Params;

use crate::error::{Error, Result};

/// How values are quantized.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "quant", rename_all = "snake_case")]
pub enum Quant {
    /// Lossless 32-bit floats.
    F32,
    /// IEEE half precision (relative error ≤ 2^-11 for normal values; refuses |v| > 65504).
    F16,
    /// Error-bounded 16-bit log codes: every decoded value satisfies
    /// `|v̂ − v| ≤ tolerance · max(|v|, floor)`.
    Log16 {
        /// Relative tolerance (default 1e-3).
        tolerance: f64,
        /// Absolute floor; `None` chooses per chunk the smallest floor for which the chunk's
        /// range fits 16 bits (stored in the chunk).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        floor: Option<f64>,
    },
}

impl Quant {
    /// Parses a codec name as given on the command line (`f32`, `f16`, `log16`).
    pub fn parse(name: &str, tolerance: Option<f64>, floor: Option<f64>) -> Result<Quant> {
        match name {
            "f32" => Ok(Quant::F32),
            "f16" => Ok(Quant::F16),
            "log16" => {
                // Checked here, before any bake, as well as where a chunk is encoded: a bad
                // tolerance or floor used to surface only after the bake, as an encode error.
                let tolerance = tolerance.unwrap_or(1e-3);
                if !(tolerance.is_finite() && (log16::MIN_TOL..=0.5).contains(&tolerance)) {
                    return Err(Error::arg(
                        "codec_tolerance",
                        format!(
                            "log16 tolerance {tolerance} is outside [{}, 0.5]; use codec f32 \
                             for lossless storage",
                            log16::MIN_TOL
                        ),
                    ));
                }
                if let Some(f) = floor
                    && !(f.is_finite() && f > 0.0)
                {
                    return Err(Error::arg(
                        "floor",
                        format!("log16 floor {f} must be a positive number"),
                    ));
                }
                Ok(Quant::Log16 { tolerance, floor })
            }
            _ => Err(Error::arg(
                "codec",
                format!("unknown codec `{name}` (expected f32, f16 or log16)"),
            )),
        }
    }

    /// The zstd level tools use when none is given: 3 for `f32` and `f16`, whose encoding is
    /// little more than the filter and zstd, so zstd's speed is the writer's speed; 6 for
    /// `log16`, whose quantization already costs more than zstd at level 3 and whose table is
    /// written once and read many times (on the default Cook-Torrance table: 24.0× at level 3,
    /// 25.4× at 6, for ~15 % more encoding time; decoding speed does not depend on the level).
    pub fn default_level(&self) -> i32 {
        match self {
            Quant::Log16 { .. } => 6,
            _ => 3,
        }
    }

    /// The short name (`f32`, `f16`, `log16`).
    pub fn name(&self) -> &'static str {
        match self {
            Quant::F32 => "f32",
            Quant::F16 => "f16",
            Quant::Log16 { .. } => "log16",
        }
    }

    fn id(&self) -> u8 {
        match self {
            Quant::F32 => 0,
            Quant::F16 => 1,
            Quant::Log16 { .. } => 2,
        }
    }
}

/// Everything the encoder needs besides the data and its layout.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Codec {
    /// Quantization (and with it the accuracy).
    #[serde(flatten)]
    pub quant: Quant,
    /// zstd level (1..=22; 3 is zstd's default; negative levels are faster).
    pub level: i32,
    /// Force one filter; `None` picks the cheapest per chunk.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub filter: Option<Filter>,
    /// Try every filter through zstd and keep the smallest (slower; `false` uses a cheap
    /// estimate).
    #[serde(default)]
    pub exhaustive: bool,
    /// Force byte or bit planes; `None`: byte planes (both tried with `exhaustive`). Bit planes
    /// gained ~2% on f16 tables with the first-order filters; with the second-order ones they
    /// are 5% (f16) and 9% (log16) larger on the codec bench table, and slower.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shuffle: Option<Shuffle>,
}

impl Default for Codec {
    fn default() -> Self {
        Codec {
            quant: Quant::F16,
            level: 3,
            filter: None,
            exhaustive: false,
            shuffle: None,
        }
    }
}

/// Chunk magic (2 bytes), then version.
pub const CHUNK_MAGIC: [u8; 2] = *b"BC";
/// Chunk format version written. Version 3 gives each channel of a log16 chunk its own grid
/// origin, through the channel's most common value, so constant and recurring values decode
/// exactly (the origins follow the escapes in the payload); version 2 forms log16
/// reconstructions on an integer grid from 0 (see [`log16`]); version 1 chunks (f64
/// reconstructions) are still read. f32 and f16 chunks mean the same in all three.
pub const CHUNK_VERSION: u8 = 3;
/// Oldest chunk format version read.
pub const CHUNK_VERSION_MIN: u8 = 1;
/// Length of the fixed chunk header. Layout (little-endian):
///
/// ```text
///  0  [u8;2] "BC"         8  u64 n values        28 u32 escapes      56  zstd frame of:
///  2  u8  version (1..3) 16 u32 channels        32 f64 lo             byte-shuffled residuals
///  3  u8  quant 0/1/2     20 u32 inner           40 f64 step           (n words), then escape
///  4  u8  filter 0..7     24 u32 next            48 f64 floor          indices (u32 deltas)
///  5  u8  shuffle 1/2                            (log16 only, else 0)  and values (f32), then
///  6  u16 reserved (0)                                                 (log16, version ≥ 3)
///                                                                      one f64 grid origin
///                                                                      per channel
/// ```
pub const CHUNK_HEADER_LEN: usize = 56;

/// Chunks above this many raw bytes are compressed with zstd's worker threads.
const MT_THRESHOLD: usize = 8 << 20;

/// zstd calls on up to this many bytes, at levels up to [`REUSE_MAX_LEVEL`], use a context kept
/// per thread: creating and sizing a context costs about a tenth of compressing a 50 kB chunk,
/// and the encoder makes three calls per chunk. Larger or slower calls take a fresh context, so
/// that no thread keeps a large one.
const REUSE_MAX: usize = 1 << 20;
/// See [`REUSE_MAX`].
const REUSE_MAX_LEVEL: i32 = 9;

thread_local! {
    static CCTX: std::cell::RefCell<Option<zstd::bulk::Compressor<'static>>> =
        const { std::cell::RefCell::new(None) };
    static DCTX: std::cell::RefCell<Option<zstd::bulk::Decompressor<'static>>> =
        const { std::cell::RefCell::new(None) };
}

/// One zstd frame of `bytes` at `level` (single-threaded; see [`REUSE_MAX`]).
pub(crate) fn zstd_compress(bytes: &[u8], level: i32) -> std::io::Result<Vec<u8>> {
    if bytes.len() > REUSE_MAX || level > REUSE_MAX_LEVEL {
        return zstd::bulk::compress(bytes, level);
    }
    CCTX.with(|c| {
        let mut c = c.borrow_mut();
        let z = match &mut *c {
            Some(z) => z,
            None => c.insert(zstd::bulk::Compressor::new(level)?),
        };
        z.set_compression_level(level)?;
        z.compress(bytes)
    })
}

/// Decompresses one zstd frame of at most `capacity` bytes (see [`REUSE_MAX`]).
fn zstd_decompress(frame: &[u8], capacity: usize) -> std::io::Result<Vec<u8>> {
    DCTX.with(|d| {
        let mut d = d.borrow_mut();
        let z = match &mut *d {
            Some(z) => z,
            None => d.insert(zstd::bulk::Decompressor::new()?),
        };
        z.decompress(frame, capacity)
    })
}

/// What a chunk header says.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChunkInfo {
    /// Chunk format version.
    pub version: u8,
    /// Quantizer name (`f32`, `f16`, `log16`).
    pub quant: &'static str,
    /// The filter the encoder chose.
    pub filter: Filter,
    /// The shuffle the encoder chose.
    pub shuffle: Shuffle,
    /// Number of values.
    pub len: usize,
    /// The layout the filter used.
    pub layout: Layout,
    /// Number of exactly stored values (log16).
    pub escapes: usize,
    /// log16 parameters.
    pub log16: Option<Log16Params>,
}

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

/// How residual words are split before zstd (stored in the chunk header).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Shuffle {
    /// Byte planes.
    Byte = 1,
    /// Bit planes (better when residuals are mostly 0 and ±1).
    Bit = 2,
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

fn compress(bytes: &[u8], level: i32) -> Result<Vec<u8>> {
    let enc_err = |e: std::io::Error| Error::Encode {
        msg: format!("zstd: {e}"),
    };
    if bytes.len() < MT_THRESHOLD {
        return zstd_compress(bytes, level).map_err(enc_err);
    }
    let mut out = Vec::with_capacity(bytes.len() / 4);
    let mut enc = zstd::stream::Encoder::new(&mut out, level).map_err(enc_err)?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()) as u32;
    enc.multithread(threads).map_err(enc_err)?;
    enc.include_contentsize(true).map_err(enc_err)?;
    enc.set_pledged_src_size(Some(bytes.len() as u64))
        .map_err(enc_err)?;
    std::io::Write::write_all(&mut enc, bytes).map_err(enc_err)?;
    enc.finish().map_err(enc_err)?;
    Ok(out)
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn codec(quant: Quant) -> Codec {
        Codec {
            quant,
            level: 1,
            ..Codec::default()
        }
    }

    /// A log16 tolerance or floor out of range is an argument error when the codec is named,
    /// not an encode error after the bake (`codec="log16:0"` failed only once the table was
    /// baked).
    #[test]
    fn log16_settings_are_checked_when_parsed() {
        let named = |r: Result<Quant>| match r {
            Err(Error::InvalidArgument { name, .. }) => name,
            other => panic!("{other:?}"),
        };
        for t in [0.0, -1e-3, 0.6, f64::NAN, f64::INFINITY] {
            assert_eq!(
                named(Quant::parse("log16", Some(t), None)),
                "codec_tolerance"
            );
        }
        for f in [0.0, -1.0, f64::NAN] {
            assert_eq!(named(Quant::parse("log16", None, Some(f))), "floor");
        }
        assert!(Quant::parse("log16", Some(log16::MIN_TOL), Some(1e-9)).is_ok());
        assert!(Quant::parse("log16", Some(0.5), None).is_ok());
        let req = crate::request::BakeSettings {
            codec: Some("log16:0".into()),
            ..Default::default()
        };
        // A tolerance written into the codec is the codec field's error.
        assert!(matches!(
            req.request("x.json"),
            Err(Error::InvalidArgument { ref name, .. }) if name == "codec"
        ));
    }

    /// Adversarial values: tiny, huge, zeros, negatives, spikes, constants.
    fn adversarial() -> impl Strategy<Value = Vec<f32>> {
        let value = prop_oneof![
            Just(0.0f32),
            Just(-0.0f32),
            1e-38f32..1e-30,
            1e-8f32..1e-3,
            0.0f32..10.0,
            1e3f32..1e30,
            -1e3f32..0.0,
            Just(f32::MIN_POSITIVE),
            Just(f32::MAX),
            Just(1e-45f32),
        ];
        prop_oneof![
            proptest::collection::vec(value, 0..300),
            (
                any::<f32>().prop_filter("finite", |v| v.is_finite()),
                0usize..300
            )
                .prop_map(|(v, n)| vec![v; n]),
            (0usize..300, 0usize..300, 1e-3f32..1e6).prop_map(|(n, at, s)| {
                let mut v: Vec<f32> = (0..n)
                    .map(|i| 0.1 + (i as f32 * 0.05).sin().abs())
                    .collect();
                if at < n {
                    v[at] = s;
                }
                v
            }),
        ]
    }

    fn layouts() -> impl Strategy<Value = Layout> {
        (1usize..4, 1usize..20, 1usize..6).prop_map(|(c, i, n)| Layout::new(c, i, n))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        #[test]
        fn f32_round_trip_is_bit_exact(data in adversarial(), layout in layouts(),
                                       f in proptest::option::of(0u8..Filter::ALL.len() as u8)) {
            let c = Codec { filter: f.and_then(Filter::from_u8), ..codec(Quant::F32) };
            let b = encode(&data, layout, &c).unwrap();
            let back = decode(&b, data.len()).unwrap();
            prop_assert_eq!(
                back.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                data.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            );
        }

        #[test]
        fn f16_round_trip_within_one_step(data in adversarial(), layout in layouts()) {
            let data: Vec<f32> = data.into_iter().filter(|v| v.abs() <= 65504.0).collect();
            let b = encode(&data, layout, &codec(Quant::F16)).unwrap();
            let back = decode(&b, data.len()).unwrap();
            for (a, b) in data.iter().zip(&back) {
                // Half of an f16 ulp relative (2^-11) or the subnormal step 2^-24 / 2.
                let bound = (a.abs() * 2f32.powi(-11)).max(2f32.powi(-25));
                prop_assert!((a - b).abs() <= bound, "{} -> {}", a, b);
            }
        }

        #[test]
        fn log16_within_bound_for_every_value(data in adversarial(), layout in layouts(),
                                               tol in prop_oneof![Just(1e-3), 1e-4f64..0.1]) {
            let c = codec(Quant::Log16 { tolerance: tol, floor: None });
            let b = match encode(&data, layout, &c) {
                Ok(b) => b,
                Err(e) => { prop_assert!(e.to_string().contains("exactly"), "{}", e); return Ok(()); }
            };
            let info = chunk_info(&b).unwrap();
            let floor = info.log16.unwrap().floor;
            let back = decode(&b, data.len()).unwrap();
            for (a, b) in data.iter().zip(&back) {
                let (a, b) = (*a as f64, *b as f64);
                prop_assert!((a - b).abs() <= tol * a.abs().max(floor),
                             "{} -> {} (tol {}, floor {})", a, b, tol, floor);
            }
        }

        #[test]
        fn bit_shuffle_round_trips(data in adversarial(), layout in layouts()) {
            let data: Vec<f32> = data.into_iter().filter(|v| v.abs() <= 65504.0).collect();
            for q in [Quant::F32, Quant::F16] {
                let c = Codec { shuffle: Some(Shuffle::Bit), ..codec(q) };
                let b = encode(&data, layout, &c).unwrap();
                let back = decode(&b, data.len()).unwrap();
                let again = decode(&encode(&back, layout, &c).unwrap(), data.len()).unwrap();
                prop_assert_eq!(back, again);
            }
        }

        /// Valid chunks of every quantizer and filter with any header byte set to anything and
        /// payload bytes flipped: decoding returns an error or values, never panics.
        #[test]
        fn damaged_chunks_never_panic(data in adversarial(), layout in layouts(),
                                      q in 0usize..3, f in 0u8..Filter::ALL.len() as u8,
                                      edits in proptest::collection::vec(
                                          (any::<usize>(), any::<u8>()), 1..4)) {
            let quant = [Quant::F32, Quant::F16, Quant::Log16 { tolerance: 1e-2, floor: None }][q];
            let data: Vec<f32> = data.into_iter().filter(|v| v.abs() <= 65504.0).collect();
            let c = Codec { filter: Filter::from_u8(f), ..codec(quant) };
            let Ok(mut b) = encode(&data, layout, &c) else { return Ok(()) };
            for (at, v) in edits {
                let at = if at % 2 == 0 { at % CHUNK_HEADER_LEN } else { at % b.len() };
                b[at] = v;
            }
            let _ = decode(&b, data.len());
        }

        #[test]
        fn decode_never_panics_on_garbage(bytes in proptest::collection::vec(any::<u8>(), 0..200),
                                          n in 0usize..1000) {
            let _ = decode(&bytes, n);
        }
    }

    #[test]
    fn smooth_data_picks_a_predictor_and_compresses() {
        let (ch, inner, next) = (3, 180, 90);
        let data: Vec<f32> = (0..next * inner * ch)
            .map(|k| {
                let (j, i, c) = (k / (inner * ch), (k / ch) % inner, k % ch);
                (1.0 + c as f32) * (-((i as f32 - 90.0).powi(2) + (j as f32).powi(2)) / 800.0).exp()
            })
            .collect();
        let b = encode(&data, Layout::new(ch, inner, next), &Codec::default()).unwrap();
        let info = chunk_info(&b).unwrap();
        assert_ne!(info.filter, Filter::None);
        assert!(b.len() * 5 < data.len() * 4, "{} bytes", b.len());
    }

    #[test]
    fn chunk_versions_outside_the_readable_range_are_refused() {
        let mut b = encode(&[1.0, 2.0], Layout::FLAT, &Codec::default()).unwrap();
        assert_eq!(chunk_info(&b).unwrap().version, CHUNK_VERSION);
        for v in [0, CHUNK_VERSION + 1, 255] {
            b[2] = v;
            let e = decode(&b, 2).unwrap_err().to_string();
            assert!(e.contains("chunk version"), "{e}");
        }
        b[2] = CHUNK_VERSION_MIN;
        assert_eq!(decode(&b, 2).unwrap(), [1.0, 2.0]);
    }

    #[test]
    fn wrong_expected_length_is_refused_before_allocating() {
        let b = encode(&[1.0, 2.0], Layout::FLAT, &Codec::default()).unwrap();
        let e = decode(&b, usize::MAX / 8).unwrap_err().to_string();
        assert!(e.contains("expected"), "{e}");
    }
}
