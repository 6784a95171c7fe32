//! `fit`: least-squares fit of a model's parameters to any SOURCE
//! ([`brdftab::request::fit`]).

use brdftab::request::{self, FitSettings};
use brdftab::{Error, Result};
use clap::Args;

use brdftab_tools::outln;

/// Arguments of `brdftab fit`.
#[derive(Args)]
pub struct FitArgs {
    /// The data to fit: a spec, table, MERL `.binary` or RGL `.bsdf` file.
    source: std::ffi::OsString,
    /// The model: a name (`ggx`, `reciprocal_phong`, ...), a sum of names
    /// (`lambert+cook_torrance`, `lambert+ggx`, `lambert+blinn_phong`, `lambert+ward`), or a JSON
    /// spec used as the first start.
    #[arg(long)]
    model: String,
    #[command(flatten)]
    settings: FitSettings,
    /// Print the whole result as JSON: {"spec": .., "rmse": .., "iterations": .., "starts": [..]}.
    #[arg(long)]
    json: bool,
}

/// Runs the fit and prints the fitted spec (or the whole result with `--json`).
pub fn fit(a: FitArgs) -> Result<()> {
    let bar = brdftab_tools::progress::Bar::new("fit {bar:30} {pos}/{len} starts {elapsed}");
    let result = request::fit(&a.source, &a.model, &a.settings, &bar)?;
    let text = if a.json {
        serde_json::to_string(&result).map_err(|e| Error::Json {
            context: "fit result".into(),
            source: e,
        })?
    } else {
        for n in result.bound_notes() {
            eprintln!("note: {n}"); // (`--json`: each parameter's `at_bound`)
        }
        result.spec.to_json()
    };
    outln!("{text}")?;
    Ok(())
}
