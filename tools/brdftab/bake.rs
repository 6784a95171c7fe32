//! `bake`, and the bake flags `convert` and `db add` share: parsed into the library's
//! [`BakeRequest`], which makes every decision.

use brdftab::bake::{self, BakeReport, BakeRequest, BakeTarget, GridChoice, SymmetryChoice};
use brdftab::table::{Param, symmetry};
use brdftab::{Error, Result};
use clap::Args;

use crate::progress::Bar;
use crate::source;

/// The flags of a bake (`bake`, `convert` to a table, `db add`): each means one thing everywhere.
#[derive(Args, Clone)]
pub struct BakeFlags {
    /// Grid size preset: small, medium or large (default: a MERL file's own cells for MERL
    /// sources, for RGL files the smallest adaptive grid within 0.7 % (see --target-error),
    /// medium otherwise).
    #[arg(long)]
    pub preset: Option<String>,
    /// Full grid sizes θ1xφ1xθ2xφ2 (e.g. 90x360x90x360), `merl`, or `adaptive[:NHxNDxNP]`
    /// (halfdiff θh, θd and stored φd nodes placed by the source's own variation; isotropic
    /// bilateral sources; default 128x48x25, or what --target-error picks); overrides --preset.
    #[arg(long)]
    pub grid: Option<String>,
    /// Parameterization: halfdiff (default) or inout.
    #[arg(long)]
    pub param: Option<String>,
    /// Wavelengths in nm (comma separated) instead of the source's channels (model specs and
    /// RGL files).
    #[arg(long)]
    pub wavelengths: Option<String>,
    /// Symmetry reduction: auto (detect), declared (what the source says, unverified), none,
    /// or a list of isotropic,reciprocal,bilateral.
    #[arg(long, default_value = "auto")]
    pub symmetry: String,
    /// Relative tolerance of symmetry detection and verification (`--tolerance` is a deprecated
    /// alias).
    #[arg(long, alias = "tolerance", default_value_t = symmetry::DEFAULT_TOLERANCE)]
    pub symmetry_tolerance: f64,
    /// Bake even if the source breaks the chosen symmetry beyond the tolerance.
    #[arg(long)]
    pub force: bool,
    /// Codec: f32 (lossless), f16 (fails above ±65504), or log16 (relative error bound at any
    /// magnitude; `log16:1e-2` sets it). log16 by default: analytic lobes such as Cook-Torrance
    /// reach 1e5 at grazing angles, beyond f16.
    #[arg(long, default_value = "log16")]
    pub codec: String,
    /// log16 relative tolerance (default 1e-3).
    #[arg(long)]
    pub codec_tolerance: Option<f64>,
    /// log16 absolute floor (default: 1e-7 of each chunk's largest value).
    #[arg(long)]
    pub floor: Option<f64>,
    /// zstd level (1..=22; default 3 for f32/f16, 6 for log16).
    #[arg(long)]
    pub level: Option<i32>,
    /// Try every filter through zstd per chunk and keep the smallest (slower).
    #[arg(long)]
    pub exhaustive: bool,
    /// Table name inside the file (default: the output file's stem).
    #[arg(long)]
    pub name: Option<String>,
    /// Samples per axis and cell (box prefilter for very sharp lobes).
    #[arg(long, default_value_t = 1)]
    pub supersample: usize,
    /// Pick the smallest adaptive grid whose table meets this error: relative RMSE of
    /// f_r cos θi cos θo, both directions within 80°, on a mirror-centred product rule (e.g.
    /// `0.5%` or `0.005`); measured sources also within 3× it in the grazing band beyond 80°.
    /// Isotropic bilateral sources; not with given node counts.
    #[arg(long)]
    pub target_error: Option<String>,
}

impl BakeFlags {
    /// The library request these flags describe for `source`.
    pub fn request(&self, source: &str) -> Result<BakeRequest> {
        let grid = match (&self.grid, &self.preset) {
            (Some(g), _) => GridChoice::parse(g),
            (None, Some(p)) => GridChoice::parse(p),
            (None, None) => Ok(GridChoice::Default),
        }
        .map_err(|e| {
            flag(
                e,
                if self.grid.is_some() {
                    "--grid"
                } else {
                    "--preset"
                },
            )
        })?;
        let mut r = BakeRequest::new(source).grid(grid);
        r.param = self.param.as_deref().map(Param::parse).transpose()?;
        r.symmetry = SymmetryChoice::parse(&self.symmetry).map_err(|e| flag(e, "--symmetry"))?;
        r.symmetry_tolerance = self.symmetry_tolerance;
        r.force = self.force;
        r.codec = bake::codec(
            &self.codec,
            self.codec_tolerance,
            self.floor,
            self.level,
            self.exhaustive,
        )
        .map_err(|e| flag(e, "--codec"))?;
        r.name = self.name.clone();
        r.supersample = self.supersample;
        r.channels = source::channels(self.wavelengths.as_deref())?;
        r.target_error = self
            .target_error
            .as_deref()
            .map(parse_error_target)
            .transpose()?;
        Ok(r)
    }
}

/// `0.5%` or `0.005` as a fraction.
fn parse_error_target(s: &str) -> Result<f64> {
    let t = s.trim();
    let (num, scale) = match t.strip_suffix('%') {
        Some(n) => (n.trim(), 0.01),
        None => (t, 1.0),
    };
    match num.parse::<f64>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x * scale),
        _ => Err(Error::arg(
            "--target-error",
            format!("`{s}`: expected a positive error such as 0.5% or 0.005"),
        )),
    }
}

/// Names the CLI flag in an argument error of the library (which names its own field).
pub fn flag(e: Error, name: &str) -> Error {
    match e {
        Error::InvalidArgument { msg, .. } => Error::arg(name, msg),
        e => e,
    }
}

/// Arguments of `brdftab bake`.
#[derive(Args)]
pub struct BakeArgs {
    /// The source: a model spec (inline JSON or .json), a table, a MERL or RGL file.
    pub source: String,
    /// Output table file (`.btdb`).
    #[arg(short, long)]
    pub output: Option<String>,
    #[command(flatten)]
    pub flags: BakeFlags,
}

/// `brdftab bake`.
pub fn bake(a: BakeArgs) -> Result<()> {
    let out = a
        .output
        .clone()
        .ok_or_else(|| Error::arg("--output", "an output file is required"))?;
    run(&a.flags.request(&a.source)?, &BakeTarget::file(out)).map(drop)
}

/// Runs a request with a progress bar and prints what it did on stderr.
pub fn run(req: &BakeRequest, target: &BakeTarget) -> Result<BakeReport> {
    let r = req.run_with(target, &Bar::values()).map_err(|e| match e {
        Error::InvalidArgument { ref name, .. } if name == "target_error" => {
            flag(e, "--target-error")
        }
        e => e,
    })?;
    eprint!("{}", r.summary(&req.codec));
    Ok(r)
}
