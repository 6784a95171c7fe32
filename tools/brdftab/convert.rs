//! `convert`: any SOURCE into a MERL file, an RGL `.bsdf` or a table
//! ([`brdftab::request::convert`]), with the output's accuracy reported.

use brdftab::Result;
use brdftab::request::{self, ConvertOutput, ConvertSettings};
use clap::Args;

use brdftab_tools::errln;
use brdftab_tools::progress::Bar;

/// Arguments of `brdftab convert`.
#[derive(Args)]
pub struct ConvertArgs {
    /// Any SOURCE: a MERL `.binary`, an RGL `.bsdf`, a spec, a table.
    input: std::ffi::OsString,
    /// The output: an RGL `.bsdf` (loads in Mitsuba 3 and pbrt-v4), a MERL `.binary` (the
    /// source's mean over each MERL cell), a table database entry `DB#NAME` (or a
    /// `.btdb` file, named after the input), or a raw table file (or `-o OUTPUT`, as `bake`).
    #[arg(required_unless_present = "to", conflicts_with = "to")]
    output: Option<brdftab_tools::args::PathArg>,
    /// The output, as `bake -o` takes it: the same as OUTPUT.
    #[arg(short = 'o', long = "output", id = "to", value_name = "OUTPUT")]
    to: Option<brdftab_tools::args::PathArg>,
    #[command(flatten)]
    settings: ConvertSettings,
}

/// Converts between formats and prints what was written.
pub fn convert(a: ConvertArgs) -> Result<()> {
    let out = a.output.or(a.to).unwrap_or_default(); // clap requires one of them
    match request::convert(&a.input, &out, &a.settings, &Bar::values())? {
        ConvertOutput::Merl(r) => errln!(
            "{}: {} on the MERL grid (90 × 90 × 180 cells: the mean of the source over each, or \
             its own cells when it is on that grid) in {:.2} s",
            r.output,
            r.source,
            r.seconds
        )?,
        ConvertOutput::Rgl(r) => {
            let f = &r.written.fields;
            errln!(
                "{}: {} as an RGL tensor file ({} φi × {} θi, {n}×{n} table, {} bytes, {:.2} s)",
                out,
                r.source,
                f.phi_i.len(),
                f.theta_i.len(),
                r.written.bytes,
                r.seconds,
                n = f.n
            )?;
            if let Some(e) = r.error {
                errln!(
                    "  error vs source (read back, {} pairs within 80°): relative RMSE of f_r weighted by cos θi cos θo {:.3e}, max relative {:.3e}",
                    e.pairs,
                    e.rel_rmse,
                    e.max_rel
                )?;
                let f = &e.fidelity;
                errln!(
                    "  over the whole domain (f_r cos θi cos θo): whole hemisphere {:.2} %, grazing band (a direction past 80°) {:.2} %, worst albedo {:.2} % at {}° (channel {})",
                    100.0 * f.whole,
                    100.0 * f.grazing,
                    100.0 * f.albedo.worst,
                    f.albedo.theta_deg,
                    f.albedo.channel
                )?;
            }
        }
        ConvertOutput::Table { report: r, interp } => {
            errln!("{}: {}", r.output, r.source)?;
            errln!(
                "  grid: {} ({} values, {:.2} s)",
                r.grid_line(),
                r.values,
                r.seconds
            )?;
            if let Some(acc) = r.accuracy {
                errln!(
                    "  accuracy vs native ({interp:?}, {} pairs): relative RMSE of f_r cos θi cos θo {:.3e}, max relative {:.3e}",
                    acc.pairs,
                    acc.rel_rmse,
                    acc.max_rel
                )?;
                errln!(
                    "  within 80° of the normal (Ngan et al.'s cut; grazing f_r of measured data ∝ 1/cos θo): relative RMSE {:.3e}, max relative {:.3e}",
                    acc.rel_rmse_80,
                    acc.max_rel_80
                )?;
            }
        }
    }
    Ok(())
}
