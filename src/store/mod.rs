//! The brdftab file format and database of named tables.
//!
//! One format serves a single table and a database of many (suggested extension `.btdb`); see
//! [`format`](mod@format) for the byte layout. A table is stored as independently decodable, checksummed
//! chunks (slabs of its outermost axis, λ innermost), so a lookup decodes only the chunks it
//! touches and whole-table reads decode in parallel.
//!
//! - [`Store::open`] maps the file (on Windows: reads it into memory, [`Store::open_in_memory`])
//!   and checks its superblock and table of contents; nothing else is decoded. [`Store::table`]
//!   reads and checks one table's header and chunk index.
//! - [`StoredTable::chunk`] decodes a chunk on first touch into a thread-safe cache bounded in
//!   memory ([`StoreOptions::cache_bytes`]), or every chunk up front with [`StoreOptions::eager`].
//! - [`Writer`] streams chunks into a new file and replaces the destination atomically;
//!   [`db`] builds add / replace / remove / verify on it.
//! - [`tables`] connects the store to [`crate::table`]: headers from a `Grid`, saving a `Table`,
//!   streaming `bake_chunks` into a [`Writer`] (`chunk_with` + [`tables::chunk_layout`]), and
//!   [`tables::open_brdf`] (`FILE` or `DB#NAME`; [`tables::open_brdf_at`] takes the path and
//!   the name apart, for a writer reading back what it wrote) giving a `TabulatedBrdf` whose
//!   `ChunkLoader` is the [`StoredTable`] (chunks decoded, checksum checked, on first touch; the
//!   `TabulatedBrdf` keeps what it loaded, so the memory bound of [`StoreOptions::cache_bytes`]
//!   applies to [`StoredTable::chunk`] users such as the exports, not to a `TabulatedBrdf`).
//! - [`export`]: `.npy` of the dense table, EXR of 2D slices; [`npy`]: the `.npy` header the
//!   export writes and the reader that takes arrays back in (`brdftab import`).
//!
//! ```
//! use brdftab::codec::{Codec, Quant};
//! use brdftab::store::{Source, Store, TableHeader, db};
//! use brdftab::Channels;
//! let dir = std::env::temp_dir().join(format!("brdftab-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir).unwrap();
//! let path = dir.join("doc.btdb");
//! let data: Vec<f32> = (0..2 * 4 * 8 * 3).map(|i| i as f32 * 0.01).collect();
//! let codec = Codec { quant: Quant::F32, ..Codec::default() };
//! let header = TableHeader::new("ramp", Source::Other { description: "doc".into() },
//!                               vec![2, 4, 8, 3], Channels::Rgb, codec);
//! db::put(&path, header, false, |w| {
//!     for chunk in data.chunks(4 * 8 * 3) {
//!         w.chunk(chunk)?; // one slab of the outermost axis at a time
//!     }
//!     Ok(())
//! })?;
//! let store = Store::open(&path)?;
//! assert_eq!(store.table("ramp")?.read_all()?, data);
//! # std::fs::remove_dir_all(&dir).ok();
//! # Ok::<(), brdftab::Error>(())
//! ```
//!
//! Files are never modified in place — every write produces a new file and renames it — so a
//! reader that has a file open keeps seeing the version it opened (on Unix it maps the old
//! inode; on Windows, which refuses to replace a mapped file, it holds a copy in memory and
//! nothing of the file: a database any reader holds open can still be written).

pub mod db;
pub mod export;
pub mod format;
pub mod info;
pub mod name;
pub mod npy;
pub mod tables;
mod writer;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use rayon::prelude::*;

pub use crate::files::check_output;
use format::{ChunkEntry, Superblock, Toc};
pub use format::{Source, TableHeader, TocEntry};
pub use writer::Writer;

/// Writes `bytes` to `path` the way every output of the crate is written: into a temporary file
/// beside it, renamed over `path` once complete, so a reader (or a kill mid-write) never sees a
/// truncated file and another hard link to the old file keeps the old contents. A `path` that
/// is a symbolic link is written where it points. For hosts writing an image or any other
/// output of their own.
///
/// # Errors
/// [`Error::Io`] naming `path`; the temporary file is removed.
pub fn write_file_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    crate::files::write_atomic(path, bytes)
}

use crate::codec;
use crate::error::{Error, Result, Section};

