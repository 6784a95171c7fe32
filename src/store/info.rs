//! What `brdftab info` reports of a brdftab file, as JSON values every host shares.
//!
//! The CLI prints these (as JSON with `--json`, as text otherwise), the bake request returns the
//! entry of the table it wrote, and the Python package hands them out as dicts — so the keys are
//! an interface: `name`, `source`, `parameterization`, `symmetry`, `channels`, `units`, `codec`,
//! `tool`, `shape`, `values`, `chunks`, `bytes`, `ratio_to_f32`, `sampling_bytes` (the importance
//! sampler's structure, built in memory on the first `sample`/`pdf`; reported of one table —
//! `DB#NAME`, a file of one table — only: sizing it builds the sampler, so neither [`list`]'s
//! rows nor [`file_info`] of a database of several tables hold it), `quantity` (what the
//! stored values are: `fr`, `fr_cos_out` or `fr_cos_cos`, [`crate::table::Quantity::name`]) and
//! `calibrated` (whether lookups multiply them by an albedo calibration's k_in(θi) k_out(θo))
//! per table; `file`, `format`, `bytes`, `ratio_to_f32`, `table_count` (the tables the file
//! holds, also when `tables` reports one of them) and `tables` per file. The last two say
//! how the raw values (`export`, Python's `Table.values`) become f_r.

use std::ffi::OsStr;
use std::fmt::Write as _;
use std::path::Path;

use serde_json::{Value, json};

use super::{Store, db};
use crate::error::{Error, Result};
use crate::table::{Quantity, SamplingResolution, Table};

/// The summary of table `name` of an open store.
pub fn table_summary(s: &Store, name: &str) -> Result<Value> {
    summary(s, name, true)
}

/// The summary of table `name`, with `sampling_bytes` when `sampling` (which builds the
/// table's importance sampler to size it: 0.1 s for the smallest table, and every chunk of a
/// table with a one-array kernel decoded); without it, what the header and index say and
/// nothing decoded.
fn summary(s: &Store, name: &str, sampling: bool) -> Result<Value> {
    let t = s.table(name)?;
    let h = t.header();
    let bytes = t.compressed_bytes();
    let isotropic = h.symmetry.split('+').any(|p| p == "isotropic");
    // The sampler a table builds when opened with its default lookup: nearest on a grid of
    // cells (TabulatedBrdf::default_interp).
    let grid = t.grid().ok();
    let cells = grid
        .as_ref()
        .is_some_and(|g| crate::table::Interp::default_for(g) == crate::table::Interp::Nearest);
    let quantity = grid.as_ref().map_or(Quantity::Fr, |g| g.quantity());
    let calibrated = grid.as_ref().is_some_and(|g| g.calibration().is_some());
    let mut v = json!({
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
        "quantity": quantity.name(),
        "calibrated": calibrated,
        "axes": grid.as_ref().map(axes_json),
    });
    if sampling {
        v["sampling_bytes"] = sampling_resolution(&t, grid.as_ref(), isotropic, cells)
            .memory_bytes(isotropic)
            .into();
    }
    Ok(v)
}

/// Where the stored nodes sit, axis by axis in the stored shape's order (the `.npy` export's
/// axes): name, mapping, node placement and every node's angle in degrees — so values
/// exported by `export --npy` can be placed without the library.
fn axes_json(g: &crate::table::Grid) -> Value {
    let mut names = g.param().axis_names();
    // An isotropic `inout` table stores φi = 0 only and φo as the difference φo − φi.
    if g.param() == crate::table::Param::InOut && g.symmetry().isotropic {
        names[3] = "phi_o_minus_phi_i";
    }
    g.stored_axes()
        .iter()
        .zip(names)
        .map(|(a, name)| {
            json!({
                "name": name,
                "mapping": a.mapping.label(),
                "nodes": a.nodes,
                "degrees": (0..a.size).map(|i| a.node(i).to_degrees()).collect::<Vec<_>>(),
            })
        })
        .collect()
}

