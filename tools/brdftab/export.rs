//! `brdftab export`: a stored table as NumPy `.npy` or a 2D slice as OpenEXR; `brdftab import`:
//! an edited `.npy` back as a table on the grid of a stored one ([`request::import_npy`]).

use brdftab::request::{self, SaveSettings};
use brdftab::store::{Store, db, export, tables};
use brdftab::{Error, Result};
use clap::Args;

/// Arguments of `brdftab export`.
#[derive(Args)]
pub struct ExportArgs {
    /// The table: a brdftab file, or `DB#NAME`.
    source: brdftab_tools::args::PathArg,
    /// Write the dense table as .npy (shape = stored grid dims + channels, float32): the stored
    /// quantity as `info` names it (f_r, f_r cos θo or f_r cos θi cos θo; before a calibration).
    #[arg(long)]
    npy: Option<brdftab_tools::args::PathArg>,
    /// Write a 2D slice as OpenEXR (channels as EXR channels): a `.exr` file.
    #[arg(long, requires = "slice")]
    exr: Option<brdftab_tools::args::PathArg>,
    /// The --exr slice: `X,Y[:I0,I1,I2,I3]` — the stored axes along x and y, then an index for
    /// every stored axis (as many as `info` lists before the channels; those at X and Y are
    /// ignored); without them, the others at index 0.
    #[arg(long, requires = "exr")]
    slice: Option<String>,
    /// Write EXR channels as half floats instead of f32 (refused when a value exceeds ±65504;
    /// values below f16's smallest subnormal, 6e-8, become 0 and are counted in a note).
    #[arg(long, requires = "exr")]
    half: bool,
}

/// `brdftab export`.
pub fn run(a: ExportArgs) -> Result<()> {
    if a.npy.is_none() && a.exr.is_none() {
        return Err(Error::arg(
            "--npy/--exr",
            "give --npy OUT and/or --exr OUT --slice ...",
        ));
    }
    // Every output is checked before anything is written.
    if let Some(out) = &a.npy {
        brdftab_tools::output::check(out, "--npy", &["npy"])?;
    }
    if let Some(out) = &a.exr {
        brdftab_tools::output::check(out, "--exr", &["exr"])?;
    }
    let (path, name) = db::split_source(&*a.source)?;
    let s = Store::open(path)?;
    let t = match name {
        Some(n) => s.table(n)?,
        None => s.single()?,
    };
    // Tables with a grid use its layout (packed reciprocal tables expand, unstored nodes NaN).
    let grid = (!t.header().grid.is_null()).then(|| t.grid()).transpose()?;
    let off = grid.as_ref().map(tables::node_offset);
    let off_ref: export::NodeOffset<'_> = off
        .as_ref()
        .map(|f| f as &(dyn Fn(&[usize]) -> Option<usize> + Sync));
    // What the raw values are (as `info` says): not f_r for tables of f_r cos θo or
    // f_r cos θi cos θo, and without a calibration's factors.
    let stored = match &grid {
        Some(g) if g.calibration().is_some() => {
            format!(
                "{}, before the albedo calibration's factors",
                g.quantity().name()
            )
        }
        Some(g) => g.quantity().name().to_owned(),
        None => "fr".to_owned(),
    };
    let axes = t.header().shape.len().saturating_sub(1);
    let sl = match &a.slice {
        Some(s) => Some(slice(s, axes)?),
        None => None,
    };
    if let Some(out) = &a.npy {
        export::npy(&t, out, off_ref).map_err(|e| named(e, "--npy"))?;
        eprintln!(
            "wrote {out} (shape {:?}, float32; stored values: {stored})",
            t.header().shape
        );
    }
    if let (Some(out), Some(sl)) = (&a.exr, &sl) {
        let zeros = export::exr(&t, sl, off_ref, out, a.half).map_err(|e| named(e, "--exr"))?;
        eprintln!("wrote {out} (stored values: {stored})");
        if zeros > 0 {
            eprintln!(
                "note: {zeros} values below f16's smallest subnormal (6e-8) were written as 0"
            );
        }
    }
    Ok(())
}

/// The library names the file it writes `output`: here that is the flag that gave it.
fn named(e: Error, flag: &str) -> Error {
    match e {
        Error::InvalidArgument { name, msg } if name == "output" => Error::arg(flag, msg),
        Error::InvalidArgument { name, msg } if name == "half" => Error::arg("--half", msg),
        e => e,
    }
}

/// `--slice X,Y[:I0,..]` for a table of `axes` stored axes: the fixed indices, when given, are
/// one per axis (the library pads a shorter list with zeros, which hid a miscount).
fn slice(s: &str, axes: usize) -> Result<export::Slice> {
    if let Some((_, fixed)) = s.split_once(':') {
        let n = fixed.split(',').count();
        if n != axes {
            return Err(Error::arg(
                "--slice",
                format!(
                    "`{s}` gives {n} of the {axes} indices after `:`: one for every stored axis \
                     (those at X and Y are ignored), or none for index 0 on the others"
                ),
            ));
        }
    }
    export::Slice::parse(s, axes)
}

/// Arguments of `brdftab import`.
#[derive(Args)]
pub struct ImportArgs {
    /// A .npy file shaped as `export --npy` writes the --like table (float32 or float64, C
    /// order; NaN only where a packed table stores nothing): values before any calibration.
    array: std::path::PathBuf,
    /// The table (file or DB#NAME) whose grid — layout, symmetry, stored quantity, albedo
    /// calibration — the values are on.
    #[arg(long)]
    like: brdftab_tools::args::PathArg,
    /// Output: a table file (`.btdb`, replaced atomically) or DB#NAME.
    #[arg(short, long)]
    output: brdftab_tools::args::PathArg,
    /// The values are another material's: drop the --like table's albedo calibration (its
    /// factors were measured for the like table's own values).
    #[arg(long)]
    no_calibration: bool,
    #[command(flatten)]
    settings: SaveSettings,
}

/// `brdftab import`.
pub fn import(a: ImportArgs) -> Result<()> {
    let info = request::import_npy(&a.array, &a.like, &a.output, &a.settings, !a.no_calibration)?;
    let t = &info["tables"][0];
    let codec = t["codec"]["quant"].as_str().unwrap_or("?");
    eprintln!("wrote {} ({} values, codec {codec})", a.output, t["values"]);
    Ok(())
}
