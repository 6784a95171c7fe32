//! Streaming, atomic writing of a brdftab file.
//!
//! A [`Writer`] writes into a temporary file next to the destination (same directory, so the
//! final rename stays on one file system). Chunks are accepted one at a time, so a table never
//! has to be in memory as a whole. [`Writer::finish`] writes the table of contents, patches the
//! superblock, fsyncs the file, renames it over the destination and fsyncs the directory: a
//! process killed at any moment leaves either the old file or the new one. Dropping an unfinished
//! writer deletes the temporary file.

use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::format::{
    self, Block, ChunkEntry, SUPERBLOCK_LEN, Superblock, TableHeader, Toc, TocEntry, VERSION,
};
use crate::codec;
use crate::error::{Error, Result};

/// Writes a new brdftab file (one table or many), atomically replacing `path` on
/// [`Writer::finish`].
pub struct Writer {
    path: PathBuf,
    tmp: PathBuf,
    out: Option<BufWriter<File>>,
    pos: u64,
    toc: Toc,
    table: Option<Open>,
}

struct Open {
    header: TableHeader,
    index: Vec<ChunkEntry>,
    bytes: u64,
}

impl Writer {
    /// Starts writing a file that will replace `path` when finished (where `path` is a symbolic
    /// link, the file it points to, followed link by link).
    pub fn create(path: impl AsRef<Path>) -> Result<Writer> {
        let path = crate::files::resolve_links(path.as_ref())?;
        let tmp = crate::files::temp_path(&path)?;
        let f = File::options()
            .write(true)
            .create_new(true)
            .open(&tmp)
            .map_err(|e| Error::io(&path, e))?;
        let mut w = Writer {
            path,
            tmp,
            out: Some(BufWriter::with_capacity(1 << 20, f)),
            pos: 0,
            toc: Toc::default(),
            table: None,
        };
        w.write(&[0u8; SUPERBLOCK_LEN])?; // patched in finish()
        Ok(w)
    }

    fn write(&mut self, b: &[u8]) -> Result<u64> {
        let at = self.pos;
        let out = self.out.as_mut().expect("writer is open");
        out.write_all(b).map_err(|e| Error::io(&self.path, e))?;
        self.pos += b.len() as u64;
        Ok(at)
    }

    fn block(&mut self, b: &[u8]) -> Result<Block> {
        let offset = self.write(b)?;
        Ok(Block {
            offset,
            len: b.len() as u64,
            xxh3: format::xxh3(b),
        })
    }

