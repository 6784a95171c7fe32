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

pub use filter::{Filter, Layout};
pub use log16::Log16Params;

mod decode;
mod encode;
mod frame;
#[cfg(test)]
mod tests;

pub use decode::{chunk_info, decode, decode_into};
pub use encode::encode;
pub(crate) use frame::zstd_compress;

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

/// How residual words are split before zstd (stored in the chunk header).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Shuffle {
    /// Byte planes.
    Byte = 1,
    /// Bit planes (better when residuals are mostly 0 and ±1).
    Bit = 2,
}
