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

use crate::codec::{Codec, Layout};
use crate::error::{Error, Result, Section};
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

/// The decoded superblock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Superblock {
    /// Format version.
    pub version: u32,
    /// The TOC block.
    pub toc: Block,
    /// The file length the writer produced.
    pub file_len: u64,
}

impl Superblock {
    /// Serializes into [`SUPERBLOCK_LEN`] bytes.
    pub fn to_bytes(&self) -> [u8; SUPERBLOCK_LEN] {
        let mut b = [0u8; SUPERBLOCK_LEN];
        b[0..8].copy_from_slice(&MAGIC);
        b[8..12].copy_from_slice(&self.version.to_le_bytes());
        b[16..24].copy_from_slice(&self.toc.offset.to_le_bytes());
        b[24..32].copy_from_slice(&self.toc.len.to_le_bytes());
        b[32..40].copy_from_slice(&self.toc.xxh3.to_le_bytes());
        b[40..48].copy_from_slice(&self.file_len.to_le_bytes());
        let h = xxh3(&b[0..56]);
        b[56..64].copy_from_slice(&h.to_le_bytes());
        b
    }

    /// Parses and checks the superblock of a file of `data.len()` bytes.
    pub fn parse(file: &str, data: &[u8]) -> Result<Superblock> {
        if data.len() < 8 || data[0..8] != MAGIC {
            let what = if data.len() < 8 && MAGIC.starts_with(data) {
                "truncated before the end of the magic"
            } else {
                "not a brdftab file (wrong magic)"
            };
            return Err(Error::format(file, Some("magic"), Some(0), what));
        }
        if data.len() < SUPERBLOCK_LEN {
            return Err(Error::format(
                file,
                Some("superblock"),
                Some(data.len() as u64),
                format!(
                    "truncated: {} bytes, the superblock alone is {SUPERBLOCK_LEN}",
                    data.len()
                ),
            ));
        }
        let u64_at = |o: usize| u64::from_le_bytes(data[o..o + 8].try_into().expect("8 bytes"));
        let version = u32::from_le_bytes(data[8..12].try_into().expect("4 bytes"));
        let stored = u64_at(56);
        let computed = xxh3(&data[0..56]);
        if stored != computed {
            return Err(Error::Checksum {
                file: file.into(),
                what: Section::Superblock,
                stored,
                computed,
            });
        }
        if version > VERSION {
            return Err(Error::format(
                file,
                Some("version"),
                Some(8),
                format!(
                    "format version {version} is newer than this build reads ({VERSION}); upgrade brdftab"
                ),
            ));
        }
        if version == 0 {
            return Err(Error::format(
                file,
                Some("version"),
                Some(8),
                "format version 0",
            ));
        }
        let sb = Superblock {
            version,
            toc: Block {
                offset: u64_at(16),
                len: u64_at(24),
                xxh3: u64_at(32),
            },
            file_len: u64_at(40),
        };
        if sb.file_len != data.len() as u64 {
            return Err(Error::format(
                file,
                Some("file length"),
                Some(40),
                format!(
                    "the file is {} bytes but was written as {} (truncated or appended to)",
                    data.len(),
                    sb.file_len
                ),
            ));
        }
        Ok(sb)
    }
}

/// xxh3-64.
pub fn xxh3(b: &[u8]) -> u64 {
    xxhash_rust::xxh3::xxh3_64(b)
}

/// Returns the bytes of `block`, checking it lies inside `data` (after the superblock) and its
/// checksum matches.
pub fn block<'a>(
    file: &str,
    data: &'a [u8],
    block: &Block,
    what: &Section,
    max: u64,
) -> Result<&'a [u8]> {
    let end = block.offset.checked_add(block.len);
    match end {
        Some(end) if block.offset >= SUPERBLOCK_LEN as u64 && end <= data.len() as u64 => {}
        _ => {
            return Err(Error::format(
                file,
                Some(&what.to_string()),
                Some(block.offset),
                format!(
                    "range {}+{} lies outside the file ({} bytes)",
                    block.offset,
                    block.len,
                    data.len()
                ),
            ));
        }
    }
    if block.len > max {
        return Err(Error::format(
            file,
            Some(&what.to_string()),
            Some(block.offset),
            format!("{} bytes is more than the {max} allowed", block.len),
        ));
    }
    let b = &data[block.offset as usize..(block.offset + block.len) as usize];
    let computed = xxh3(b);
    if computed != block.xxh3 {
        return Err(Error::Checksum {
            file: file.into(),
            what: what.clone(),
            stored: block.xxh3,
            computed,
        });
    }
    Ok(b)
}

/// Parses JSON from a file block, naming the file and block on error.
pub fn json<T: serde::de::DeserializeOwned>(file: &str, what: &str, b: &[u8]) -> Result<T> {
    serde_json::from_slice(b).map_err(|e| Error::Json {
        context: format!("{file}: {what}"),
        source: e,
    })
}

/// Checks a table header and its chunk index against each other and the file; returns the index.
pub fn check_table(
    file: &str,
    data_len: u64,
    h: &TableHeader,
    index: &[u8],
    n: u64,
) -> Result<Vec<ChunkEntry>> {
    let what = |f: &str| format!("table `{}` {f}", h.name);
    let err = |f: &str, msg: String| Error::format(file, Some(&what(f)), None, msg);
    let dense = h.dense_values().unwrap_or(u64::MAX);
    // Packed layouts store at least half of the dense shape; chunks are slabs of axis 0.
    if h.shape.is_empty()
        || h.values > MAX_VALUES
        || h.values > dense
        || dense / 2 > h.values
        || h.shape[0] != n
    {
        return Err(err(
            "shape",
            format!(
                "{:?} / {} values: empty, inconsistent or more than {MAX_VALUES}",
                h.shape, h.values
            ),
        ));
    }
    if index.len() as u64 != n.saturating_mul(INDEX_ENTRY_LEN as u64) || n > h.values.max(1) {
        return Err(err(
            "index",
            format!(
                "{n} chunks in an index of {} bytes for {} values",
                index.len(),
                h.values
            ),
        ));
    }
    let mut out = Vec::with_capacity(n as usize);
    let mut sum = 0u64;
    for (i, b) in index.chunks_exact(INDEX_ENTRY_LEN).enumerate() {
        let e = ChunkEntry::read(b);
        let ok_range = e
            .offset
            .checked_add(e.len)
            .is_some_and(|end| e.offset >= SUPERBLOCK_LEN as u64 && end <= data_len);
        if !ok_range {
            return Err(err(
                &format!("chunk {i}"),
                format!(
                    "range {}+{} lies outside the file ({data_len} bytes)",
                    e.offset, e.len
                ),
            ));
        }
        if e.values > MAX_CHUNK_VALUES || e.values > e.len.saturating_mul(MAX_VALUES_PER_BYTE) {
            return Err(err(
                &format!("chunk {i}"),
                format!("claims {} values in {} bytes", e.values, e.len),
            ));
        }
        sum += e.values;
        out.push(e);
    }
    if sum != h.values {
        return Err(err(
            "index",
            format!("chunks hold {sum} values, the header says {}", h.values),
        ));
    }
    Ok(out)
}
