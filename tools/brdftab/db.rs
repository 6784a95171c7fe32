//! `db` subcommands (add, list, rm, verify) and `info` for brdftab files: thin over
//! `brdftab::store`.

use brdftab::store::{Store, db};
use brdftab::{Error, Result};
use clap::{Args, Subcommand};
use serde_json::json;

use crate::table::{BakeArgs, Target};

/// Arguments of `brdftab db`.
#[derive(Args)]
pub struct DbArgs {
    #[command(subcommand)]
    command: DbCommand,
}

#[derive(Subcommand)]
enum DbCommand {
    /// Bake SOURCE into the database DB as table NAME (DB is created if absent).
    Add(AddArgs),
    /// List the tables of DB.
    List(ListArgs),
    /// Remove table NAME from DB.
    Rm(RmArgs),
    /// Check every checksum and decode every chunk of DB.
    Verify(VerifyArgs),
}

#[derive(Args)]
struct AddArgs {
    /// The database file.
    db: String,
    /// Replace an existing table of the same name.
    #[arg(long)]
    replace: bool,
    #[command(flatten)]
    bake: Box<BakeArgs>,
}

#[derive(Args)]
struct ListArgs {
    /// The database file.
    db: String,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct RmArgs {
    /// The database file.
    db: String,
    /// The table to remove.
    name: String,
}

#[derive(Args)]
struct VerifyArgs {
    /// The database file.
    db: String,
}

/// `brdftab db ...`.
pub fn run(a: DbArgs) -> Result<()> {
    match a.command {
        DbCommand::Add(a) => {
            let name = a
                .bake
                .name
                .clone()
                .ok_or_else(|| Error::arg("--name", "db add needs --name NAME"))?;
            if a.bake.output.is_some() {
                return Err(Error::arg(
                    "--output",
                    "db add writes into DB; drop --output",
                ));
            }
            crate::table::bake_to(
                *a.bake,
                Target::Db {
                    path: &a.db,
                    name: &name,
                    replace: a.replace,
                },
            )
        }
        DbCommand::List(a) => list(&a.db, a.json),
        DbCommand::Rm(a) => {
            db::remove(&a.db, &a.name)?;
            eprintln!("removed `{}` from {}", a.name, a.db);
            Ok(())
        }
        DbCommand::Verify(a) => {
            let n = db::verify(&a.db)?;
            println!("ok: {} ({n} chunks checked)", a.db);
            Ok(())
        }
    }
}

fn summary(s: &Store, name: &str) -> Result<serde_json::Value> {
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

fn list(path: &str, as_json: bool) -> Result<()> {
    let s = Store::open(path)?;
    let rows: Vec<serde_json::Value> = s
        .tables()
        .iter()
        .map(|e| summary(&s, &e.name))
        .collect::<Result<_>>()?;
    if as_json {
        println!(
            "{}",
            serde_json::to_string_pretty(&rows).unwrap_or_default()
        );
        return Ok(());
    }
    println!(
        "{:<24} {:<8} {:>12} {:>12} {:>7}  grid",
        "name", "codec", "values", "bytes", "ratio"
    );
    for r in &rows {
        println!(
            "{:<24} {:<8} {:>12} {:>12} {:>6.1}x  {} {} {}",
            r["name"].as_str().unwrap_or(""),
            r["codec"]["quant"].as_str().unwrap_or(""),
            r["values"].as_u64().unwrap_or(0),
            r["bytes"].as_u64().unwrap_or(0),
            r["ratio_to_f32"].as_f64().unwrap_or(0.0),
            r["parameterization"].as_str().unwrap_or(""),
            r["shape"]
                .as_array()
                .map(|a| a
                    .iter()
                    .map(|x| x.to_string())
                    .collect::<Vec<_>>()
                    .join("x"))
                .unwrap_or_default(),
            r["symmetry"].as_str().unwrap_or(""),
        );
    }
    Ok(())
}

/// `brdftab info` for a brdftab file (`FILE` or `DB#NAME`).
pub fn info(source: &str, as_json: bool) -> Result<()> {
    let (path, name) = db::split_source(source);
    let s = Store::open(path)?;
    let names: Vec<String> = match name {
        Some(n) => vec![n.to_owned()],
        None => s.tables().iter().map(|e| e.name.clone()).collect(),
    };
    let tables: Vec<serde_json::Value> = names
        .iter()
        .map(|n| summary(&s, n))
        .collect::<Result<_>>()?;
    let values: u64 = tables
        .iter()
        .map(|t| t["values"].as_u64().unwrap_or(0))
        .sum();
    let v = json!({
        "file": path,
        "format": "btdb",
        "bytes": s.file_len(),
        "ratio_to_f32": values as f64 * 4.0 / s.file_len().max(1) as f64,
        "tables": tables,
    });
    if as_json {
        println!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
        return Ok(());
    }
    println!(
        "file:    {path} (brdftab format, {} tables)",
        s.tables().len()
    );
    println!(
        "bytes:   {} ({:.1}x smaller than f32)",
        s.file_len(),
        v["ratio_to_f32"].as_f64().unwrap_or(0.0)
    );
    for t in &tables {
        println!("table `{}`:", t["name"].as_str().unwrap_or(""));
        println!("  source:   {}", t["source"]);
        println!(
            "  grid:     {} {} {}",
            t["parameterization"].as_str().unwrap_or(""),
            t["shape"],
            t["symmetry"].as_str().unwrap_or("")
        );
        println!("  codec:    {}", t["codec"]);
        println!(
            "  values:   {} in {} chunks, {} bytes ({:.1}x smaller than f32)",
            t["values"],
            t["chunks"],
            t["bytes"],
            t["ratio_to_f32"].as_f64().unwrap_or(0.0)
        );
        println!(
            "  units:    {}   tool: {}",
            t["units"].as_str().unwrap_or(""),
            t["tool"].as_str().unwrap_or("")
        );
    }
    Ok(())
}
