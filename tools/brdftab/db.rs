//! `db` subcommands (add, list, rm, verify) and `info` for brdftab files: thin over
//! `brdftab::store`.

use brdftab::bake::BakeTarget;
use brdftab::store::{self, db};
use brdftab::{Error, Result};
use clap::{Args, Subcommand};

use crate::bake::BakeFlags;

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
    /// The source: a model spec (inline JSON or .json), a table, a MERL or RGL file.
    source: String,
    #[command(flatten)]
    bake: Box<BakeFlags>,
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
            let req = a.bake.request(&a.source)?;
            let target = BakeTarget::Db {
                path: a.db.clone(),
                name,
                replace: a.replace,
            };
            crate::bake::run(&req, &target).map(drop)
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

fn list(path: &str, as_json: bool) -> Result<()> {
    let rows = store::info::list(path)?;
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
    let v = store::info::file_info(source)?;
    let tables = v["tables"].as_array().cloned().unwrap_or_default();
    if as_json {
        println!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
        return Ok(());
    }
    println!(
        "file:    {} (brdftab format, {} tables)",
        v["file"].as_str().unwrap_or(""),
        tables.len()
    );
    println!(
        "bytes:   {} ({:.1}x smaller than f32)",
        v["bytes"],
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
