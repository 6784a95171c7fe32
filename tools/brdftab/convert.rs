//! `convert`: any SOURCE into a MERL file or a table, with the table's accuracy reported.

use brdftab::Result;
use brdftab::bake::BakeTarget;
use brdftab::measured::rgl_write;
use brdftab::table::Interp;
use clap::Args;

use crate::bake::BakeFlags;
use crate::progress::Bar;
use crate::source::{self, Kind};

/// Arguments of `brdftab convert`.
#[derive(Args)]
pub struct ConvertArgs {
    /// Any SOURCE: a MERL `.binary`, an RGL `.bsdf`, a spec, a table.
    input: String,
    /// The output: an RGL `.bsdf` (loads in Mitsuba 3 and pbrt-v4), a MERL `.binary` (the
    /// source resampled at the MERL cell centres), a table database entry `DB#NAME` (or a `.btdb` file, named after the input), or a raw table file.
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
    #[command(flatten)]
    rgl: RglArgs,
}

/// Options of `.bsdf` outputs (defaults: the library's; a `.bsdf` input keeps its own layout
/// unless --theta-i, --phi-i or --ndf-resolution is given).
#[derive(Args, Clone)]
pub struct RglArgs {
    /// .bsdf output: reflectance table resolution N (default 64, a .bsdf input's own).
    #[arg(long)]
    resolution: Option<usize>,
    /// .bsdf output: number of incident elevations θi (default 16; 8 = the RGL database's spacing).
    #[arg(long)]
    theta_i: Option<usize>,
    /// .bsdf output: number of incident azimuths φi (default 1 if isotropic, else 17).
    #[arg(long)]
    phi_i: Option<usize>,
    /// .bsdf output: NDF, σ and VNDF grid resolution (default 128).
    #[arg(long)]
    ndf_resolution: Option<usize>,
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
        Kind::Rgl => to_rgl(a),
        _ => to_table(a),
    }
}

/// Writes the input as an RGL tensor file and reports the error of the file read back.
fn to_rgl(a: ConvertArgs) -> Result<()> {
    let opts = rgl_write::Options {
        resolution: a.rgl.resolution,
        theta_i: a.rgl.theta_i,
        phi_i: a.rgl.phi_i,
        ndf_resolution: a.rgl.ndf_resolution,
        ..Default::default()
    };
    let ch = source::channels(a.flags.wavelengths.as_deref())?;
    let r = brdftab::bake::to_rgl(&a.input, ch, &a.output, &opts, a.pairs, &Bar::values())?;
    let f = &r.written.fields;
    println!(
        "{}: {} as an RGL tensor file ({} φi × {} θi, {n}×{n} table, {} bytes, {:.2} s)",
        a.output,
        r.source,
        f.phi_i.len(),
        f.theta_i.len(),
        r.written.bytes,
        r.seconds,
        n = f.n
    );
    if let Some(e) = r.error {
        println!(
            "  error vs source (read back, {} pairs within 80°): relative RMSE of f_r weighted by cos θi cos θo {:.3e}, max relative {:.3e}",
            e.pairs, e.rel_rmse, e.max_rel
        );
    }
    Ok(())
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
