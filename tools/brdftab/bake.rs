//! `bake`, and the bake settings `convert` and `db add` share: the library's
//! [`brdftab::request::BakeSettings`] as flags, so a flag is the field of the same
//! name in Python and in the C ABI's JSON, and the library makes every decision. The library's
//! argument errors name the field (`target_error`); `main` names the flag (`--target-error`).

use brdftab::bake::{BakeReport, BakeRequest, BakeTarget};
use brdftab::request::{self, BakeSettings};
use brdftab::{Error, Result};
use clap::Args;

use brdftab_tools::progress::Bar;

/// Arguments of `brdftab bake`.
#[derive(Args)]
pub struct BakeArgs {
    /// The source: a model spec (inline JSON or .json), a table, a MERL or RGL file.
    pub source: std::ffi::OsString,
    /// Output table file (`.btdb`), or `DB#NAME`.
    #[arg(short, long)]
    pub output: brdftab_tools::args::PathArg,
    #[command(flatten)]
    pub settings: BakeSettings,
}

/// `brdftab bake`.
pub fn bake(a: BakeArgs) -> Result<()> {
    let codec = a.settings.request(&a.source)?.codec;
    let r = request::bake(&a.source, &a.output, &a.settings, &Bar::values())?;
    eprint!("{}", r.summary(&codec));
    Ok(())
}

/// Runs a request with a progress bar and prints what it did on stderr.
pub fn run(req: &BakeRequest, target: &BakeTarget) -> Result<BakeReport> {
    let r = req.run_with(target, &Bar::values())?;
    eprint!("{}", r.summary(&req.codec));
    Ok(r)
}

/// Names the CLI flag `name` in an argument error of the library.
pub fn flag_named(e: Error, name: &str) -> Error {
    match e {
        Error::InvalidArgument { msg, .. } => Error::arg(name, msg),
        e => e,
    }
}