/// Options for [`Store::open_with`].
#[derive(Debug, Clone, Copy)]
pub struct StoreOptions {
    /// Memory bound of the decoded-chunk cache, in bytes (default 512 MiB). The least recently
    /// used chunks are dropped beyond it (chunks still referenced by a caller stay alive).
    pub cache_bytes: usize,
    /// Decode every chunk of a table when it is opened (in parallel), instead of on first touch.
    pub eager: bool,
}

impl Default for StoreOptions {
    fn default() -> Self {
        StoreOptions {
            cache_bytes: 512 << 20,
            eager: false,
        }
    }
}

/// An open brdftab file (one table or a database).
pub struct Store {
    path: PathBuf,
    name: String,
    map: Arc<Backing>,
    toc: Toc,
    cache: Arc<ChunkCache>,
    opts: StoreOptions,
}

impl std::fmt::Debug for Store {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Store")
            .field("path", &self.path)
            .field("tables", &self.toc.tables.len())
            .finish()
    }
}

/// The error of a table `name` that the database `container` (its `tables`) does not hold: the
/// same words for every reader and for `db::remove`, with the names it holds.
pub(crate) fn no_table(container: &str, name: &str, tables: &[TocEntry]) -> Error {
    let names: Vec<&str> = tables.iter().map(|t| t.name.as_str()).collect();
    Error::NotFound(match names.is_empty() {
        true => format!("table `{name}` in {container} (it holds no table)"),
        false => format!("table `{name}` in {container} (has: {})", names.join(", ")),
    })
}

impl Store {
    /// Opens a file with default options.
    pub fn open(path: impl AsRef<Path>) -> Result<Store> {
        Self::open_with(path, StoreOptions::default())
    }

    /// Opens a file and checks the superblock and table of contents. On Unix the file is
    /// mapped ([`Store::open_mapped`]); on Windows it is read into memory
    /// ([`Store::open_in_memory`]), so that no handle or mapping of it stays open: Windows
    /// refuses to replace a mapped file, and a database held open by any reader could otherwise
    /// not be added to, replaced in or removed from (the writers rename a new file over it).
    pub fn open_with(path: impl AsRef<Path>, opts: StoreOptions) -> Result<Store> {
        #[cfg(windows)]
        return Self::open_in_memory(path, opts);
        #[cfg(not(windows))]
        Self::open_mapped(path, opts)
    }

    /// Opens a file through a read-only memory map (what [`Store::open_with`] does on Unix):
    /// pages are read as lookups touch them, and a reader keeps the version it opened when a
    /// writer renames a new file over it. On Windows the map keeps the file from being replaced
    /// or removed until the store and every table opened from it are dropped.
    pub fn open_mapped(path: impl AsRef<Path>, opts: StoreOptions) -> Result<Store> {
        let (path, name, f, _) = Self::open_file(path.as_ref())?;
        // SAFETY: brdftab never modifies a file in place (writers rename a new file over it), so
        // the mapped bytes do not change under us. A foreign process truncating the file could
        // still fault; that is the usual caveat of memory maps.
        let map = unsafe { memmap2::Mmap::map(&f) }.map_err(|e| Error::io(&path, e))?;
        Self::from_backing(path, name, Backing::Map(map), opts)
    }

    /// Opens a file by reading all of it into memory and closing it (what [`Store::open_with`]
    /// does on Windows): the store holds no handle or mapping of the file, so writers may
    /// replace or remove it at once, the store keeping the version it read. A database of N
    /// bytes costs N bytes of memory per open store; tables' chunks are still decoded on first
    /// touch (or up front with [`StoreOptions::eager`]).
    ///
    /// # Errors
    /// [`Error::Io`] naming `path` when it cannot be read or its size does not fit in memory;
    /// the errors of [`Store::open_with`].
    pub fn open_in_memory(path: impl AsRef<Path>, opts: StoreOptions) -> Result<Store> {
        let (path, name, f, len) = Self::open_file(path.as_ref())?;
        let mut bytes = Vec::new();
        let reserved = usize::try_from(len)
            .ok()
            .and_then(|n| bytes.try_reserve_exact(n).ok());
        if reserved.is_none() {
            let e = std::io::Error::new(
                std::io::ErrorKind::OutOfMemory,
                format!("its {len} bytes do not fit in memory"),
            );
            return Err(Error::io(&path, e));
        }
        std::io::Read::read_to_end(&mut &f, &mut bytes).map_err(|e| Error::io(&path, e))?;
        drop(f); // closed before the store exists: nothing of the file stays open
        Self::from_backing(path, name, Backing::Bytes(Box::new(bytes)), opts)
    }

