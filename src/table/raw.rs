//! A simple table file: a JSON header and raw little-endian f32 values.
//!
//! The uncompressed format beside the store's compressed, chunked one ([`crate::store`]):
//! `convert` writes it for an output named neither `.btdb` nor `DB#NAME`
//! ([`crate::bake::BakeTarget::Raw`]), and every host opens it as a SOURCE. Layout:
//!
//! ```text
//! magic   b"BRDFTAB-RAW\n"   (12 bytes)
//! u64 LE  header length H
//! H bytes JSON header: {"format": 1, "grid": <Grid>, "description": "...", "values": N}
//! N × f32 LE values in the grid's stored layout (λ innermost, chunks in order)
//! ```

use serde::{Deserialize, Serialize};
use std::io::{Read, Write};
use std::path::Path;

use crate::error::{Error, Result};
use crate::table::{Grid, Table};

/// The magic bytes at the start of a raw table file.
pub const MAGIC: &[u8; 12] = b"BRDFTAB-RAW\n";

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Header {
    format: u32,
    grid: Grid,
    description: String,
    values: u64,
}

/// Writes a raw table file chunk by chunk (bounded memory): feed it from
/// [`bake_chunks`](crate::table::bake_chunks). The file appears under its name only after
/// [`RawWriter::finish`] (written to a temporary name, then renamed).
pub struct RawWriter {
    tmp: std::path::PathBuf,
    path: std::path::PathBuf,
    w: std::io::BufWriter<std::fs::File>,
    remaining: u64,
    bytes: Vec<u8>,
}

impl RawWriter {
    /// Starts a raw file for a table on `grid`.
    pub fn create(path: impl AsRef<Path>, grid: &Grid, description: &str) -> Result<RawWriter> {
        // Through a symbolic link: the file it points to (`files::resolve_links`).
        let path = crate::files::resolve_links(path.as_ref())?;
        let header = serde_json::to_vec(&Header {
            format: 1,
            grid: grid.clone(),
            description: description.to_owned(),
            values: grid.stored_values() as u64,
        })
        .map_err(|e| Error::Json {
            context: path.display().to_string(),
            source: e,
        })?;
        let tmp = crate::files::temp_path(&path)?;
        let f = std::fs::File::create(&tmp).map_err(|e| Error::io(&path, e))?;
        let mut w = std::io::BufWriter::with_capacity(1 << 20, f);
        let mut head = MAGIC.to_vec();
        head.extend_from_slice(&(header.len() as u64).to_le_bytes());
        head.extend_from_slice(&header);
        w.write_all(&head).map_err(|e| Error::io(&path, e))?;
        Ok(RawWriter {
            tmp,
            path,
            w,
            remaining: grid.stored_values() as u64,
            bytes: Vec::new(),
        })
    }

    /// Appends values (the next chunk, in order).
    pub fn write_chunk(&mut self, values: &[f32]) -> Result<()> {
        if values.len() as u64 > self.remaining {
            return Err(Error::arg("values", "more values than the grid stores"));
        }
        self.remaining -= values.len() as u64;
        for part in values.chunks(1 << 18) {
            self.bytes.clear();
            self.bytes.extend(part.iter().flat_map(|v| v.to_le_bytes()));
            self.w
                .write_all(&self.bytes)
                .map_err(|e| Error::io(&self.path, e))?;
        }
        Ok(())
    }

    /// Flushes and moves the file into place; fails if values are missing.
    pub fn finish(mut self) -> Result<()> {
        if self.remaining != 0 {
            let _ = std::fs::remove_file(&self.tmp);
            return Err(Error::arg(
                "values",
                format!("{} values missing", self.remaining),
            ));
        }
        self.w.flush().map_err(|e| Error::io(&self.path, e))?;
        crate::files::rename_over(&self.tmp, &self.path).map_err(|e| Error::io(&self.path, e))
    }
}

impl Table {
    /// Writes the table as a raw file (see [`crate::table::raw`]).
    pub fn save_raw(&self, path: impl AsRef<Path>) -> Result<()> {
        let mut w = RawWriter::create(path, self.grid(), self.description())?;
        w.write_chunk(self.values())?;
        w.finish()
    }

    /// True when the file starts with the raw table magic.
    pub fn is_raw(path: impl AsRef<Path>) -> bool {
        let mut m = [0u8; 12];
        crate::files::is_regular(path.as_ref())
            && std::fs::File::open(path)
                .and_then(|mut f| f.read_exact(&mut m))
                .is_ok()
            && &m == MAGIC
    }

    /// Reads a raw table file.
    pub fn open_raw(path: impl AsRef<Path>) -> Result<Table> {
        let path = path.as_ref();
        crate::files::require_regular(path)?;
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        Table::from_raw_bytes(&path.display().to_string(), &bytes)
    }

    /// Reads a raw table file held in memory (`name` is used in error messages): what
    /// [`Table::open_raw`] runs on the file's bytes, and the fuzz target's entry.
    pub fn from_raw_bytes(name: &str, bytes: &[u8]) -> Result<Table> {
        let name = name.to_owned();
        if bytes.len() < 20 || &bytes[..12] != MAGIC {
            return Err(Error::format(
                &name,
                Some("magic"),
                Some(0),
                "not a brdftab raw table",
            ));
        }
        let hl = u64::from_le_bytes(bytes[12..20].try_into().unwrap_or_default());
        let end = 20u64
            .checked_add(hl)
            .filter(|&e| e <= bytes.len() as u64)
            .ok_or_else(|| {
                Error::format(
                    &name,
                    Some("header length"),
                    Some(12),
                    format!("{hl} exceeds the file"),
                )
            })? as usize;
        let json = |e| Error::Json {
            context: name.clone(),
            source: e,
        };
        let v: serde_json::Value = serde_json::from_slice(&bytes[20..end]).map_err(json)?;
        // The values the file holds bound every axis before the grid is built (a folded axis
        // stores a quarter of its nodes, plus one): a size in a header of a few hundred bytes
        // was an allocation of that size (2^40: the process aborted; 2e8: 1.6 GB and 5 s
        // before the size check below refused it).
        let held = (bytes.len() - end) as u64 / 4;
        let max = held.saturating_mul(4).saturating_add(4);
        if let Some(s) = v
            .get("grid")
            .map(crate::table::grid::json_sizes)
            .and_then(|sizes| sizes.into_iter().find(|&s| s > max))
        {
            return Err(Error::format(
                &name,
                Some("grid"),
                Some(20),
                format!("axis size {s} does not fit the {held} values the file holds"),
            ));
        }
        let h: Header = serde_json::from_value(v).map_err(json)?;
        if h.format != 1 {
            return Err(Error::format(
                &name,
                Some("format"),
                None,
                format!("version {} unknown", h.format),
            ));
        }
        let n = h.grid.stored_values();
        if h.values != n as u64 || bytes.len() - end != n * 4 {
            return Err(Error::format(
                &name,
                Some("values"),
                Some(end as u64),
                format!(
                    "{} bytes of values, the grid needs {}",
                    bytes.len() - end,
                    n * 4
                ),
            ));
        }
        let values = bytes[end..]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        Table::new(h.grid, values, h.description)
    }
}
