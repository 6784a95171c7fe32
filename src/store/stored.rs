//! One table of an open file ([`StoredTable`]): its chunks located, checked and decoded on
//! demand, one at a time or all in parallel.

use std::sync::Arc;

use rayon::prelude::*;

use super::format::{self, ChunkEntry};
use super::{Backing, ChunkCache, TableHeader};
use crate::codec;
use crate::error::{Error, Result, Section};

/// One stored table: its header, chunk index, and decoded chunks on demand.
#[derive(Clone)]
pub struct StoredTable {
    pub(super) file: String,
    pub(super) map: Arc<Backing>,
    pub(super) header: TableHeader,
    pub(super) index: Vec<ChunkEntry>,
    pub(super) starts: Vec<u64>,
    pub(super) cache: Arc<ChunkCache>,
    pub(super) id: usize,
}

impl std::fmt::Debug for StoredTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StoredTable")
            .field("file", &self.file)
            .field("name", &self.header.name)
            .field("chunks", &self.index.len())
            .finish()
    }
}

impl StoredTable {
    /// The file name (for messages).
    pub fn file(&self) -> &str {
        &self.file
    }

    /// The table's header.
    pub fn header(&self) -> &TableHeader {
        &self.header
    }

    /// Number of chunks.
    pub fn chunk_count(&self) -> usize {
        self.index.len()
    }

    /// Total compressed bytes of the chunks.
    pub fn compressed_bytes(&self) -> u64 {
        self.index.iter().map(|e| e.len).sum()
    }

    /// The checksummed bytes of chunk `i` as stored (encoded): borrowed from a map or bytes in
    /// memory, read from an open file.
    pub fn raw_chunk(&self, i: usize) -> Result<std::borrow::Cow<'_, [u8]>> {
        let e = self.index.get(i).ok_or_else(|| {
            Error::arg(
                "chunk",
                format!(
                    "chunk {i} of {} in table `{}`",
                    self.index.len(),
                    self.header.name
                ),
            )
        })?;
        let b = self.map.read(&self.file, e.offset, e.len)?;
        let computed = format::xxh3(&b);
        if computed != e.xxh3 {
            return Err(Error::Checksum {
                file: self.file.clone(),
                what: Section::Chunk {
                    table: self.header.name.clone(),
                    chunk: i,
                },
                stored: e.xxh3,
                computed,
            });
        }
        Ok(b)
    }

    /// Number of values in chunk `i`.
    pub fn chunk_values(&self, i: usize) -> usize {
        self.index.get(i).map_or(0, |e| e.values as usize)
    }

    /// The chunk holding flat value offset `flat`, and the offset inside it.
    pub fn locate(&self, flat: u64) -> Result<(usize, usize)> {
        let i = self
            .starts
            .partition_point(|&s| s <= flat)
            .saturating_sub(1);
        match self.index.get(i) {
            Some(e) if flat < self.starts[i] + e.values => {
                Ok((i, (flat - self.starts[i]) as usize))
            }
            _ => Err(Error::arg(
                "offset",
                format!(
                    "value {flat} is outside table `{}` ({} values)",
                    self.header.name, self.header.values
                ),
            )),
        }
    }

    /// Decodes chunk `i` (bypassing the cache).
    pub fn decode_chunk(&self, i: usize) -> Result<Vec<f32>> {
        let b = self.raw_chunk(i)?;
        codec::decode(&b, self.index[i].values as usize).map_err(|e| self.in_chunk(e, i))
    }

    fn in_chunk(&self, e: Error, i: usize) -> Error {
        match e {
            Error::Format {
                field, offset, msg, ..
            } => Error::Format {
                file: self.file.clone(),
                field: Some(format!(
                    "table `{}` chunk {i}{}",
                    self.header.name,
                    field.map(|f| format!(" {f}")).unwrap_or_default()
                )),
                offset: offset.map(|o| o + self.index[i].offset),
                msg,
            },
            e => e,
        }
    }

    /// Chunk `i`, decoded on first touch and kept in the cache.
    pub fn chunk(&self, i: usize) -> Result<Arc<[f32]>> {
        if let Some(c) = self.cache.get(self.id, i) {
            return Ok(c);
        }
        let v: Arc<[f32]> = self.decode_chunk(i)?.into();
        self.cache.put(self.id, i, v.clone());
        Ok(v)
    }

    /// Decodes the whole table (chunks in parallel, a few at a time), outermost axis first. The
    /// vector has room for [`Packed::PAD`](crate::table::kernel::Packed::PAD) values more, so
    /// that a table's one-array kernel keeps it without a copy.
    ///
    /// The table's size is the file's word until its chunks decode: it is reserved fallibly (a
    /// size beyond memory is an error, not an abort) and filled as chunks decode, so a file that
    /// claims more than its chunks hold fails at its first chunk, having touched little of it.
    pub fn read_all(&self) -> Result<Vec<f32>> {
        let total: usize = self.index.iter().map(|e| e.values as usize).sum();
        let mut out = Vec::new();
        if out
            .try_reserve_exact(total + crate::table::kernel::Packed::PAD)
            .is_err()
        {
            return Err(Error::format(
                &self.file,
                Some(&format!("table `{}` values", self.header.name)),
                None,
                format!(
                    "{total} values ({:.1} GB of f32) do not fit in memory",
                    total as f64 * 4e-9
                ),
            ));
        }
        // Chunks decoded at a time: enough for the pool, but at most a 32nd of the table (each
        // held twice while it decodes, the payload and the values) on a machine of many cores.
        let window = (2 * crate::par::threads())
            .min(self.index.len() / 32)
            .max(1);
        for first in (0..self.index.len()).step_by(window) {
            let last = (first + window).min(self.index.len());
            let decoded: Vec<Vec<f32>> = crate::par::install(|| {
                (first..last)
                    .into_par_iter()
                    .map(|i| self.decode_chunk(i))
                    .collect::<Result<_>>()
            })?;
            for v in decoded {
                out.extend_from_slice(&v);
            }
        }
        Ok(out)
    }

    /// Checks every chunk's checksum and decodes it (in parallel).
    pub fn verify(&self) -> Result<()> {
        crate::par::install(|| {
            (0..self.index.len())
                .into_par_iter()
                .try_for_each(|i| self.decode_chunk(i).map(drop))
        })
    }

    /// A loader of this table's chunks, for `TabulatedBrdf`.
    pub fn loader(&self) -> Arc<StoredTable> {
        Arc::new(self.clone())
    }
}
