//! A simple table file: a JSON header and raw little-endian f32 values.
//!
//! Stop-gap until the store's compressed chunked format lands (it replaces this). Layout:
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

impl Table {
    /// Writes the table as a raw file (see [`crate::table::raw`]).
    pub fn save_raw(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let header = serde_json::to_vec(&Header {
            format: 1,
            grid: self.grid().clone(),
            description: self.description().to_owned(),
            values: self.values().len() as u64,
        })
        .map_err(|e| Error::Json {
            context: path.display().to_string(),
            source: e,
        })?;
        let tmp = path.with_extension("tmp-raw");
        let io = |e| Error::io(&tmp, e);
        let f = std::fs::File::create(&tmp).map_err(io)?;
        let mut w = std::io::BufWriter::new(f);
        w.write_all(MAGIC).map_err(io)?;
        w.write_all(&(header.len() as u64).to_le_bytes()).map_err(io)?;
        w.write_all(&header).map_err(io)?;
        for chunk in self.values().chunks(1 << 16) {
            let bytes: Vec<u8> = chunk.iter().flat_map(|v| v.to_le_bytes()).collect();
            w.write_all(&bytes).map_err(io)?;
        }
        w.flush().map_err(io)?;
        drop(w);
        std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
    }

    /// True when the file starts with the raw table magic.
    pub fn is_raw(path: impl AsRef<Path>) -> bool {
        let mut m = [0u8; 12];
        std::fs::File::open(path)
            .and_then(|mut f| f.read_exact(&mut m))
            .is_ok()
            && &m == MAGIC
    }

    /// Reads a raw table file.
    pub fn open_raw(path: impl AsRef<Path>) -> Result<Table> {
        let path = path.as_ref();
        let name = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        if bytes.len() < 20 || &bytes[..12] != MAGIC {
            return Err(Error::format(&name, Some("magic"), Some(0), "not a brdftab raw table"));
        }
        let hl = u64::from_le_bytes(bytes[12..20].try_into().unwrap_or_default());
        let end = 20u64.checked_add(hl).filter(|&e| e <= bytes.len() as u64).ok_or_else(|| {
            Error::format(&name, Some("header length"), Some(12), format!("{hl} exceeds the file"))
        })? as usize;
        let h: Header = serde_json::from_slice(&bytes[20..end]).map_err(|e| Error::Json {
            context: name.clone(),
            source: e,
        })?;
        if h.format != 1 {
            return Err(Error::format(&name, Some("format"), None, format!("version {} unknown", h.format)));
        }
        let n = h.grid.stored_values();
        if h.values != n as u64 || bytes.len() - end != n * 4 {
            return Err(Error::format(
                &name,
                Some("values"),
                Some(end as u64),
                format!("{} bytes of values, the grid needs {}", bytes.len() - end, n * 4),
            ));
        }
        let values = bytes[end..]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        Table::new(h.grid, values, h.description)
    }
}