    /// The open file (a regular file, at least a superblock long), its path, its name for
    /// messages and its length.
    fn open_file(path: &Path) -> Result<(PathBuf, String, std::fs::File, u64)> {
        let path = path.to_path_buf();
        let name = path.display().to_string();
        crate::files::require_regular(&path)?; // before the open: a FIFO would block it
        let f = std::fs::File::open(&path).map_err(|e| Error::io(&path, e))?;
        let len = f.metadata().map_err(|e| Error::io(&path, e))?.len();
        if len < format::SUPERBLOCK_LEN as u64 {
            let mut head = Vec::new();
            std::io::Read::read_to_end(&mut &f, &mut head).map_err(|e| Error::io(&path, e))?;
            return Err(match Superblock::parse(&name, &head) {
                Err(e) => e,
                Ok(_) => Error::format(&name, Some("superblock"), None, "truncated"),
            });
        }
        Ok((path, name, f, len))
    }

    /// Opens a file held in memory (`name` is used in error messages): a `Vec<u8>`, or a buffer
    /// a host owns, read where it is (Python's `Database.add_bytes` hands over the `bytes`
    /// object itself, so a table as large as memory allows needs no second copy). Used by the
    /// fuzz target too.
    pub fn from_bytes(
        name: &str,
        bytes: impl AsRef<[u8]> + Send + Sync + 'static,
        opts: StoreOptions,
    ) -> Result<Store> {
        Self::from_backing(
            PathBuf::from(name),
            name.to_owned(),
            Backing::Bytes(Box::new(bytes)),
            opts,
        )
    }

    fn from_backing(
        path: PathBuf,
        name: String,
        map: Backing,
        opts: StoreOptions,
    ) -> Result<Store> {
        let sb = Superblock::parse(&name, &map)?;
        let toc_bytes = format::block(&name, &map, &sb.toc, &Section::Toc, format::MAX_JSON_LEN)?;
        let toc: Toc = format::json(&name, "table of contents", toc_bytes)?;
        let mut seen = std::collections::HashSet::new();
        for t in &toc.tables {
            if !seen.insert(t.name.as_str()) {
                return Err(Error::format(
                    &name,
                    Some("table of contents"),
                    None,
                    format!("duplicate table `{}`", t.name),
                ));
            }
        }
        Ok(Store {
            path,
            name,
            map: Arc::new(map),
            toc,
            cache: Arc::new(ChunkCache::new(opts.cache_bytes)),
            opts,
        })
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The size of the file in bytes.
    pub fn file_len(&self) -> u64 {
        self.map.len() as u64
    }

    /// The tables, in file order.
    pub fn tables(&self) -> &[TocEntry] {
        &self.toc.tables
    }

    /// Opens the table `name` (reads and checks its header and chunk index).
    pub fn table(&self, name: &str) -> Result<StoredTable> {
        let (i, e) = self
            .toc
            .tables
            .iter()
            .enumerate()
            .find(|(_, t)| t.name == name)
            .ok_or_else(|| no_table(&self.name, name, &self.toc.tables))?;
        self.table_at(i, e)
    }

    /// Opens the only table of a single-table file (error if there are several or none).
    pub fn single(&self) -> Result<StoredTable> {
        match self.toc.tables.as_slice() {
            [e] => self.table_at(0, e),
            [] => Err(Error::NotFound(format!(
                "{}: the file holds no table",
                self.name
            ))),
            ts => Err(Error::arg(
                "SOURCE",
                format!(
                    "{} is a database of {} tables; name one as {}#NAME",
                    self.name,
                    ts.len(),
                    self.name
                ),
            )),
        }
    }

    fn table_at(&self, i: usize, e: &TocEntry) -> Result<StoredTable> {
        let what = |s: &str| format!("table `{}` {s}", e.name);
        let hb = format::block(
            &self.name,
            &self.map,
            &e.header,
            &Section::Header {
                table: e.name.clone(),
            },
            format::MAX_JSON_LEN,
        )?;
        let header: TableHeader = format::json(&self.name, &what("header"), hb)?;
        if header.name != e.name {
            return Err(Error::format(
                &self.name,
                Some(&what("header")),
                Some(e.header.offset),
                format!("header names the table `{}`", header.name),
            ));
        }
        let ib = format::block(
            &self.name,
            &self.map,
            &e.index,
            &Section::Index {
                table: e.name.clone(),
            },
            self.map.len() as u64,
        )?;
        let index = format::check_table(&self.name, self.map.len() as u64, &header, ib, e.chunks)?;
        let starts = index
            .iter()
            .scan(0u64, |acc, e| {
                let s = *acc;
                *acc += e.values;
                Some(s)
            })
            .collect();
        let t = StoredTable {
            file: self.name.clone(),
            map: self.map.clone(),
            header,
            index,
            starts,
            cache: self.cache.clone(),
            id: i,
        };
        if self.opts.eager {
            crate::par::install(|| {
                (0..t.index.len())
                    .into_par_iter()
                    .try_for_each(|c| t.chunk(c).map(drop))
            })?;
        }
        Ok(t)
    }

    /// Checks every checksum and decodes every chunk of every table (in parallel). Returns the
    /// number of chunks checked.
    pub fn verify(&self) -> Result<usize> {
        let mut n = 0;
        for e in &self.toc.tables {
            let t = self.table(&e.name)?;
            t.verify()?;
            n += t.chunk_count();
        }
        Ok(n)
    }
}

/// The bytes of an open file: a read-only memory map, or bytes in memory.
pub enum Backing {
    /// A memory-mapped file.
    Map(memmap2::Mmap),
    /// Bytes in memory, owned by the store (a `Vec<u8>`) or by a host (a Python `bytes`).
    Bytes(Box<dyn AsRef<[u8]> + Send + Sync>),
}

impl std::ops::Deref for Backing {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        match self {
            Backing::Map(m) => m,
            Backing::Bytes(b) => (**b).as_ref(),
        }
    }
}