    /// Names of the tables written so far.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.toc.tables.iter().map(|t| t.name.as_str())
    }

    /// Starts a table. Its chunks follow with [`Writer::chunk`] (or [`Writer::encoded_chunk`]),
    /// then [`Writer::end_table`]. Its name must keep the table-name rule
    /// ([`super::name::check`]).
    pub fn begin_table(&mut self, header: TableHeader) -> Result<()> {
        super::name::check("name", &header.name)?;
        self.begin(header)
    }

    /// [`Writer::begin_table`] of a table copied from a database, whose name an earlier
    /// version may have stored with a `\` (kept, as [`super::name`] says).
    pub(crate) fn begin_kept_table(&mut self, header: TableHeader) -> Result<()> {
        super::name::check_stored("name", &header.name)?;
        self.begin(header)
    }

    fn begin(&mut self, header: TableHeader) -> Result<()> {
        if self.table.is_some() {
            return Err(Error::arg("table", "the previous table was not ended"));
        }
        if self.names().any(|n| n == header.name) {
            return Err(Error::Duplicate {
                container: self.path.display().to_string(),
                name: header.name,
            });
        }
        let dense = header.dense_values().unwrap_or(u64::MAX);
        if header.shape.is_empty() || header.values > dense || header.values > format::MAX_VALUES {
            return Err(Error::arg(
                "shape",
                format!(
                    "{:?} / {} values: empty, inconsistent or too large",
                    header.shape, header.values
                ),
            ));
        }
        self.table = Some(Open {
            header,
            index: Vec::new(),
            bytes: 0,
        });
        Ok(())
    }

    /// The header of the table being written.
    pub fn header(&self) -> Option<&TableHeader> {
        self.table.as_ref().map(|t| &t.header)
    }

    /// Encodes and appends the next chunk of the open table (with the header's layout).
    pub fn chunk(&mut self, values: &[f32]) -> Result<()> {
        let layout = self
            .header()
            .map(|h| h.layout)
            .unwrap_or(codec::Layout::FLAT);
        self.chunk_with(values, layout)
    }

    /// Encodes and appends the next chunk with its own predictor layout (e.g. packed tables whose
    /// chunks have different row counts).
    pub fn chunk_with(&mut self, values: &[f32], layout: codec::Layout) -> Result<()> {
        let t = self
            .table
            .as_ref()
            .ok_or_else(|| Error::arg("table", "no table begun"))?;
        let bytes = codec::encode(values, layout, &t.header.codec).map_err(|e| match e {
            Error::Encode { msg } => Error::Encode {
                msg: format!("table `{}` chunk {}: {msg}", t.header.name, t.index.len()),
            },
            e => e,
        })?;
        self.encoded_chunk(&bytes, values.len() as u64)
    }

    /// Appends an already encoded chunk (e.g. copied from another file) holding `values` values.
    pub fn encoded_chunk(&mut self, bytes: &[u8], values: u64) -> Result<()> {
        let t = self
            .table
            .as_ref()
            .ok_or_else(|| Error::arg("table", "no table begun"))?;
        let done: u64 = t.index.iter().map(|e| e.values).sum();
        if done + values > t.header.values || values > format::MAX_CHUNK_VALUES {
            return Err(Error::arg(
                "chunk",
                format!(
                    "table `{}` chunk {} of {values} values overflows the header's {} values (or the chunk limit)",
                    t.header.name,
                    t.index.len(),
                    t.header.values
                ),
            ));
        }
        let offset = self.write(bytes)?;
        let t = self.table.as_mut().expect("checked");
        t.bytes += bytes.len() as u64;
        t.index.push(ChunkEntry {
            offset,
            len: bytes.len() as u64,
            values,
            xxh3: format::xxh3(bytes),
        });
        Ok(())
    }

    /// Encodes chunks held in memory in parallel (each with its layout) and appends them in
    /// order.
    pub fn chunks_par(&mut self, chunks: &[(&[f32], codec::Layout)]) -> Result<()> {
        let t = self
            .table
            .as_ref()
            .ok_or_else(|| Error::arg("table", "no table begun"))?;
        let c = t.header.codec;
        let encoded: Vec<Result<Vec<u8>>> = crate::par::install(|| {
            chunks
                .par_iter()
                .map(|(v, l)| codec::encode(v, *l, &c))
                .collect()
        });
        for (e, (v, _)) in encoded.into_iter().zip(chunks) {
            self.encoded_chunk(&e?, v.len() as u64)?;
        }
        Ok(())
    }

    /// Ends the open table: writes its header and chunk index.
    pub fn end_table(&mut self) -> Result<()> {
        let t = self
            .table
            .take()
            .ok_or_else(|| Error::arg("table", "no table begun"))?;
        let got: u64 = t.index.iter().map(|e| e.values).sum();
        if got != t.header.values {
            return Err(Error::arg(
                "table",
                format!(
                    "table `{}` got {got} values in {} chunks, its header says {}",
                    t.header.name,
                    t.index.len(),
                    t.header.values
                ),
            ));
        }
        let json = serde_json::to_vec(&t.header).map_err(|e| Error::Json {
            context: "table header".into(),
            source: e,
        })?;
        let header = self.block(&json)?;
        let mut idx = Vec::with_capacity(t.index.len() * format::INDEX_ENTRY_LEN);
        for e in &t.index {
            e.write(&mut idx);
        }
        let index = self.block(&idx)?;
        self.toc.tables.push(TocEntry {
            name: t.header.name.clone(),
            header,
            index,
            chunks: t.index.len() as u64,
            bytes: t.bytes,
        });
        Ok(())
    }

    /// Writes the table of contents and the superblock, makes the file durable and renames it
    /// over the destination.
    pub fn finish(mut self) -> Result<()> {
        if self.table.is_some() {
            return Err(Error::arg("table", "the last table was not ended"));
        }
        let json = serde_json::to_vec(&self.toc).map_err(|e| Error::Json {
            context: "table of contents".into(),
            source: e,
        })?;
        let toc = self.block(&json)?;
        let sb = Superblock {
            version: VERSION,
            toc,
            file_len: self.pos,
        };
        let mut out = self.out.take().expect("writer is open");
        let io = |e| Error::io(&self.path, e);
        out.flush().map_err(io)?;
        let mut f = out.into_inner().map_err(|e| io(e.into_error()))?;
        f.seek(SeekFrom::Start(0)).map_err(io)?;
        f.write_all(&sb.to_bytes()).map_err(io)?;
        f.sync_all().map_err(io)?;
        drop(f);
        crate::files::rename_over(&self.tmp, &self.path).map_err(|e| Error::io(&self.path, e))?;
        sync_dir(&parent(&self.path))?;
        self.tmp = PathBuf::new(); // nothing to clean up
        Ok(())
    }
}

impl Drop for Writer {
    fn drop(&mut self) {
        if !self.tmp.as_os_str().is_empty() {
            drop(self.out.take());
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

fn parent(p: &Path) -> PathBuf {
    match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// fsyncs a directory so a rename in it is durable.
fn sync_dir(dir: &Path) -> Result<()> {
    #[cfg(unix)]
    {
        File::open(dir)
            .and_then(|d| d.sync_all())
            .map_err(|e| Error::io(dir, e))?;
    }
    #[cfg(not(unix))]
    let _ = dir;
    Ok(())
}
