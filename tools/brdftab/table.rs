//! `info`: what a table file holds.

use std::fmt::Write as _;

use brdftab::store::{db, tables};
use brdftab::table::Table;
use brdftab::{Error, Result};
use clap::Args;
use serde_json::json;

use crate::source;

/// Writes `text` to stdout; a closed pipe (`| head`) is not an error.
pub fn print_out(text: &str) -> Result<()> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(Error::io("stdout", e)),
        _ => Ok(()),
    }
}

/// Arguments of `brdftab info`.
#[derive(Args)]
pub struct InfoArgs {
    /// A table file.
    file: String,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// `brdftab info`.
pub fn info(a: InfoArgs) -> Result<()> {
    if matches!(
        source::kind(&a.file),
        source::Kind::Merl | source::Kind::Rgl
    ) {
        return crate::measured::info_source(&a.file);
    }
    if tables::is_store_file(db::split_source(&a.file).0) {
        return crate::db::info(&a.file, a.json);
    }
    let t = Table::open_raw(&a.file)?;
    let g = t.grid();
    let bytes = std::fs::metadata(&a.file)
        .map_err(|e| Error::io(&a.file, e))?
        .len();
    let mut o = String::new();
    let v = json!({
        "file": a.file,
        "format": "raw",
        "description": t.description(),
        "grid": g,
        "parameterization": g.param(),
        "symmetry": g.symmetry().to_string(),
        "channels": g.channels().names(),
        "stored_shape": g.stored_shape(),
        "chunks": g.layout().chunk_count(),
        "stored_values": g.stored_values(),
        "full_values": g.full_values(),
        "bytes": bytes,
    });
    if a.json {
        let _ = writeln!(
            o,
            "{}",
            serde_json::to_string_pretty(&v).unwrap_or_default()
        );
    } else {
        let _ = writeln!(o, "file:          {}", a.file);
        let _ = writeln!(o, "source:        {}", t.description());
        let _ = writeln!(o, "grid:          {}", g.summary());
        let _ = writeln!(o, "symmetry:      {}", g.symmetry());
        let _ = writeln!(o, "channels:      {}", g.channels().names().join(" "));
        let _ = writeln!(o, "chunks:        {}", g.layout().chunk_count());
        let _ = writeln!(o, "stored_values: {}", g.stored_values());
        let _ = writeln!(o, "full_values:   {}", g.full_values());
        let _ = writeln!(o, "bytes:         {bytes}");
    }
    print_out(&o)
}
