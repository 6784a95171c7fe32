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

mod chunk_cache;
pub mod db;
pub mod export;
pub mod format;
pub mod info;
pub mod name;
pub mod npy;
mod open;
mod stored;
pub mod tables;
mod writer;

use std::path::Path;

pub use crate::files::check_output;
pub use chunk_cache::ChunkCache;
pub use format::{Source, TableHeader, TocEntry};
pub use open::{Backing, Store};
pub use stored::StoredTable;
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

use crate::error::{Error, Result};

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

/// The error of a table `name` that the database `container` (its `tables`) does not hold: the
/// same words for every reader and for `db::remove`, with the names it holds.
pub(crate) fn no_table(container: &str, name: &str, tables: &[TocEntry]) -> Error {
    let names: Vec<&str> = tables.iter().map(|t| t.name.as_str()).collect();
    Error::NotFound(match names.is_empty() {
        true => format!("table `{name}` in {container} (it holds no table)"),
        false => format!("table `{name}` in {container} (has: {})", names.join(", ")),
    })
}
