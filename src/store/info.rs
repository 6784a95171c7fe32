//! What `brdftab info` reports of a brdftab file, as JSON values every host shares.
//!
//! The CLI prints these (as JSON with `--json`, as text otherwise), the bake request returns the
//! entry of the table it wrote, and the Python package hands them out as dicts — so the keys are
//! an interface: `name`, `source`, `parameterization`, `symmetry`, `channels`, `units`, `codec`,
//! `tool`, `shape`, `values`, `chunks`, `bytes`, `ratio_to_f32` per table; `file`, `format`,
//! `bytes`, `ratio_to_f32`, `tables` per file.

use serde_json::{Value, json};

use super::{Store, db};
use crate::error::Result;

/// The summary of table `name` of an open store.
pub fn table_summary(s: &Store, name: &str) -> Result<Value> {
    let t = s.table(name)?;
    let h = t.header();
    let bytes = t.compressed_bytes();
    Ok(json!({
        "name": h.name,
        "source": h.source,
        "parameterization": h.parameterization,
        "symmetry": h.symmetry,
        "channels": h.channels,
        "units": h.units,
        "codec": h.codec,
        "tool": h.tool,
        "shape": h.shape,
        "values": h.values,
        "chunks": t.chunk_count(),
        "bytes": bytes,
        "ratio_to_f32": (h.values as f64 * 4.0) / (bytes.max(1) as f64),
    }))
}

/// The summary of table `name` of the file at `path`.
pub fn table_info(path: &str, name: &str) -> Result<Value> {
    table_summary(&Store::open(path)?, name)
}

/// The summaries of every table of the file at `path`, in file order.
pub fn list(path: &str) -> Result<Vec<Value>> {
    let s = Store::open(path)?;
    s.tables()
        .iter()
        .map(|e| table_summary(&s, &e.name))
        .collect()
}

/// What `info` reports of `FILE` (every table) or `DB#NAME` (that table).
pub fn file_info(source: &str) -> Result<Value> {
    let (path, name) = db::split_source(source);
    let s = Store::open(path)?;
    let names: Vec<String> = match name {
        Some(n) => vec![n.to_owned()],
        None => s.tables().iter().map(|e| e.name.clone()).collect(),
    };
    let tables: Vec<Value> = names
        .iter()
        .map(|n| table_summary(&s, n))
        .collect::<Result<_>>()?;
    let values: u64 = tables
        .iter()
        .map(|t| t["values"].as_u64().unwrap_or(0))
        .sum();
    Ok(json!({
        "file": path,
        "format": "btdb",
        "bytes": s.file_len(),
        "ratio_to_f32": values as f64 * 4.0 / s.file_len().max(1) as f64,
        "tables": tables,
    }))
}