/// The resolution of the sampler the table `t` builds when opened with its default lookup
/// ([`SamplingResolution::for_source`]: probes the table's peak at normal incidence, reading
/// the chunks it needs); [`SamplingResolution::for_lookup`] when the grid is unreadable.
fn sampling_resolution(
    t: &super::StoredTable,
    grid: Option<&crate::table::Grid>,
    isotropic: bool,
    cells: bool,
) -> SamplingResolution {
    match grid {
        Some(g) if isotropic => {
            let mut b = crate::table::TabulatedBrdf::lazy(g.clone(), Box::new(t.loader()), "");
            if cells {
                b.set_interp(crate::table::Interp::Nearest);
            }
            SamplingResolution::for_source(&b, isotropic, cells)
        }
        _ => SamplingResolution::for_lookup(isotropic, cells),
    }
}

/// The summary of table `name` of the file at `path`.
pub fn table_info(path: impl AsRef<Path>, name: &str) -> Result<Value> {
    table_summary(&Store::open(path)?, name)
}

/// The summaries of every table of the file at `path`, in file order (`brdftab db list`):
/// what each table's header and chunk index say, without `sampling_bytes` and with no chunk
/// decoded. (Sizing each table's sampler made `db list` of a database of 1,000 tables of
/// 576 values take 94 s, and decoded every chunk of every table with a one-array kernel:
/// [`table_summary`] and `info` of one table report it.)
pub fn list(path: impl AsRef<Path>) -> Result<Vec<Value>> {
    let s = Store::open(path)?;
    s.tables()
        .iter()
        .map(|e| summary(&s, &e.name, false))
        .collect()
}

/// What `info` reports of `FILE` (every table) or `DB#NAME` (that table); SOURCE need not be
/// UTF-8 ([`db::split_source`]).
pub fn file_info(source: impl AsRef<OsStr>) -> Result<Value> {
    let (path, name) = db::split_source(source.as_ref())?;
    file_info_at(path, name)
}

/// [`file_info`] of the brdftab file at `path`, taken as a path (never split at a `#`): table
/// `name`, or every table for `None`. `sampling_bytes` is reported of one table (`name`, or a
/// file holding one table): sizing a sampler builds it (0.1 s for the smallest table, every
/// chunk of a one-array table decoded), and `info` of a database of 1,000 small tables took
/// 94 s (session 39). A database of several tables is reported as [`list`] reads it. `file` is
/// the path as text (lossily when it is not UTF-8).
pub fn file_info_at(path: impl AsRef<Path>, name: Option<&str>) -> Result<Value> {
    let path = path.as_ref();
    let s = Store::open(path)?;
    let names: Vec<String> = match name {
        Some(n) => vec![n.to_owned()],
        None => s.tables().iter().map(|e| e.name.clone()).collect(),
    };
    let sampling = names.len() == 1;
    let tables: Vec<Value> = names
        .iter()
        .map(|n| summary(&s, n, sampling))
        .collect::<Result<_>>()?;
    // The file's ratio compares the whole file with every table it holds, also when one table
    // is asked for (`DB#NAME`): against that table alone it read "0.6x smaller than f32".
    let values = s
        .tables()
        .iter()
        .map(|e| s.table(&e.name).map(|t| t.header().values))
        .sum::<Result<u64>>()?;
    Ok(json!({
        "file": path.display().to_string(),
        "format": "btdb",
        "bytes": s.file_len(),
        "ratio_to_f32": values as f64 * 4.0 / s.file_len().max(1) as f64,
        "table_count": s.tables().len(),
        "tables": tables,
    }))
}

/// Renders an `info` report as the text `brdftab info` prints.
pub type TextFn = fn(&Value) -> String;

/// What `info` reports of a table SOURCE that is no measured file, with the function that
/// renders it as text: a brdftab file or `DB#NAME` ([`file_info`], [`file_text`]) or a raw
/// table ([`raw_info`], [`raw_text`]). A `DB#NAME` is a database's table even when DB is
/// missing, so that the error names DB (not a raw file `DB#NAME`).
pub fn table_file_info(source: impl AsRef<OsStr>) -> Result<(Value, TextFn)> {
    let source = source.as_ref();
    let (path, name) = db::split_source(source)?;
    if name.is_some() || super::tables::is_store_file(path) {
        Ok((file_info(source)?, file_text))
    } else {
        Ok((raw_info(source)?, raw_text))
    }
}

