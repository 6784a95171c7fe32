//! An open brdftab file ([`Store`]): the file mapped or read, its superblock and table of
//! contents checked, and a table's header and chunk index read on request.

use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use rayon::prelude::*;

use super::format::{self, Superblock, Toc};
use super::{ChunkCache, StoreOptions, StoredTable, TableHeader, TocEntry, no_table};
use crate::error::{Error, Result, Section};

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

impl Store {
    /// Opens a file with default options.
    pub fn open(path: impl AsRef<Path>) -> Result<Store> {
        Self::open_with(path, StoreOptions::default())
    }

    /// Opens a file and checks the superblock and table of contents. On Unix the file stays
    /// open and is read where its records and chunks lie when they are needed
    /// ([`Store::open_reading`]); on Windows it is read into memory
    /// ([`Store::open_in_memory`]), so that no handle or mapping of it stays open: Windows
    /// refuses to replace an open file, and a database held open by any reader could otherwise
    /// not be added to, replaced in or removed from (the writers rename a new file over it).
    pub fn open_with(path: impl AsRef<Path>, opts: StoreOptions) -> Result<Store> {
        #[cfg(windows)]
        return Self::open_in_memory(path, opts);
        #[cfg(not(windows))]
        Self::open_reading(path, opts)
    }

    /// Opens a file that stays open and is read at offsets (`pread`) as its table headers,
    /// indices and chunks are needed (what [`Store::open_with`] does on Unix): a reader keeps
    /// the version it opened when a writer renames a new file over it, and a file another
    /// program truncates or rewrites in place while it is open (`cp new.btdb db.btdb`) gives
    /// the chunks read after that an error (cut short, or a checksum mismatch), where a memory
    /// map of it ([`Store::open_mapped`]) kills the process with SIGBUS at the first page past
    /// the new end. Each chunk's compressed bytes are copied once, when it is decoded.
    pub fn open_reading(path: impl AsRef<Path>, opts: StoreOptions) -> Result<Store> {
        let (path, name, f, len) = Self::open_file(path.as_ref())?;
        Self::from_backing(path, name, Backing::File { file: f, len }, opts)
    }

    /// Opens a file through a read-only memory map: pages are read as lookups touch them, and a
    /// reader keeps the version it opened when a writer renames a new file over it. Another
    /// program truncating the file while it is mapped makes the next read of a page past the
    /// new end a SIGBUS, which kills the process ([`Store::open_reading`], the default on Unix,
    /// gives an error instead). On Windows the map keeps the file from being replaced or
    /// removed until the store and every table opened from it are dropped.
    pub fn open_mapped(path: impl AsRef<Path>, opts: StoreOptions) -> Result<Store> {
        let (path, name, f, _) = Self::open_file(path.as_ref())?;
        // SAFETY: brdftab never modifies a file in place (writers rename a new file over it), so
        // the mapped bytes do not change under us. A foreign process truncating the file could
        // still fault; that is the usual caveat of memory maps, and why this is not the default.
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
        let head = map.read(&name, 0, map.len().min(format::SUPERBLOCK_LEN as u64))?;
        let sb = Superblock::parse_head(&name, &head, map.len())?;
        let toc_bytes = map.block(&name, &sb.toc, &Section::Toc, format::MAX_JSON_LEN)?;
        let toc: Toc = format::json(&name, "table of contents", &toc_bytes)?;
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
        self.map.len()
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
        let hb = self.map.block(
            &self.name,
            &e.header,
            &Section::Header {
                table: e.name.clone(),
            },
            format::MAX_JSON_LEN,
        )?;
        let header: TableHeader = format::json(&self.name, &what("header"), &hb)?;
        if header.name != e.name {
            return Err(Error::format(
                &self.name,
                Some(&what("header")),
                Some(e.header.offset),
                format!("header names the table `{}`", header.name),
            ));
        }
        let ib = self.map.block(
            &self.name,
            &e.index,
            &Section::Index {
                table: e.name.clone(),
            },
            self.map.len(),
        )?;
        let index = format::check_table(&self.name, self.map.len(), &header, &ib, e.chunks)?;
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

/// The bytes of an open file: the file itself read at offsets, a read-only memory map, or
/// bytes in memory.
pub enum Backing {
    /// An open file, read at offsets as its parts are needed ([`Store::open_reading`]); `len`
    /// is its length when it was opened.
    File {
        /// The file.
        file: std::fs::File,
        /// Its length in bytes when opened.
        len: u64,
    },
    /// A memory-mapped file.
    Map(memmap2::Mmap),
    /// Bytes in memory, owned by the store (a `Vec<u8>`) or by a host (a Python `bytes`).
    Bytes(Box<dyn AsRef<[u8]> + Send + Sync>),
}

impl Backing {
    /// The length of the file (as opened) or of the bytes.
    pub fn len(&self) -> u64 {
        match self {
            Backing::File { len, .. } => *len,
            Backing::Map(m) => m.len() as u64,
            Backing::Bytes(b) => (**b).as_ref().len() as u64,
        }
    }

    /// True for an empty file.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The `len` bytes at `offset` (within [`Backing::len`]: the caller has checked the range);
    /// `file` names the file in errors. A file cut short since it was opened (another program
    /// truncated or rewrote it in place) is an [`Error::Format`] saying so.
    pub fn read(&self, file: &str, offset: u64, len: u64) -> Result<Cow<'_, [u8]>> {
        let range = || offset as usize..(offset + len) as usize;
        match self {
            Backing::Map(m) => Ok(Cow::Borrowed(&m[range()])),
            Backing::Bytes(b) => Ok(Cow::Borrowed(&(**b).as_ref()[range()])),
            Backing::File { file: f, .. } => {
                let mut buf = vec![0u8; len as usize];
                read_exact_at(f, &mut buf, offset).map_err(|e| {
                    if e.kind() == std::io::ErrorKind::UnexpectedEof {
                        Error::format(
                            file,
                            None,
                            Some(offset),
                            format!(
                                "the file ends before byte {}: it was cut short after it was \
                                 opened (rewritten in place by another program?)",
                                offset + len
                            ),
                        )
                    } else {
                        Error::io(Path::new(file), e)
                    }
                })?;
                Ok(Cow::Owned(buf))
            }
        }
    }

    /// The bytes of `block`, checked: inside the file after the superblock, at most `max`
    /// bytes, and matching its checksum.
    pub(crate) fn block(
        &self,
        file: &str,
        block: &format::Block,
        what: &Section,
        max: u64,
    ) -> Result<Cow<'_, [u8]>> {
        format::check_range(file, self.len(), block, what, max)?;
        let b = self.read(file, block.offset, block.len)?;
        format::check_sum(file, &b, block, what)?;
        Ok(b)
    }
}

/// Fills `buf` from `file` at `offset` (`pread`), whatever the file's cursor.
#[cfg(unix)]
fn read_exact_at(file: &std::fs::File, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
}

/// Fills `buf` from `file` at `offset` (`ReadFile` at an offset).
#[cfg(windows)]
fn read_exact_at(file: &std::fs::File, mut buf: &mut [u8], mut offset: u64) -> std::io::Result<()> {
    use std::os::windows::fs::FileExt;
    while !buf.is_empty() {
        match file.seek_read(buf, offset) {
            Ok(0) => return Err(std::io::ErrorKind::UnexpectedEof.into()),
            Ok(n) => {
                buf = &mut buf[n..];
                offset += n as u64;
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(())
}
