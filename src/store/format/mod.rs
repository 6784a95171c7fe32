//! The on-disk layout of a brdftab file (`.btdb`): one format for one table or a database of many.
//!
//! ```text
//! offset 0   superblock (64 bytes, little-endian)
//!            0  [u8; 8] magic  89 'B' 'T' 'D' 'B' 0D 0A 1A
//!            8  u32 format version (1)     12 u32 flags (0)
//!            16 u64 toc offset             24 u64 toc length        32 u64 toc xxh3-64
//!            40 u64 file length            48 u64 reserved (0)      56 u64 xxh3-64 of bytes 0..56
//! 64         per table, in order: its chunks (each a self-describing codec chunk, see
//!            `codec::CHUNK_HEADER_LEN`), then its header (JSON, [`TableHeader`]), then its chunk
//!            index (32 bytes per chunk: u64 offset, u64 compressed length, u64 value count,
//!            u64 xxh3-64 of the compressed bytes)
//! toc        JSON [`Toc`]: for every table its name and where its header and index are, with
//!            their lengths and xxh3-64 checksums
//! ```
//!
//! Every byte of the file is covered by a checksum: the superblock by its own, the table of
//! contents by the superblock's, headers and indexes by the TOC's, chunks by their index entries.
//! Opening reads and checks the superblock and TOC; a table's header and index are read and
//! checked when the table is first asked for; a chunk when it is first decoded.
//!
//! Sizes read from the file are validated before anything is allocated from them: every range
//! must lie inside the file, a chunk may not claim more values than zstd could physically expand
//! its bytes to, and a table may not exceed [`MAX_VALUES`].

use serde::{Deserialize, Serialize};

mod check;
mod superblock;

pub use check::{block, check_range, check_sum, check_table, json};
pub use superblock::Superblock;

use crate::codec::{Codec, Layout};
use crate::spectrum::Channels;

/// File magic.
pub const MAGIC: [u8; 8] = [0x89, b'B', b'T', b'D', b'B', 0x0D, 0x0A, 0x1A];
/// The format version this build writes and reads.
pub const VERSION: u32 = 1;
/// Superblock length.
pub const SUPERBLOCK_LEN: usize = 64;
/// Bytes per chunk index entry.
pub const INDEX_ENTRY_LEN: usize = 32;
/// The largest table (values, channels included) the reader accepts: 2^34 (64 GiB as f32).
pub const MAX_VALUES: u64 = 1 << 34;
/// The largest chunk (values) the reader accepts: 2^28 (1 GiB as f32).
pub const MAX_CHUNK_VALUES: u64 = 1 << 28;
/// zstd expands at most ~32768 bytes per compressed byte (RLE blocks); with 2-byte words at least
/// that bounds values per compressed byte. Used to refuse allocation bombs.
pub const MAX_VALUES_PER_BYTE: u64 = 1 << 15;
/// The largest JSON header or TOC the reader accepts.
pub const MAX_JSON_LEN: u64 = 64 << 20;

/// Where a table came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Source {
    /// An analytic model: its spec (JSON, as `ModelSpec` serializes it).
    Model {
        /// The model spec.
        spec: serde_json::Value,
    },
    /// A measured data file.
    Measured {
        /// The file name (no directories).
        file: String,
        /// SHA-256 of the file's bytes, hex.
        sha256: String,
    },
    /// Anything else (synthetic data, tests), described in words.
    Other {
        /// A description.
        description: String,
    },
}

/// The JSON header of one stored table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TableHeader {
    /// The table's name (unique within a file).
    pub name: String,
    /// Where the values came from.
    pub source: Source,
    /// The grid (axes and their mappings), as the table module serializes it.
    pub grid: serde_json::Value,
    /// The parameterization (e.g. `halfdiff`).
    pub parameterization: String,
    /// The symmetry reduction applied (e.g. `isotropic+reciprocal`).
    pub symmetry: String,
    /// The channels (RGB or wavelengths).
    pub channels: Channels,
    /// Units of the values (`1/sr`).
    pub units: String,
    /// The codec and its tolerance.
    pub codec: Codec,
    /// The tool that wrote the table (`brdftab 0.1.0`).
    pub tool: String,
    /// Stored dimensions, outermost first, channels last. Chunks are slabs of the outermost
    /// axis; the chunk index gives each chunk's length.
    pub shape: Vec<u64>,
    /// Total number of stored values (the product of `shape`, or fewer for packed layouts such
    /// as the reciprocal upper triangle of in/out tables).
    pub values: u64,
    /// The default layout the predictor used (each chunk header records its own).
    pub layout: Layout,
}

impl TableHeader {
    /// A header for a dense table of `shape` (angular axes outermost first, channels last) with
    /// the predictor layout taken from the shape; grid, parameterization and symmetry are left
    /// empty for the caller to fill in.
    pub fn new(
        name: impl Into<String>,
        source: Source,
        shape: Vec<u64>,
        channels: Channels,
        codec: Codec,
    ) -> TableHeader {
        let dim = |k: usize| shape.len().checked_sub(k).map_or(1, |i| shape[i] as usize);
        let values = shape
            .iter()
            .try_fold(1u64, |a, &d| a.checked_mul(d))
            .unwrap_or(u64::MAX);
        TableHeader {
            name: name.into(),
            source,
            grid: serde_json::Value::Null,
            parameterization: String::new(),
            symmetry: String::new(),
            channels,
            units: "1/sr".into(),
            codec,
            tool: concat!("brdftab ", env!("CARGO_PKG_VERSION")).into(),
            layout: Layout::new(dim(1), dim(2), dim(3)),
            shape,
            values,
        }
    }

    /// The product of `shape`, or `None` on overflow.
    pub fn dense_values(&self) -> Option<u64> {
        self.shape.iter().try_fold(1u64, |a, &d| a.checked_mul(d))
    }
}

/// A byte range with its checksum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Block {
    /// Offset from the start of the file.
    pub offset: u64,
    /// Length in bytes.
    pub len: u64,
    /// xxh3-64 of the bytes.
    pub xxh3: u64,
}

/// One table in the table of contents.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TocEntry {
    /// The table's name.
    pub name: String,
    /// Its JSON header.
    pub header: Block,
    /// Its chunk index.
    pub index: Block,
    /// Number of chunks.
    pub chunks: u64,
    /// Total compressed bytes of its chunks.
    pub bytes: u64,
}

/// The table of contents.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Toc {
    /// The tables, in file order.
    pub tables: Vec<TocEntry>,
}

/// One chunk index entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChunkEntry {
    /// Offset of the chunk's bytes.
    pub offset: u64,
    /// Compressed length.
    pub len: u64,
    /// Number of values.
    pub values: u64,
    /// xxh3-64 of the compressed bytes.
    pub xxh3: u64,
}

impl ChunkEntry {
    /// Serializes into 32 bytes.
    pub fn write(&self, out: &mut Vec<u8>) {
        for x in [self.offset, self.len, self.values, self.xxh3] {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }

    /// Reads one entry (`b` holds at least 32 bytes).
    pub fn read(b: &[u8]) -> ChunkEntry {
        let u = |k: usize| u64::from_le_bytes(b[8 * k..8 * k + 8].try_into().expect("8 bytes"));
        ChunkEntry {
            offset: u(0),
            len: u(1),
            values: u(2),
            xxh3: u(3),
        }
    }
}

/// xxh3-64.
pub fn xxh3(b: &[u8]) -> u64 {
    xxhash_rust::xxh3::xxh3_64(b)
}