/// What `info` reports of a raw table file (`format` = `raw`).
pub fn raw_info(path: impl AsRef<Path>) -> Result<Value> {
    let path = path.as_ref();
    let t = Table::open_raw(path)?;
    let g = t.grid();
    let bytes = std::fs::metadata(path)
        .map_err(|e| Error::io(path, e))?
        .len();
    Ok(json!({
        "file": path.display().to_string(),
        "format": "raw",
        "description": t.description(),
        "grid": g,
        "grid_summary": g.summary(),
        "parameterization": g.param(),
        "symmetry": g.symmetry().to_string(),
        "channels": g.channels().names(),
        "stored_shape": g.stored_shape(),
        "chunks": g.layout().chunk_count(),
        "stored_values": g.stored_values(),
        "full_values": g.full_values(),
        "bytes": bytes,
    }))
}

/// [`raw_info`] as the text `brdftab info` prints.
pub fn raw_text(v: &Value) -> String {
    let s = |k: &str| v[k].as_str().unwrap_or("").to_owned();
    let names: Vec<&str> = v["channels"]
        .as_array()
        .map(|a| a.iter().filter_map(Value::as_str).collect())
        .unwrap_or_default();
    let mut o = String::new();
    let _ = writeln!(o, "file:          {}", s("file"));
    let _ = writeln!(o, "source:        {}", s("description"));
    let _ = writeln!(o, "grid:          {}", s("grid_summary"));
    let _ = writeln!(o, "symmetry:      {}", s("symmetry"));
    let _ = writeln!(o, "channels:      {}", names.join(" "));
    for k in ["chunks", "stored_values", "full_values"] {
        let _ = writeln!(o, "{:<15}{}", format!("{k}:"), v[k]);
    }
    let _ = writeln!(o, "bytes:         {}", v["bytes"]);
    o
}

/// [`list`] as the table `brdftab db list` prints: one line per table.
pub fn list_text(rows: &[Value]) -> String {
    use unicode_width::UnicodeWidthStr;
    // The name column is as wide as the widest name on a terminal (a CJK character takes two
    // cells, a combining accent none), at least 24: `{:<24}` counted chars and a long or wide
    // name pushed its row's other columns out of line.
    let name_of = |r: &Value| r["name"].as_str().unwrap_or("").to_owned();
    let width = rows
        .iter()
        .map(|r| name_of(r).width())
        .max()
        .unwrap_or(0)
        .max(24);
    let pad = |s: &str| format!("{s}{}", " ".repeat(width - s.width().min(width)));
    let mut o = format!(
        "{} {:<8} {:>12} {:>12} {:>7}  grid\n",
        pad("name"),
        "codec",
        "values",
        "bytes",
        "ratio"
    );
    for r in rows {
        let shape = r["shape"]
            .as_array()
            .map(|a| {
                a.iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join("x")
            })
            .unwrap_or_default();
        let _ = writeln!(
            o,
            "{} {:<8} {:>12} {:>12} {:>6.1}x  {} {} {}",
            pad(&name_of(r)),
            r["codec"]["quant"].as_str().unwrap_or(""),
            r["values"].as_u64().unwrap_or(0),
            r["bytes"].as_u64().unwrap_or(0),
            r["ratio_to_f32"].as_f64().unwrap_or(0.0),
            r["parameterization"].as_str().unwrap_or(""),
            shape,
            r["symmetry"].as_str().unwrap_or(""),
        );
    }
    o
}