/// One stored table: its header, chunk index, and decoded chunks on demand.
#[derive(Clone)]
pub struct StoredTable {
    file: String,
    map: Arc<Backing>,
    header: TableHeader,
    index: Vec<ChunkEntry>,
    starts: Vec<u64>,
    cache: Arc<ChunkCache>,
    id: usize,
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

    /// The checksummed bytes of chunk `i` as stored (encoded).
    pub fn raw_chunk(&self, i: usize) -> Result<&[u8]> {
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
        let b = &self.map[e.offset as usize..(e.offset + e.len) as usize];
        let computed = format::xxh3(b);
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
        codec::decode(b, self.index[i].values as usize).map_err(|e| self.in_chunk(e, i))
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

/// A thread-safe cache of decoded chunks with a memory bound (least recently used out).
pub struct ChunkCache {
    budget: usize,
    inner: Mutex<CacheInner>,
}

/// A decoded chunk and its last use.
type Entry = (Arc<[f32]>, u64);

#[derive(Default)]
struct CacheInner {
    map: HashMap<(usize, usize), Entry>,
    bytes: usize,
    tick: u64,
}

impl ChunkCache {
    /// A cache holding at most `budget` bytes of decoded values.
    pub fn new(budget: usize) -> ChunkCache {
        ChunkCache {
            budget,
            inner: Mutex::new(CacheInner::default()),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, CacheInner> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn get(&self, t: usize, i: usize) -> Option<Arc<[f32]>> {
        let mut g = self.lock();
        g.tick += 1;
        let tick = g.tick;
        g.map.get_mut(&(t, i)).map(|(v, last)| {
            *last = tick;
            v.clone()
        })
    }

    fn put(&self, t: usize, i: usize, v: Arc<[f32]>) {
        let size = v.len() * 4;
        let mut g = self.lock();
        g.tick += 1;
        let tick = g.tick;
        if let Some((old, _)) = g.map.insert((t, i), (v, tick)) {
            g.bytes -= old.len() * 4;
        }
        g.bytes += size;
        while g.bytes > self.budget && g.map.len() > 1 {
            let oldest = g
                .map
                .iter()
                .filter(|(k, _)| **k != (t, i))
                .min_by_key(|(_, (_, last))| *last)
                .map(|(k, _)| *k);
            match oldest {
                Some(k) => {
                    let (old, _) = g.map.remove(&k).expect("present");
                    g.bytes -= old.len() * 4;
                }
                None => break,
            }
        }
    }

    /// Bytes of decoded values currently cached.
    pub fn bytes(&self) -> usize {
        self.lock().bytes
    }
}
