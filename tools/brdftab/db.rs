//! `db` subcommands (add, list, rm, rename, verify): thin over `brdftab::store`.

use brdftab::bake::BakeTarget;
use brdftab::store::{self, db};
use brdftab::{Error, Result};
use clap::{Args, Subcommand};

use brdftab::request::BakeSettings;
use brdftab_tools::outln;

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
    /// Rename table OLD of DB to NEW (refused when DB holds a table NEW).
    Rename {
        /// The database file.
        db: brdftab_tools::args::PathArg,
        /// The table's name.
        old: String,
        /// Its new name.
        new: String,
    },
    /// Check every checksum and decode every chunk of DB.
    Verify(VerifyArgs),
}

/// A table of a database is found by its name, so `db add` takes one: the bake settings'
/// `--name` (whose default, a file's stem, would name every table of DB alike) is required.
#[derive(Args)]
#[command(mut_arg("name", |a| a
    .required(true)
    .help("Table name inside the database (required)")
    .long_help(None::<&str>)))]
struct AddArgs {
    /// The database file.
    db: brdftab_tools::args::PathArg,
    /// The source: a model spec (inline JSON or .json), a table, a MERL or RGL file.
    source: std::ffi::OsString,
    #[command(flatten)]
    bake: Box<BakeSettings>,
}

#[derive(Args)]
struct ListArgs {
    /// The database file.
    db: brdftab_tools::args::PathArg,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args)]
struct RmArgs {
    /// The database file.
    db: brdftab_tools::args::PathArg,
    /// The table to remove.
    name: String,
}

#[derive(Args)]
struct VerifyArgs {
    /// The database file.
    db: brdftab_tools::args::PathArg,
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
                path: a.db.to_path_buf(),
                name,
                replace: a.bake.replace,
            };
            crate::bake::run(&req, &target).map(drop)
        }
        DbCommand::List(a) => list(&a.db, a.json),
        DbCommand::Rm(a) => {
            db::remove(&a.db, &a.name).map(|()| eprintln!("removed `{}` from {}", a.name, a.db))
        }
        DbCommand::Rename { db, old, new } => store::db::rename(&db, &old, &new)
            .map(|()| eprintln!("renamed `{old}` to `{new}` in {db}")),
        DbCommand::Verify(a) => outln!("ok: {} ({} chunks checked)", a.db, db::verify(&a.db)?),
    }
}

fn list(path: &std::path::Path, as_json: bool) -> Result<()> {
    let rows = store::info::list(path)?;
    if as_json {
        let json = serde_json::to_string_pretty(&rows).unwrap_or_default();
        outln!("{json}")?;
    } else {
        brdftab_tools::text::print_out(&store::info::list_text(&rows))?;
    }
    Ok(())
}