/// [`file_info`] as the text `brdftab info` prints.
pub fn file_text(v: &Value) -> String {
    let tables = v["tables"].as_array().cloned().unwrap_or_default();
    let str_of = |t: &Value, k: &str| t[k].as_str().unwrap_or("").to_owned();
    // The file's tables, not the ones reported: `DB#NAME` reports one of several.
    let count = v["table_count"].as_u64().unwrap_or(tables.len() as u64);
    let shown = if (tables.len() as u64) < count {
        format!(", {} shown", tables.len())
    } else {
        String::new()
    };
    let mut o = String::new();
    let _ = writeln!(
        o,
        "file:    {} (brdftab format, {count} table{}{shown})",
        str_of(v, "file"),
        if count == 1 { "" } else { "s" }
    );
    if tables.is_empty() {
        // No values to compare with (it read "0.0x smaller than f32").
        let _ = writeln!(o, "bytes:   {} (no tables)", v["bytes"]);
    } else {
        let _ = writeln!(
            o,
            "bytes:   {} ({:.1}x smaller than f32)",
            v["bytes"],
            v["ratio_to_f32"].as_f64().unwrap_or(0.0)
        );
    }
    for t in &tables {
        let _ = writeln!(o, "table `{}`:", str_of(t, "name"));
        let _ = writeln!(o, "  source:   {}", t["source"]);
        let _ = writeln!(
            o,
            "  grid:     {} {} {}",
            str_of(t, "parameterization"),
            t["shape"],
            str_of(t, "symmetry")
        );
        let _ = writeln!(o, "  codec:    {}", t["codec"]);
        let _ = writeln!(
            o,
            "  values:   {} in {} chunks, {} bytes ({:.1}x smaller than f32)",
            t["values"],
            t["chunks"],
            t["bytes"],
            t["ratio_to_f32"].as_f64().unwrap_or(0.0)
        );
        let _ = match t.get("sampling_bytes") {
            Some(b) => writeln!(o, "  sampling: {b} bytes in memory once sampled"),
            None => writeln!(o, "  sampling: sized for one table at a time (DB#NAME)"),
        };
        let stores = match t["quantity"].as_str() {
            Some("fr_cos_cos") => "f_r cos θi cos θo (lookups divide by both cosines)",
            Some("fr_cos_out") => "f_r cos θo (lookups divide by cos θo)",
            _ => "f_r",
        };
        let calibrated = if t["calibrated"].as_bool() == Some(true) {
            ", times an albedo calibration k_in(θi) k_out(θo) at lookup"
        } else {
            ""
        };
        let _ = writeln!(o, "  stores:   {stores}{calibrated}");
        let _ = writeln!(
            o,
            "  units:    {}   tool: {}",
            str_of(t, "units"),
            str_of(t, "tool")
        );
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;
    use unicode_width::UnicodeWidthStr;

    #[test]
    fn the_header_counts_the_files_tables_not_the_ones_reported() {
        // `info DB#NAME` of a database of two tables said "1 table".
        let row = json!({"name": "a", "codec": {"quant": "f32"}, "values": 1, "bytes": 1});
        let one_of_two = json!({"file": "x.btdb", "bytes": 9, "table_count": 2, "tables": [row]});
        let text = file_text(&one_of_two);
        assert!(
            text.contains("(brdftab format, 2 tables, 1 shown)"),
            "{text}"
        );
        let whole = json!({"file": "x.btdb", "bytes": 9, "table_count": 1, "tables": [row]});
        assert!(file_text(&whole).contains("(brdftab format, 1 table)"));
    }

    #[test]
    fn list_columns_stay_aligned_with_long_and_wide_names() {
        // A 34-cell CJK name and a 40-character one pushed their rows' columns right of the
        // header's (`{:<24}` pads by chars, and not at all past 24).
        let names = [
            "c",
            "日本語の長い名前のテーブル名前です",
            &"n".repeat(40),
            "é",
        ];
        let rows: Vec<Value> = names
            .iter()
            .map(|n| json!({"name": n, "codec": {"quant": "log16"}, "values": 1, "bytes": 1}))
            .collect();
        let text = list_text(&rows);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), names.len() + 1);
        let column = |line: &str, word: &str| line[..line.find(word).unwrap()].width();
        let codec_at = column(lines[0], "codec");
        assert_eq!(codec_at, 41, "{text}");
        for l in &lines[1..] {
            assert_eq!(column(l, "log16"), codec_at, "{text}");
        }
    }
}
