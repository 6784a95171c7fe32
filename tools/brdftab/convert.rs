//! `convert`: any SOURCE into a MERL file or a table, with the table's accuracy reported.

use brdftab::bake::BakeTarget;
use brdftab::table::Interp;
use brdftab::{Error, Result};
use clap::Args;

use crate::bake::BakeFlags;
use crate::progress::Bar;
use crate::source::{self, Kind};

/// Arguments of `brdftab convert`.
#[derive(Args)]
pub struct ConvertArgs {
    /// Any SOURCE: a MERL `.binary`, an RGL `.bsdf`, a spec, a table.
    input: String,
    /// The output: a MERL `.binary` (the source resampled at the MERL cell centres), a table
    /// database entry `DB#NAME` (or a `.btdb` file, named after the input), or a raw table file.
    output: String,
    /// Interpolation for the reported accuracy: nearest or linear.
    #[arg(long, default_value = "linear")]
    interp: String,
    /// Random pairs for the reported accuracy (0 = skip).
    #[arg(long, default_value_t = 200_000)]
    pairs: usize,
    /// Replace an existing table of that name (database outputs).
    #[arg(long)]
    replace: bool,
    #[command(flatten)]
    flags: BakeFlags,
}

/// Converts between formats.
pub fn convert(a: ConvertArgs) -> Result<()> {
    match source::kind(&a.output) {
        Kind::Merl => {
            let req = a.flags.request(&a.input)?;
            let r = req.run_with(&BakeTarget::Merl(a.output.clone()), &Bar::values())?;
            println!(
                "{}: {} resampled on the MERL grid (90 × 90 × 180 cell centres) in {:.2} s",
                r.output, r.source, r.seconds
            );
            Ok(())
        }
        Kind::Rgl => Err(Error::Unsupported(
            "writing RGL .bsdf files (they are read only)".into(),
        )),
        _ => to_table(a),
    }
}

/// Tabulates the input into `DB#NAME`, a `.btdb` file (a table named after the input) or a raw
/// table file, and reports the tabulated-vs-native accuracy.
fn to_table(a: ConvertArgs) -> Result<()> {
    let mut req = a.flags.request(&a.input)?;
    req.accuracy_pairs = a.pairs;
    req.accuracy_interp = Interp::parse(&a.interp).map_err(|e| crate::bake::flag(e, "--interp"))?;
    let name = req
        .name
        .clone()
        .unwrap_or_else(|| brdftab::bake::stem(&a.input));
    let target = match BakeTarget::parse(&a.output, None, a.replace) {
        BakeTarget::File(p) => BakeTarget::Db {
            path: p,
            name,
            replace: a.replace,
        },
        t => t,
    };
    let r = req.run_with(&target, &Bar::values())?;
    println!("{}: {}", r.output, r.source);
    println!(
        "  grid: {} ({} values, {:.2} s)",
        r.grid_line(),
        r.values,
        r.seconds
    );
    if let Some(acc) = r.accuracy {
        println!(
            "  accuracy vs native ({:?}, {} pairs): cosine-weighted relative RMSE {:.3e}, max relative {:.3e}",
            req.accuracy_interp, acc.pairs, acc.rel_rmse, acc.max_rel
        );
        println!(
            "  within 80° of the normal (Ngan et al.'s cut; grazing f_r of measured data ∝ 1/cos θo): relative RMSE {:.3e}, max relative {:.3e}",
            acc.rel_rmse_80, acc.max_rel_80
        );
    }
    Ok(())
}
