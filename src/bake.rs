//! One way to turn any SOURCE into a stored table: [`BakeRequest`].
//!
//! `brdftab bake`, `convert`, `db add`, the demo, the accuracy suite, the Python package and the
//! C ABI all bake through this type, so the choices a bake makes — the grid, the symmetry and
//! its tolerance, the codec, the provenance recorded in the file — are made in one place and the
//! same for every host.
//!
//! ```
//! use brdftab::bake::{BakeRequest, BakeTarget};
//! use brdftab::table::presets::Preset;
//! # let dir = std::env::temp_dir().join(format!("brdftab-bake-doc-{}", std::process::id()));
//! # std::fs::create_dir_all(&dir)?;
//! let out = dir.join("lambert.btdb");
//! let report = BakeRequest::new(r#"{"model": "lambert", "kd": [0.1, 0.2, 0.3]}"#)
//!     .preset(Preset::Small)
//!     .run(&BakeTarget::file(out.to_str().unwrap()))?;
//! assert_eq!(report.name, "lambert");
//! assert_eq!(report.info["codec"]["quant"], "log16");
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::Path;
use std::time::Instant;

use crate::analysis::accuracy::{Region, Weight, compare_region};
use crate::analysis::fidelity::AlbedoError;
use crate::brdf::Brdf;
use crate::codec::{Codec, Quant};
use crate::error::{Error, Result};
use crate::measured::rgl_write;
use crate::progress::{Progress, Silent, Stage};
use crate::source::{self, OpenOptions, SourceKind};
use crate::spectrum::Channels;
use crate::store::{TableHeader, Writer, db, tables};
use crate::table::adaptive;
use crate::table::calibration::{
    ANISOTROPIC_AZIMUTHS, AlbedoReference, CalibrationOptions, calibrate,
};
use crate::table::presets::Preset;
use crate::table::target::{self, TargetSearch};
use crate::table::warp::WarpVar;
use crate::table::{
    BakeOptions, Grid, Interp, Mapping, Param, Quantity, Symmetry, Table, TabulatedBrdf,
    bake_chunks, symmetry,
};

/// The grid a bake samples on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GridChoice {
    /// The source's natural grid: a MERL file's own cells for MERL sources, for RGL files the
    /// smallest adaptive grid ([`GridChoice::Adaptive`]) that meets [`MEASURED_TARGET_ERROR`]
    /// (the medium preset when the file is not isotropic and bilateral within
    /// [`MEASURED_BILATERAL_TOLERANCE`]), the medium preset otherwise — but for a model whose
    /// medium table misses its albedo by more than [`PRESET_ALBEDO_TOLERANCE`], the adaptive
    /// grid of [`MODEL_FALLBACK_TARGET_ERROR`], calibrated (isotropic, bilateral models), or
    /// the medium table calibrated, whichever the check takes. With an error target
    /// ([`BakeRequest::target_error`]) any source gets the adaptive grid that meets it.
    #[default]
    Default,
    /// A size preset.
    Preset(Preset),
    /// Full axis sizes θ1 × φ1 × θ2 × φ2 (halfdiff: sqrt θh, uniform θd; inout: uniform).
    Sizes([usize; 4]),
    /// The MERL grid (90 θh × 90 θd × 180 φd cell centres). A MERL source keeps its cells.
    Merl,
    /// An adaptive `halfdiff` grid ([`crate::table::adaptive`]): θh, θd and φd warped by the
    /// source's own variation, with these node counts (θh, θd, stored φd), or without them
    /// the counts an error target picks ([`crate::table::target`]) or else
    /// [`adaptive::DEFAULT_NODES`].
    Adaptive(Option<[usize; 3]>),
}

impl std::str::FromStr for GridChoice {
    type Err = crate::Error;

    /// Parses `small`/`medium`/`large`, `merl`, sizes `θ1xφ1xθ2xφ2`, `adaptive` or
    /// `adaptive:NHxNDxNP` (θh, θd and stored φd nodes).
    fn from_str(s: &str) -> std::result::Result<Self, crate::Error> {
        let t = s.trim().to_ascii_lowercase();
        if let Some(rest) = t.strip_prefix("adaptive") {
            let Some(n) = rest.strip_prefix(':') else {
                return if rest.is_empty() {
                    Ok(GridChoice::Adaptive(None))
                } else {
                    Err(Error::arg(
                        "grid",
                        format!("`{s}`: expected adaptive[:NHxNDxNP]"),
                    ))
                };
            };
            let v = sizes(n)?;
            let n: [usize; 3] = v.try_into().map_err(|_| {
                Error::arg(
                    "grid",
                    format!("`{s}`: expected adaptive:NHxNDxNP (three sizes)"),
                )
            })?;
            return Ok(GridChoice::Adaptive(Some(n)));
        }
        match t.as_str() {
            "merl" => Ok(GridChoice::Merl),
            "default" => Ok(GridChoice::Default),
            "small" | "medium" | "large" => Ok(GridChoice::Preset(t.parse::<Preset>()?)),
            _ => {
                let v = sizes(&t)?;
                let sizes: [usize; 4] = v.try_into().map_err(|_| {
                    Error::arg(
                        "grid",
                        format!("`{s}`: expected four sizes θ1xφ1xθ2xφ2, merl, or a preset"),
                    )
                })?;
                Ok(GridChoice::Sizes(sizes))
            }
        }
    }
}

/// `AxBxC…` as sizes.
fn sizes(t: &str) -> Result<Vec<usize>> {
    t.split(['x', '×'])
        .map(|x| {
            x.trim()
                .parse::<usize>()
                .map_err(|_| Error::arg("grid", format!("`{x}` is not a size")))
        })
        .collect()
}

/// How far a measured source may break bilateral symmetry (largest relative difference over
/// [`symmetry::CHECK_PAIRS`] mirrored pairs) for an adaptive grid to assume it anyway: measured
/// isotropic materials meet it up to noise (RGL files: ≤ 1%), and the table's error reports
/// what assuming it costs.
pub const MEASURED_BILATERAL_TOLERANCE: f64 = 0.02;

/// The error target of an RGL measurement's default bake ([`BakeRequest::target_error`] when
/// none is given): 0.7 % relative RMSE of f_r cos θi cos θo within 80° (and
/// [`MEASURED_GRAZING_FACTOR`] times that in the grazing band), measured on the product rule of
/// [`crate::analysis::pair_rule`]. On the seven shipped files (BENCHMARKS.md, "Measured
/// materials") it keeps every table within 1 % inside 80° with a margin for the scatter of
/// random-pair checks, and every table file smaller than its RGL file.
pub const MEASURED_TARGET_ERROR: f64 = 0.007;

/// How far a model's default (medium preset) table may miss the source's directional albedo
/// (worst over [`PRESET_CHECK_THETAS_DEG`], a channel darker than 0.02 judged against 0.02; an
/// anisotropic source's albedo the mean over the light's [`ANISOTROPIC_AZIMUTHS`]) before the
/// default bake takes the adaptive, calibrated table of [`MODEL_FALLBACK_TARGET_ERROR`] or the
/// medium table calibrated instead: the fidelity bar of measured tables, 1 %. Sharp lobes need
/// the adaptive table — on the medium preset GGX α = 0.002 was 13.8 % off at 89° (and gained
/// energy: albedo 1.077 at 55°), α = 0.01 4.7 %, α = 0.02 2.4 % —, the max-Phong at n = 50
/// (1.5 % off at 89°, its adaptive table 6 % off over random pairs where the preset is 0.8 %)
/// and the anisotropic models (Ward α = (0.1, 0.3) 4.8 %, GGX (0.1, 0.4) 2.9 % at 89°: no
/// adaptive grid serves them) the calibration; GGX α ≥ 0.1, Cook-Torrance gold, Oren-Nayar and
/// the rest of the lecture's Phong family at n = 50 keep their preset tables.
pub const PRESET_ALBEDO_TOLERANCE: f64 = 0.01;

/// The incidence angles (degrees) at which [`PRESET_ALBEDO_TOLERANCE`] is checked: the
/// preset's errors grow towards grazing, and a sharp lobe's show at every angle.
pub const PRESET_CHECK_THETAS_DEG: [f64; 6] = [1.0, 30.0, 60.0, 80.0, 85.0, 89.0];

/// Random pairs on which a model's adaptive default table must not be worse than its preset's
/// ([`PRESET_ALBEDO_TOLERANCE`]).
pub const PRESET_CHECK_PAIRS: usize = 20_000;

/// How much larger (relative) than the preset's a candidate's error over
/// [`PRESET_CHECK_PAIRS`] random pairs may be for the preset check to take it (any error up to
/// 1 % passes): a calibration that brings an albedo 5 % off to within 0.1 % moves node values,
/// and with them that error a little — Ward α = (0.05, 0.2): 1.59 → 1.67 %, which "no larger"
/// refused, leaving its default 5.3 % off at 89° — while the candidates this guards against are
/// several times worse (the max-Phong's adaptive table: 0.78 → 6.0 %).
pub const PRESET_CHECK_RMSE_SLACK: f64 = 0.1;

/// The error target of a model's default bake when its preset table misses the albedo
/// ([`PRESET_ALBEDO_TOLERANCE`]): 0.2 % relative RMSE, as the Mitsuba plugin's JIT tables of
/// models (`brdftab.mitsuba.MODEL_TARGET_ERROR`), calibrated. A lobe too sharp for it gets the
/// largest adaptive grid (GGX α = 0.002: 2.2 % within 80°, 0.4 % albedo, against the preset's
/// 26 % and 14 %).
pub const MODEL_FALLBACK_TARGET_ERROR: f64 = 0.002;

/// The error-target search also judges the grazing band (a direction beyond 80°), against this
/// multiple of the target — for every table but one of a measurement's own f_r: the fidelity
/// bars are 1 % within 80° and 3 % in the band.
pub const MEASURED_GRAZING_FACTOR: f64 = 3.0;

/// What a bake will do with a source: the grid, why the symmetry differs from what the source
/// declares, and whether the symmetry is assumed rather than verified.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The grid to bake on.
    pub grid: Grid,
    /// A note on the symmetry (detection vs declaration, or an assumption).
    pub note: Option<String>,
    /// The bake does not verify the symmetry (forced, declared or assumed).
    pub force: bool,
    /// The symmetry is assumed for a measured source (the note says by how much it is broken;
    /// the bake's own violation report would repeat it).
    pub assumed: bool,
    /// The error-target search that chose the grid, when the request has a target.
    pub search: Option<TargetSearch>,
    /// The source's albedo the table is calibrated to, when it is
    /// ([`crate::table::calibration`]).
    pub albedo: Option<AlbedoReference>,
}

/// The table a model's default bake takes instead of the medium preset's
/// ([`BakeRequest::preset_misses`]).
enum Fallback {
    /// The adaptive, calibrated table of [`MODEL_FALLBACK_TARGET_ERROR`]: the bake runs as the
    /// request with that target would.
    Adaptive,
    /// The medium preset's table, calibrated (this one, as the check baked it).
    CalibratedPreset(Box<Table>),
}

/// What the preset's check ([`BakeRequest::preset_misses`]) decided.
enum Checked {
    /// The check does not apply to this request.
    Unchecked,
    /// The preset's table meets the albedo: the table the check baked, and its bake's stats
    /// (the bake takes it as its own instead of baking the same grid again).
    Kept(Box<(Table, crate::table::fill::BakeStats)>),
    /// Another table instead, and why.
    Instead(Fallback, String),
    /// The preset's table misses the albedo and no other table was taken: the preset's table
    /// is baked as without the check, and the note says by how much it misses.
    Missed(String),
}

/// `why` before the bake's own note, if it has one.
fn with_note(why: String, note: Option<String>) -> String {
    match note {
        Some(n) => format!("{why}; {n}"),
        None => why,
    }
}

/// The symmetry a bake reduces by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SymmetryChoice {
    /// Detect the symmetries the source meets within the symmetry tolerance.
    #[default]
    Auto,
    /// Exactly these (verified against the source unless forced).
    Exactly(Symmetry),
    /// What the source declares ([`Symmetry::from_flags`]), not verified: for measured data,
    /// which declares the symmetries of the material but meets them only up to noise.
    Declared,
}

impl std::str::FromStr for SymmetryChoice {
    type Err = crate::Error;

    /// Parses `auto`, `declared`, `none`, `all` or a list of `isotropic,reciprocal,bilateral`.
    fn from_str(s: &str) -> std::result::Result<Self, crate::Error> {
        match s.trim() {
            "auto" => Ok(SymmetryChoice::Auto),
            "declared" => Ok(SymmetryChoice::Declared),
            s => Ok(SymmetryChoice::Exactly(s.parse::<Symmetry>()?)),
        }
    }
}

/// Where a bake writes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BakeTarget {
    /// A single-table brdftab file, replaced atomically.
    File(String),
    /// Table `name` of database `path` (created if absent).
    Db {
        /// The database file.
        path: String,
        /// The table's name.
        name: String,
        /// Replace a table of that name (otherwise an existing name is an error).
        replace: bool,
    },
    /// A raw (uncompressed f32) table file.
    Raw(String),
    /// A MERL `.binary` file: the source resampled as MERL cell means, in RGB (the grid,
    /// symmetry and codec of the request do not apply; the format fixes them).
    Merl(String),
}

impl BakeTarget {
    /// A single-table file.
    pub fn file(path: impl Into<String>) -> BakeTarget {
        BakeTarget::File(path.into())
    }

    /// A new table of a database.
    pub fn db(path: impl Into<String>, name: impl Into<String>) -> BakeTarget {
        BakeTarget::Db {
            path: path.into(),
            name: name.into(),
            replace: false,
        }
    }

    /// Reads an output string the way `convert` does: `DB#NAME` is a database entry, a `.btdb`
    /// file a single-table file (or, with `name`, an entry of that database), anything else a
    /// raw table file.
    pub fn parse(output: &str, name: Option<&str>, replace: bool) -> Result<BakeTarget> {
        let (path, entry) = crate::store::name::parse_source("output", output)?;
        Ok(
            match (entry.or(name), path.to_ascii_lowercase().ends_with(".btdb")) {
                (Some(n), _) => BakeTarget::Db {
                    path: path.into(),
                    name: n.into(),
                    replace,
                },
                (None, true) => BakeTarget::File(path.into()),
                (None, false) => BakeTarget::Raw(path.into()),
            },
        )
    }

    /// The file written.
    pub fn path(&self) -> &str {
        match self {
            BakeTarget::File(p)
            | BakeTarget::Raw(p)
            | BakeTarget::Merl(p)
            | BakeTarget::Db { path: p, .. } => p,
        }
    }
}

/// Everything a bake decides, in one place. Builder-style setters; `new(source)` starts from the
/// defaults every host shares (grid [`GridChoice::Default`], symmetry detected at 1e-3, codec
/// log16 ≤ 1e-3 at zstd level 6).
#[derive(Debug, Clone)]
pub struct BakeRequest {
    /// The SOURCE (see [`crate::source`]).
    pub source: String,
    /// The grid.
    pub grid: GridChoice,
    /// The parameterization (`None`: halfdiff).
    pub param: Option<Param>,
    /// The symmetry reduction.
    pub symmetry: SymmetryChoice,
    /// Relative tolerance of symmetry detection and verification.
    pub symmetry_tolerance: f64,
    /// Bake even when the source breaks the chosen symmetry beyond the tolerance.
    pub force: bool,
    /// The codec (quantization, its tolerance, zstd level).
    pub codec: Codec,
    /// The table's name (default: the output file's stem).
    pub name: Option<String>,
    /// Samples per stored axis and cell (box prefilter; 1 = node values).
    pub supersample: usize,
    /// Channels for model specs and RGL files (`None`: the source's own).
    pub channels: Option<Channels>,
    /// Random pairs for the accuracy report of the written table against its source (0 = none).
    pub accuracy_pairs: usize,
    /// Interpolation of the accuracy report.
    pub accuracy_interp: Interp,
    /// Pick the smallest adaptive grid whose table meets this error (relative RMSE of
    /// f_r cos θi cos θo within 80°; [`crate::table::target`]) instead of fixed node counts.
    /// Applies to adaptive grids: RGL files by default, any isotropic bilateral source with
    /// [`GridChoice::Adaptive`]`(None)` or [`GridChoice::Default`].
    pub target_error: Option<f64>,
    /// What the table stores (`None`: [`Quantity::FrCosOut`] for measured sources, RGL files
    /// and MERL files resampled to an error target, [`Quantity::FrCosCos`] for models whose f_r
    /// is unbounded at the horizon ([`Brdf::grows_at_horizon`]), [`Quantity::Fr`] otherwise;
    /// see [`Quantity`] for why).
    pub quantity: Option<Quantity>,
    /// Pin the table's directional albedo to the source's ([`crate::table::calibration`]) on
    /// tables that store a projected quantity and do not fold by reciprocity (measured sources
    /// by default), on adaptive tables of models (one symmetric factor: they stay reciprocal)
    /// and on a model's default medium table where it misses the albedo
    /// ([`PRESET_ALBEDO_TOLERANCE`]). True by default; false also turns that check off.
    pub calibrate: bool,
}

impl BakeRequest {
    /// A request with the defaults for `source`.
    pub fn new(source: impl Into<String>) -> BakeRequest {
        BakeRequest {
            source: source.into(),
            grid: GridChoice::Default,
            param: None,
            symmetry: SymmetryChoice::Auto,
            symmetry_tolerance: symmetry::DEFAULT_TOLERANCE,
            force: false,
            codec: default_codec(),
            name: None,
            supersample: 1,
            channels: None,
            accuracy_pairs: 0,
            accuracy_interp: Interp::Linear,
            target_error: None,
            quantity: None,
            calibrate: true,
        }
    }

    /// Sets whether the table's albedo is calibrated (see [`BakeRequest::calibrate`]).
    pub fn calibrate(mut self, on: bool) -> BakeRequest {
        self.calibrate = on;
        self
    }

    /// Sets what the table stores (see [`BakeRequest::quantity`]).
    pub fn quantity(mut self, q: Quantity) -> BakeRequest {
        self.quantity = Some(q);
        self
    }

    /// What the table of `src` (this request's source, opened) stores: the request's own
    /// choice, or the default for its source — f_r cos θo for measured data, f_r cos θi cos θo
    /// for a model whose f_r is unbounded at the horizon ([`Brdf::grows_at_horizon`]), f_r
    /// otherwise.
    pub fn effective_quantity(&self, src: &dyn Brdf) -> Quantity {
        self.quantity
            .unwrap_or(match source::classify(&self.source) {
                SourceKind::Rgl => Quantity::FrCosOut,
                // Resampled onto an adaptive grid (an error target): bounded at the horizon
                // like an RGL file's values. Its own cells are copied as they are (f_r).
                SourceKind::Merl if self.adaptive() => Quantity::FrCosOut,
                _ if src.grows_at_horizon() => Quantity::FrCosCos,
                _ => Quantity::Fr,
            })
    }

    /// Sets the error target (see [`BakeRequest::target_error`]).
    pub fn target_error(mut self, e: f64) -> BakeRequest {
        self.target_error = Some(e);
        self
    }

    /// Sets the grid to a preset.
    pub fn preset(mut self, p: Preset) -> BakeRequest {
        self.grid = GridChoice::Preset(p);
        self
    }

    /// Sets the grid.
    pub fn grid(mut self, g: GridChoice) -> BakeRequest {
        self.grid = g;
        self
    }

    /// Sets the parameterization.
    pub fn param(mut self, p: Param) -> BakeRequest {
        self.param = Some(p);
        self
    }

    /// Sets the symmetry.
    pub fn symmetry(mut self, s: SymmetryChoice) -> BakeRequest {
        self.symmetry = s;
        self
    }

    /// Sets the codec.
    pub fn codec(mut self, c: Codec) -> BakeRequest {
        self.codec = c;
        self
    }

    /// Sets the table name.
    pub fn name(mut self, n: impl Into<String>) -> BakeRequest {
        self.name = Some(n.into());
        self
    }

    /// Sets the channels.
    pub fn channels(mut self, c: Channels) -> BakeRequest {
        self.channels = Some(c);
        self
    }

    /// Reports the accuracy of the written table on `pairs` random pairs.
    pub fn accuracy(mut self, pairs: usize) -> BakeRequest {
        self.accuracy_pairs = pairs;
        self
    }

    /// Opens the source as the request says.
    pub fn open_source(&self) -> Result<Box<dyn Brdf + Send + Sync>> {
        let opts = OpenOptions {
            channels: self.channels.clone(),
            ..OpenOptions::default()
        };
        source::open_with(&self.source, &opts)
    }

    /// The symmetry this request reduces `src` by, with a note when detection disagrees with
    /// what the source declares.
    pub fn resolve_symmetry(&self, src: &dyn Brdf) -> (Symmetry, Option<String>) {
        match self.symmetry {
            SymmetryChoice::Exactly(s) => (s, None),
            SymmetryChoice::Declared => (Symmetry::from_flags(src.flags()), None),
            SymmetryChoice::Auto => {
                let d = symmetry::detect(src, self.symmetry_tolerance);
                let declared = Symmetry::from_flags(src.flags());
                let note = (d != declared)
                    .then(|| format!("the source declares {declared}, detected {d}; using {d}"));
                (d, note)
            }
        }
    }

    /// True when this request bakes `src` on an adaptive grid: asked for, or the default grid
    /// of an RGL measurement.
    fn adaptive(&self) -> bool {
        match self.grid {
            GridChoice::Adaptive(_) => true,
            GridChoice::Default => {
                (source::classify(&self.source) == SourceKind::Rgl || self.target_error.is_some())
                    && self.param.is_none_or(|p| p == Param::HalfDiff)
                    && self.supersample == 1
            }
            _ => false,
        }
    }

    /// The grid, symmetry note and verification this request uses for `src`.
    pub fn plan(&self, src: &dyn Brdf) -> Result<Plan> {
        self.plan_with(src, &Silent)
    }

    /// [`plan`](Self::plan), reporting an error-target search (about a second) on `progress`.
    pub fn plan_with(&self, src: &dyn Brdf, progress: &dyn Progress) -> Result<Plan> {
        let (mut sym, mut note) = self.resolve_symmetry(src);
        let quantity = self.effective_quantity(src);
        if quantity == Quantity::FrCosOut && sym.reciprocal {
            // f_r cos θo differs between a pair and its swap: the table cannot fold by it.
            sym.reciprocal = false;
        }
        let mut force = self.force || self.symmetry == SymmetryChoice::Declared;
        let mut assumed = false;
        if self.adaptive()
            && sym.isotropic
            && !sym.bilateral
            && self.symmetry == SymmetryChoice::Auto
        {
            let (v, _) = symmetry::violation(src, 2, symmetry::CHECK_PAIRS, 0x5EED);
            if v <= MEASURED_BILATERAL_TOLERANCE {
                sym.bilateral = true;
                force = true;
                assumed = true;
                note = Some(format!(
                    "bilateral symmetry assumed (largest relative violation {:.2}%, within {}%); \
                     using {sym}",
                    v * 100.0,
                    MEASURED_BILATERAL_TOLERANCE * 100.0
                ));
            }
        }
        let albedo = if self.calibrate
            && ((quantity != Quantity::Fr && !sym.reciprocal) || self.calibrates_model_table())
        {
            progress.note("integrating the source's albedo");
            Some(AlbedoReference::new(src, &CalibrationOptions::default())?)
        } else {
            None
        };
        let mut search = None;
        let grid = match self.grid {
            GridChoice::Default
                if self.adaptive()
                    && !(sym.isotropic && sym.bilateral)
                    && self.target_error.is_none() =>
            {
                // Not a source an adaptive grid serves: the preset, as for any other.
                Preset::Medium.grid(self.param, sym, src.channels().clone())?
            }
            _ => match self.effective_target() {
                Some(e) => {
                    let (g, s) = self.search_grid(src, sym, e, albedo.as_ref(), force, progress)?;
                    search = Some(s);
                    g
                }
                None => self.resolve_grid(src, sym)?,
            },
        };
        Ok(Plan {
            grid: grid.with_quantity(quantity)?,
            note,
            force,
            assumed,
            search,
            albedo,
        })
    }

    /// Why a model's default table is not the medium preset's, and which it is instead:
    /// `Some` when the request leaves the grid to the library, the source is a model spec whose
    /// preset table would not be calibrated anyway, and that table misses the source's albedo
    /// by more than [`PRESET_ALBEDO_TOLERANCE`] at one of [`PRESET_CHECK_THETAS_DEG`] (for an
    /// anisotropic source the mean over the light's [`ANISOTROPIC_AZIMUTHS`], which is what a
    /// calibration can pin; a bake of the preset and its albedos, ~0.3 s). The candidates, in
    /// this order, each kept only if its albedo is closer and its error over
    /// [`PRESET_CHECK_PAIRS`] random pairs at most [`PRESET_CHECK_RMSE_SLACK`] larger (or within
    /// 1 %): for an isotropic, bilateral
    /// source the adaptive, calibrated table of [`MODEL_FALLBACK_TARGET_ERROR`] (one more bake,
    /// ~1 s), then the preset's own table calibrated. The first within the tolerance is taken,
    /// else the closest; when neither is kept the preset's table stays ([`Checked::Missed`]:
    /// the bake's note says by how much it misses).
    fn preset_misses(&self, src: &dyn Brdf, progress: &dyn Progress) -> Result<Checked> {
        let quantity = self.effective_quantity(src);
        if !(self.grid == GridChoice::Default
            && self.target_error.is_none()
            && self.calibrate
            && self.supersample == 1
            && self.param.is_none_or(|p| p == Param::HalfDiff)
            && source::classify(&self.source) == SourceKind::Spec)
        {
            return Ok(Checked::Unchecked);
        }
        let (mut sym, _) = self.resolve_symmetry(src);
        if quantity == Quantity::FrCosOut {
            // As `plan_with`: f_r cos θo cannot fold by reciprocity.
            sym.reciprocal = false;
        }
        if quantity != Quantity::Fr && !sym.reciprocal {
            // Calibrated by default already (`plan_with`): its albedo is pinned.
            return Ok(Checked::Unchecked);
        }
        let _stage = Stage::begin(progress, "checking the preset's albedo", 0);
        let grid = Preset::Medium
            .grid(Some(Param::HalfDiff), sym, src.channels().clone())?
            .with_quantity(quantity)?;
        let opts = BakeOptions {
            tolerance: self.symmetry_tolerance,
            force: self.force || self.symmetry == SymmetryChoice::Declared,
            ..BakeOptions::default()
        };
        let (preset, stats) = crate::table::bake(src, &grid, &opts)?;
        let fid = crate::analysis::fidelity::FidelityOptions {
            albedo_thetas_deg: PRESET_CHECK_THETAS_DEG.to_vec(),
            albedo_phi: 64,
            albedo_order: 6,
            albedo_azimuths: if sym.isotropic {
                1
            } else {
                ANISOTROPIC_AZIMUTHS
            },
            ..Default::default()
        };
        let albedo = |t: &dyn Brdf| crate::analysis::fidelity::albedo_error(t, src, &fid);
        // Over random pairs, the same pairs for every table (half near the mirror direction,
        // weighted back to uniform, `compare_region`: uniform pairs alone made a sharp lobe's
        // figure depend on whether one landed on its peak): f_r cos θi, but f_r cos θi cos θo
        // for a table that stores it (Ward's f_r ∝ 1/√(cos θi cos θo): f_r cos θi has no finite
        // RMS, and the pairs nearest the horizon would decide).
        let weight = if quantity == Quantity::FrCosCos {
            Weight::CosInCosOut
        } else {
            Weight::CosIn
        };
        let rmse = |t: &dyn Brdf| {
            let whole = Region::Cap(std::f64::consts::FRAC_PI_2);
            compare_region(t, src, PRESET_CHECK_PAIRS, 1, whole, weight).map(|a| a.rel_rmse)
        };
        let plain = TabulatedBrdf::from_table(preset.clone());
        let e = albedo(&plain)?;
        if e.worst <= PRESET_ALBEDO_TOLERANCE {
            return Ok(Checked::Kept(Box::new((preset, stats))));
        }
        let rp = rmse(&plain)?;
        drop(plain);
        let mut best: Option<(Fallback, AlbedoError)> = None;
        let mut consider = |f: Fallback, a: AlbedoError, r: f64| {
            let bound = (rp * (1.0 + PRESET_CHECK_RMSE_SLACK)).max(0.01);
            if a.worst < best.as_ref().map_or(e.worst, |b| b.1.worst) && r <= bound {
                best = Some((f, a));
            }
            best.as_ref()
                .is_some_and(|b| b.1.worst <= PRESET_ALBEDO_TOLERANCE)
        };
        // The adaptive table first: it resolves a lobe the preset's nodes cannot (GGX
        // α = 0.002: 2.2 % against 26 % within 80°), which a calibration would only rescale.
        // A lobe whose f_r spikes at the grazing mirror pair (the max-Phong's
        // 1/max(cos θi, cos θo)) is followed by the preset's 180 θd nodes and not by the
        // adaptive grid (over random pairs 0.78 → 6.0 %), and is left to the calibration.
        let mut done = false;
        if sym.isotropic && sym.bilateral {
            let (adaptive, _) = self
                .clone()
                .target_error(MODEL_FALLBACK_TARGET_ERROR)
                .table_of(src, &Silent)?;
            let adaptive = TabulatedBrdf::from_table(adaptive);
            done = consider(Fallback::Adaptive, albedo(&adaptive)?, rmse(&adaptive)?);
        }
        if !done {
            // A reciprocal table takes one factor, fitted to the light's albedo (the viewer's
            // is the same for a reciprocal source).
            let copts = CalibrationOptions {
                two_sided: !sym.reciprocal,
                ..CalibrationOptions::default()
            };
            let reference = AlbedoReference::new(src, &copts)?;
            let calibrated = calibrate(preset, &reference)?;
            let tab = TabulatedBrdf::from_table(calibrated.clone());
            let (a, r) = (albedo(&tab)?, rmse(&tab)?);
            drop(tab);
            consider(Fallback::CalibratedPreset(Box::new(calibrated)), a, r);
        }
        let azimuths = if sym.isotropic {
            ""
        } else {
            " (mean over the light's azimuths)"
        };
        let Some((f, a)) = best else {
            // The preset stays (its table was spent on the calibration's candidate), but the
            // bake says that it misses.
            return Ok(Checked::Missed(format!(
                "the medium preset's table missed the albedo{azimuths} by {:.1} % at {}°; no \
                 other table was closer without a larger error over random pairs, so it stays",
                100.0 * e.worst,
                e.theta_deg
            )));
        };
        {
            let instead = match f {
                Fallback::Adaptive => format!(
                    "baked to an error target of {} % instead",
                    100.0 * MODEL_FALLBACK_TARGET_ERROR
                ),
                Fallback::CalibratedPreset(_) => "calibrated it".to_owned(),
            };
            let why = format!(
                "the medium preset's table missed the albedo{azimuths} by {:.1} % at {}°: \
                 {instead} ({:.2} % at {}°)",
                100.0 * e.worst,
                e.theta_deg,
                100.0 * a.worst,
                a.theta_deg
            );
            Ok(Checked::Instead(f, why))
        }
    }

    /// The preset's table the check baked ([`Checked::Kept`]) as this bake's table and report,
    /// when it is what the bake would make — the planned grid, not calibrated, from the source
    /// itself —, so the check's bake is not repeated (~0.2 s); `None` otherwise.
    fn reuse_checked(
        &self,
        src: &dyn Brdf,
        (table, stats): (Table, crate::table::fill::BakeStats),
        progress: &dyn Progress,
        t0: Instant,
    ) -> Result<Option<(Table, BakeReport)>> {
        if src.bake_source().and_then(|b| b.bake_view()).is_some() {
            return Ok(None);
        }
        let plan = self.plan_with(src, progress)?;
        if plan.albedo.is_some() || &plan.grid != table.grid() {
            return Ok(None);
        }
        let mut report = self.report_for(src, &plan.grid, plan.note, t0, false);
        report.forced = stats.forced.filter(|_| !plan.assumed);
        report.target = plan.search;
        Ok(Some((table, report)))
    }

    /// The error target this request bakes to: its own, or [`MEASURED_TARGET_ERROR`] for an
    /// RGL file on the default grid.
    pub fn effective_target(&self) -> Option<f64> {
        self.target_error.or_else(|| {
            (self.grid == GridChoice::Default
                && self.adaptive()
                && source::classify(&self.source) == SourceKind::Rgl)
                .then_some(MEASURED_TARGET_ERROR)
        })
    }

    /// The smallest adaptive grid meeting error `e` ([`crate::table::target::search`]).
    fn search_grid(
        &self,
        src: &dyn Brdf,
        sym: Symmetry,
        e: f64,
        albedo: Option<&AlbedoReference>,
        force: bool,
        progress: &dyn Progress,
    ) -> Result<(Grid, TargetSearch)> {
        if !self.adaptive() {
            return Err(Error::arg(
                "target_error",
                "an error target picks the node counts of an adaptive halfdiff grid; this \
                 request bakes on a fixed grid",
            ));
        }
        if matches!(self.grid, GridChoice::Adaptive(Some(_))) {
            return Err(Error::arg(
                "target_error",
                "an error target picks the node counts itself; do not give them too",
            ));
        }
        if !(sym.isotropic && sym.bilateral) {
            return Err(Error::arg(
                "target_error",
                format!("an error target needs an isotropic, bilateral source (it is {sym})"),
            ));
        }
        let mut opts = target::TargetOptions::new(e);
        if self.reaches_horizon(src) {
            opts = opts.with_grazing(MEASURED_GRAZING_FACTOR);
        }
        target::search(
            src,
            sym,
            &self.adaptive_options(src, adaptive::DEFAULT_NODES),
            &opts,
            albedo,
            force,
            progress,
        )
    }

    /// Whether this request calibrates an adaptive table of a model (or other unmeasured
    /// source): the error target's search judges f_r's RMSE, which weighs the last degrees
    /// above the horizon little, and the directional albedo there escaped it (GGX copper
    /// α = 0.1 at a 0.2 % target: 1.6 % at 88°, the medium preset 0.35 %). A symmetric
    /// calibration (k(θi) k(θo), [`crate::table::calibration`]) pins it and keeps the table
    /// reciprocal. Presets stay uncalibrated (their albedo is within 0.5 % already) but where
    /// a model's default check finds one off ([`PRESET_ALBEDO_TOLERANCE`]).
    fn calibrates_model_table(&self) -> bool {
        self.calibrate && self.adaptive() && !source::classify(&self.source).is_measured()
    }

    /// Whether this request's adaptive grids of `src` place θh nodes up to the horizon and its
    /// error target judges the grazing band: every table but one of a measurement's own f_r,
    /// which grows like 1/cos θ there (a measured source's default table stores f_r cos θo).
    /// A model's bounded f_r is judged over the whole domain: on grids stopping at θh = 85°
    /// and judged within 80° only, GGX copper's table was 6.4 % off in the grazing band and
    /// 7 % in albedo at 89°, Cook-Torrance gold's 12 % and 18 % (BENCHMARKS.md).
    fn reaches_horizon(&self, src: &dyn Brdf) -> bool {
        self.effective_quantity(src) != Quantity::Fr
            || !source::classify(&self.source).is_measured()
    }

    /// The options of this request's adaptive grids of `nodes`.
    fn adaptive_options(&self, src: &dyn Brdf, nodes: [usize; 3]) -> adaptive::AdaptiveOptions {
        let horizon = self.reaches_horizon(src);
        adaptive::AdaptiveOptions {
            nodes,
            quantity: self.effective_quantity(src),
            // Judged to the horizon, with θh nodes up to it.
            cap_deg: if horizon { 90.0 } else { 85.0 },
            h_var: if horizon {
                WarpVar::QuarterPower
            } else {
                WarpVar::SqrtSine
            },
            ..Default::default()
        }
    }

    /// The grid this request bakes `src` on.
    pub fn resolve_grid(&self, src: &dyn Brdf, sym: Symmetry) -> Result<Grid> {
        let ch = src.channels().clone();
        if self.adaptive() {
            let nodes = match self.grid {
                GridChoice::Adaptive(Some(n)) => n,
                _ => adaptive::DEFAULT_NODES,
            };
            if self.param.is_some_and(|p| p != Param::HalfDiff) {
                return Err(Error::arg("grid", "an adaptive grid is halfdiff"));
            }
            return adaptive::adaptive_grid(src, sym, &self.adaptive_options(src, nodes));
        }
        match self.grid {
            GridChoice::Merl => Grid::merl(ch).with_symmetry(sym),
            GridChoice::Sizes(s) => {
                let p = self.param.unwrap_or(Param::HalfDiff);
                let m = match p {
                    Param::HalfDiff => [Mapping::Sqrt, Mapping::Uniform],
                    Param::InOut => [Mapping::Uniform, Mapping::Uniform],
                };
                Grid::with_sizes(p, s, m, ch, sym)
            }
            GridChoice::Preset(p) => p.grid(self.param, sym, ch),
            GridChoice::Default | GridChoice::Adaptive(_) => {
                Preset::Medium.grid(self.param, sym, ch)
            }
        }
    }

    /// True when the request keeps a MERL file's own cells instead of resampling it.
    fn keeps_merl_cells(&self) -> bool {
        self.target_error.is_none()
            && source::classify(&self.source) == SourceKind::Merl
            && matches!(self.grid, GridChoice::Default | GridChoice::Merl)
            && self.param.is_none_or(|p| p == Param::HalfDiff)
            && self.supersample == 1
    }

    /// Bakes into memory: the table and what the bake did.
    pub fn table(&self, progress: &dyn Progress) -> Result<(Table, BakeReport)> {
        let src = self.open_source()?;
        self.table_of(src.as_ref(), progress)
    }

    /// Bakes an already opened source (for callers that also use it, e.g. to compare).
    pub fn table_of(&self, src: &dyn Brdf, progress: &dyn Progress) -> Result<(Table, BakeReport)> {
        let t0 = Instant::now();
        match self.preset_misses(src, progress)? {
            Checked::Instead(Fallback::Adaptive, why) => {
                let (table, mut report) = self
                    .clone()
                    .target_error(MODEL_FALLBACK_TARGET_ERROR)
                    .table_of(src, progress)?;
                report.symmetry_note = Some(with_note(why, report.symmetry_note));
                Ok((table, report))
            }
            Checked::Instead(Fallback::CalibratedPreset(table), why) => {
                let report = self.calibrated_preset_report(src, &table, why, t0);
                Ok((*table, report))
            }
            Checked::Kept(kept) => match self.reuse_checked(src, *kept, progress, t0)? {
                Some(built) => Ok(built),
                None => self.table_unchecked(src, progress),
            },
            Checked::Missed(why) => {
                let (table, mut report) = self.table_unchecked(src, progress)?;
                report.symmetry_note = Some(with_note(why, report.symmetry_note));
                Ok((table, report))
            }
            Checked::Unchecked => self.table_unchecked(src, progress),
        }
    }

    /// The report of a default bake that took the medium preset's table, calibrated.
    fn calibrated_preset_report(
        &self,
        src: &dyn Brdf,
        table: &Table,
        why: String,
        t0: Instant,
    ) -> BakeReport {
        let (_, note) = self.resolve_symmetry(src);
        self.report_for(src, table.grid(), Some(with_note(why, note)), t0, false)
    }

    /// [`table_of`](Self::table_of) without the preset's check.
    fn table_unchecked(
        &self,
        src: &dyn Brdf,
        progress: &dyn Progress,
    ) -> Result<(Table, BakeReport)> {
        let t0 = Instant::now();
        if self.keeps_merl_cells() {
            let table = crate::measured::MerlBrdf::open(&self.source)?.to_table();
            let report = self.report_for(src, table.grid(), None, t0, true);
            return Ok((table, report));
        }
        // What the bake samples ([`BakeSource::bake_view`](crate::brdf::BakeSource::bake_view)); the report describes the source.
        let view = src.bake_source().and_then(|b| b.bake_view());
        let bake_src: &dyn Brdf = view.as_deref().unwrap_or(src);
        let Plan {
            grid,
            note,
            force,
            assumed,
            search,
            albedo,
        } = self.plan_with(bake_src, progress)?;
        let (mut table, r) = {
            let _stage = Stage::begin(progress, "baking", grid.stored_values() as u64);
            let set = |done: u64, _total: u64| progress.set(done);
            let opts = self.bake_options(&set, force);
            crate::table::bake(bake_src, &grid, &opts)?
        };
        // A lazily read table source whose chunk failed gave zeros: refuse them.
        src.health()?;
        if let Some(a) = &albedo {
            let _stage = Stage::begin(progress, "calibrating albedo", 0);
            table = calibrate(table, a)?;
            src.health()?;
        }
        let grid = table.grid().clone();
        let mut report = self.report_for(src, &grid, note, t0, false);
        report.forced = r.forced.filter(|_| !assumed);
        report.target = search;
        Ok((table, report))
    }

    fn bake_options<'a>(
        &self,
        set: crate::table::fill::Progress<'a>,
        force: bool,
    ) -> BakeOptions<'a> {
        BakeOptions {
            supersample: self.supersample,
            force,
            tolerance: self.symmetry_tolerance,
            progress: Some(set),
            ..BakeOptions::default()
        }
    }

    fn report_for(
        &self,
        src: &dyn Brdf,
        grid: &Grid,
        note: Option<String>,
        t0: Instant,
        merl_cells: bool,
    ) -> BakeReport {
        BakeReport {
            source: src.describe(),
            name: String::new(),
            output: String::new(),
            grid: grid.clone(),
            values: grid.stored_values() as u64,
            seconds: t0.elapsed().as_secs_f64(),
            symmetry_note: note,
            forced: None,
            merl_cells,
            accuracy: None,
            info: serde_json::Value::Null,
            target: None,
            written: None,
        }
    }

    /// Bakes and writes to `target` with provenance; returns what the bake did and what `info`
    /// reports of the written table. Chunks stream into the file as they are baked (bounded
    /// memory), except for raw targets and MERL cells, which are built in memory.
    pub fn run(&self, target: &BakeTarget) -> Result<BakeReport> {
        self.run_with(target, &Silent)
    }

    /// [`run`](Self::run), reporting progress.
    pub fn run_with(&self, target: &BakeTarget, progress: &dyn Progress) -> Result<BakeReport> {
        self.refuse_overwrite(target)?;
        let name = match (target, &self.name) {
            (BakeTarget::Db { name, .. }, _) => name.clone(),
            (_, Some(n)) => n.clone(),
            (t, None) => stem(t.path()),
        };
        // Before any work (and before a `File` target's old file is removed): a table name
        // the store would refuse ([`crate::store::name`]).
        if matches!(target, BakeTarget::File(_) | BakeTarget::Db { .. }) {
            crate::store::name::check("name", &name)?;
        }
        let src = self.open_source()?;
        let t0 = Instant::now();
        // A model the medium preset misses is baked as the request with an error target would
        // be (the whole path: calibrated, built whole), or gets the check's calibrated table;
        // one the preset serves gets the table the check baked.
        let mut checked = None;
        let mut missed = None;
        if !matches!(target, BakeTarget::Merl(_)) {
            match self.preset_misses(src.as_ref(), progress)? {
                Checked::Instead(Fallback::Adaptive, why) => {
                    let mut report = self
                        .clone()
                        .target_error(MODEL_FALLBACK_TARGET_ERROR)
                        .run_with(target, progress)?;
                    report.symmetry_note = Some(with_note(why, report.symmetry_note));
                    return Ok(report);
                }
                Checked::Instead(Fallback::CalibratedPreset(table), why) => {
                    let report = self.calibrated_preset_report(src.as_ref(), &table, why, t0);
                    checked = Some((*table, report));
                }
                Checked::Kept(kept) => {
                    checked = self.reuse_checked(src.as_ref(), *kept, progress, t0)?;
                }
                Checked::Missed(why) => missed = Some(why),
                Checked::Unchecked => {}
            }
        }
        if let BakeTarget::Merl(path) = target {
            let t0 = Instant::now();
            let merl = crate::measured::MerlBrdf::from_brdf_with(src.as_ref(), progress);
            src.health()?;
            merl.write(path)?;
            let mut report =
                self.report_for(src.as_ref(), &Grid::merl(Channels::Rgb), None, t0, true);
            report.name = stem(path);
            report.output = path.clone();
            report.written = Some(target.clone());
            return Ok(report);
        }
        let provenance = source::provenance(&self.source, src.as_ref())?;
        let built = |checked: Option<(Table, BakeReport)>| match checked {
            Some(c) => Ok(c),
            None => self.table_unchecked(src.as_ref(), progress),
        };
        let (mut report, table) = match target {
            BakeTarget::Raw(path) => {
                let (table, r) = built(checked)?;
                table.save_raw(path)?;
                (r, Some(table))
            }
            // Tables built whole before they are written: MERL cells, and calibrated tables
            // (the calibration needs every value; measured and adaptive tables are small).
            _ if checked.is_some()
                || self.keeps_merl_cells()
                || self.effective_quantity(src.as_ref()) != Quantity::Fr
                || self.calibrates_model_table() =>
            {
                let (table, r) = built(checked)?;
                let (path, replace) = match target {
                    BakeTarget::Db { path, replace, .. } => (path.as_str(), *replace),
                    t => (t.path(), true),
                };
                if matches!(target, BakeTarget::File(_)) {
                    let _ = std::fs::remove_file(path);
                }
                tables::save(path, &name, provenance, &table, self.codec, replace)?;
                (r, Some(table))
            }
            _ => (
                self.stream(src.as_ref(), target, &name, provenance, progress)?,
                None,
            ),
        };
        if let Some(why) = missed {
            report.symmetry_note = Some(with_note(why, report.symmetry_note.take()));
        }
        report.name = name.clone();
        report.output = match target {
            BakeTarget::Db { path, .. } => format!("{path}#{name}"),
            t => t.path().to_owned(),
        };
        report.written = Some(target.clone());
        if matches!(target, BakeTarget::File(_) | BakeTarget::Db { .. }) {
            report.info = crate::store::info::table_info(target.path(), &name)?;
        }
        if self.accuracy_pairs > 0 {
            // The written table by its path and name: a `DB#NAME` string would be looked up
            // whole first, and a file of that name beside the output read instead.
            let tab = match table {
                Some(t) => TabulatedBrdf::from_table(t),
                None => crate::store::tables::open_brdf_at(target.path(), Some(&name), false)?,
            }
            .with_interp(self.accuracy_interp);
            report.accuracy = Some(Accuracy::measure(&tab, src.as_ref(), self.accuracy_pairs)?);
        }
        Ok(report)
    }

    /// Refuses a target that is the source's own file (`convert p.bsdf p.bsdf`, `bake t.btdb
    /// -o t.btdb`): the write would replace the source with its resample. Another entry of the
    /// database a `DB#NAME` source reads is fine (the source entry is kept as it is).
    fn refuse_overwrite(&self, target: &BakeTarget) -> Result<()> {
        if let BakeTarget::Db { name, .. } = target
            && let Ok((_, Some(entry))) = db::split_source(&self.source)
            && entry != name
        {
            return Ok(());
        }
        crate::files::refuse_input(std::path::Path::new(target.path()), &[&self.source])
    }

    fn stream(
        &self,
        src: &dyn Brdf,
        target: &BakeTarget,
        name: &str,
        provenance: crate::store::Source,
        progress: &dyn Progress,
    ) -> Result<BakeReport> {
        let t0 = Instant::now();
        // What the bake samples ([`BakeSource::bake_view`](crate::brdf::BakeSource::bake_view)).
        let view = src.bake_source().and_then(|b| b.bake_view());
        let bake_src: &dyn Brdf = view.as_deref().unwrap_or(src);
        let Plan {
            grid,
            note,
            force,
            assumed,
            search,
            // Calibrated tables are built in memory (`run_with`), never streamed.
            albedo: _,
        } = self.plan_with(bake_src, progress)?;
        let header = TableHeader::for_grid(name.to_owned(), provenance, &grid, self.codec);
        let _stage = Stage::begin(progress, "baking", grid.stored_values() as u64);
        let set = |done: u64, _total: u64| progress.set(done);
        let opts = self.bake_options(&set, force);
        let mut baked = None;
        let mut write = |w: &mut Writer| -> Result<()> {
            baked = Some(bake_chunks(bake_src, &grid, &opts, |i, v| {
                src.health()?; // a failed table source: stop before its zeros are written
                w.chunk_with(v, tables::chunk_layout(&grid, i))
            })?);
            // Before the file is committed (an error here leaves the old file as it was).
            src.health()
        };
        match target {
            BakeTarget::Db { path, replace, .. } => db::put(path, header, *replace, write)?,
            t => {
                let mut w = Writer::create(t.path())?;
                w.begin_table(header)?;
                write(&mut w)?;
                w.end_table()?;
                w.finish()?;
            }
        }
        let baked = baked.ok_or_else(|| Error::Unsupported("the bake wrote no table".into()))?;
        let mut report = self.report_for(src, &grid, note, t0, false);
        report.values = baked.values;
        report.forced = baked.forced.filter(|_| !assumed);
        report.target = search;
        Ok(report)
    }
}

/// The codec every host bakes with unless told otherwise: log16 ≤ 1e-3 at its default level.
pub fn default_codec() -> Codec {
    let quant = Quant::Log16 {
        tolerance: 1e-3,
        floor: None,
    };
    Codec {
        quant,
        level: quant.default_level(),
        ..Codec::default()
    }
}

/// Builds a codec from its parts as hosts name them: `name` is `f32`, `f16` or `log16` (also
/// `log16:TOL`), `tolerance` log16's relative bound, `level` the zstd level (default per codec).
pub fn codec(
    name: &str,
    tolerance: Option<f64>,
    floor: Option<f64>,
    level: Option<i32>,
    exhaustive: bool,
) -> Result<Codec> {
    let (name, tol) = match name.split_once(':') {
        Some((n, t)) => (
            n,
            Some(
                t.trim()
                    .parse::<f64>()
                    .map_err(|_| Error::arg("codec", format!("`{t}` is not a tolerance")))?,
            ),
        ),
        None => (name, None),
    };
    let quant = Quant::parse(name.trim(), tolerance.or(tol), floor)?;
    let level = level.unwrap_or(quant.default_level());
    if !(1..=22).contains(&level) {
        return Err(Error::arg(
            "level",
            format!("zstd level {level} is outside 1..=22"),
        ));
    }
    Ok(Codec {
        quant,
        level,
        exhaustive,
        ..Codec::default()
    })
}

/// What a bake did and what was written.
#[derive(Debug, Clone)]
pub struct BakeReport {
    /// The source's description.
    pub source: String,
    /// The table's name.
    pub name: String,
    /// What was written: a file, `DB#NAME`, or a raw file.
    pub output: String,
    /// The grid baked on.
    pub grid: Grid,
    /// Stored values.
    pub values: u64,
    /// Wall-clock seconds of the bake.
    pub seconds: f64,
    /// Set when symmetry detection disagreed with what the source declares.
    pub symmetry_note: Option<String>,
    /// The symmetry violation that `force` overrode, if any.
    pub forced: Option<String>,
    /// True when a MERL file's own cells were stored (no resampling).
    pub merl_cells: bool,
    /// The written table against its source, when asked for.
    pub accuracy: Option<Accuracy>,
    /// What `brdftab info --json` reports of the written table (null for raw files).
    pub info: serde_json::Value,
    /// The error-target search that chose the grid, if the request had a target.
    pub target: Option<TargetSearch>,
    /// Where it was written (`None` for a table built in memory, [`BakeRequest::table`]): the
    /// file's path as a path, which `output`, the display string, is not for a database entry
    /// (`DB#NAME`).
    pub written: Option<BakeTarget>,
}

impl BakeReport {
    /// What `brdftab info --json` reports of the written brdftab file — every table of a
    /// single-table file, the entry of a database — read from the path written (`Null` for a
    /// raw or MERL file, or nothing written). Not `info::file_info(&output)`: a `DB#NAME` string
    /// is looked up whole first, and a file named `db.btdb#m` beside the database would be read.
    pub fn output_info(&self) -> Result<serde_json::Value> {
        match &self.written {
            Some(BakeTarget::File(path)) => crate::store::info::file_info_at(path, None),
            Some(BakeTarget::Db { path, name, .. }) => {
                crate::store::info::file_info_at(path, Some(name))
            }
            _ => Ok(serde_json::Value::Null),
        }
    }

    /// The grid line of a report: the grid's summary, and whether a MERL file's cells were kept.
    pub fn grid_line(&self) -> String {
        let cells = if self.merl_cells {
            ", the file's own cells"
        } else {
            ""
        };
        format!("{}{cells}", self.grid.summary())
    }

    /// What the bake did, in a few lines for people: notes and warnings first, then the source,
    /// grid, reduction, output and throughput (`codec` names the quantization).
    pub fn summary(&self, codec: &Codec) -> String {
        let mut s = String::new();
        if let Some(n) = &self.symmetry_note {
            s += &format!("note: {n}\n");
        }
        if let Some(f) = &self.forced {
            s += &format!("warning: forced past a symmetry violation: {f}\n");
        }
        if let Some(t) = &self.target {
            let kind = if t.met { "note" } else { "warning" };
            s += &format!("{kind}: {}\n", t.summary());
        }
        let full = self.grid.full_values();
        s += &format!(
            "baked {}\n  grid: {}\n  {} stored values ({full} unreduced, {:.1}x reduction)\n",
            self.source,
            self.grid_line(),
            self.values,
            full as f64 / self.values.max(1) as f64
        );
        s + &format!(
            "wrote {} ({} values in {:.2} s, {:.1} M values/s, codec {})\n",
            self.output,
            self.values,
            self.seconds,
            self.values as f64 / self.seconds.max(1e-9) / 1e6,
            codec.quant.name()
        )
    }
}

/// Cosine-weighted accuracy of a table against its source.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Accuracy {
    /// Random pairs compared.
    pub pairs: usize,
    /// Relative RMSE of f_r weighted by cos θi cos θo, whole hemisphere.
    pub rel_rmse: f64,
    /// Largest relative error, whole hemisphere.
    pub max_rel: f64,
    /// The same RMSE with both directions within 80° of the normal (Ngan et al.'s cut; the
    /// grazing f_r of measured data grows as 1/cos θo).
    pub rel_rmse_80: f64,
    /// Largest relative error within 80°.
    pub max_rel_80: f64,
}

impl Accuracy {
    /// Compares `table` with `source` on `pairs` random pairs (seed 1).
    pub fn measure(table: &dyn Brdf, source: &dyn Brdf, pairs: usize) -> Result<Accuracy> {
        use crate::analysis::accuracy::{compare, compare_cap};
        let all = compare(table, source, pairs, 1)?;
        let cap = compare_cap(table, source, pairs, 1, 80f64.to_radians())?;
        Ok(Accuracy {
            pairs: all.pairs,
            rel_rmse: all.rel_rmse,
            max_rel: all.max_rel,
            rel_rmse_80: cap.rel_rmse,
            max_rel_80: cap.max_rel,
        })
    }
}

/// A file name's stem, the default name of a table (`table` when it has none). `path` is a
/// path, not a `DB#NAME` (a SOURCE's file is [`crate::store::name::path_of`]); a `#` in the stem
/// (a file named `scan#2.bsdf`), which a table name cannot hold, becomes `_`.
pub fn stem(path: &str) -> String {
    Path::new(path)
        .file_stem()
        .map(|s| s.to_string_lossy().replace('#', "_"))
        .unwrap_or_else(|| "table".into())
}

/// What [`to_rgl`] did: the file written, the source's description, the seconds it took and,
/// when asked for, the error of the file read back against the source.
#[derive(Debug, Clone)]
pub struct Converted {
    /// The file written.
    pub written: rgl_write::Written,
    /// The source's description.
    pub source: String,
    /// Wall-clock seconds of the encoding and writing.
    pub seconds: f64,
    /// The written file (through brdftab's reader) against the source, within 80°.
    pub error: Option<rgl_write::Report>,
}

/// Opens SOURCE (with `channels`, `None` = its own), writes it to `output` as an RGL file (a
/// `.bsdf` source keeps its own layout unless `opts` change it, see
/// [`rgl_write::Options::reuse_source_file`]) and, with `pairs > 0`, reports the written file's error.
pub fn to_rgl(
    source: &str,
    channels: Option<Channels>,
    output: &str,
    opts: &rgl_write::Options,
    pairs: usize,
    progress: &dyn Progress,
) -> Result<Converted> {
    let open = OpenOptions {
        channels,
        ..Default::default()
    };
    crate::files::refuse_input(std::path::Path::new(output), &[source])?;
    let brdf = source::open_with(source, &open)?;
    let opts = opts.clone().reuse_source_file(source)?;
    let t = std::time::Instant::now();
    let written = rgl_write::write(&*brdf, output, &opts, progress)?;
    let seconds = t.elapsed().as_secs_f64();
    let error = match pairs {
        0 => None,
        n => Some(rgl_write::report(
            &crate::measured::RglBrdf::open(output)?,
            &*brdf,
            n,
            1,
        )?),
    };
    Ok(Converted {
        written,
        source: brdf.describe(),
        seconds,
        error,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> crate::testkit::TempDir {
        crate::testkit::TempDir::new(&format!("bake-{name}"))
    }

    #[test]
    fn grid_choice_parses() {
        assert_eq!("merl".parse::<GridChoice>().unwrap(), GridChoice::Merl);
        assert_eq!(
            "90x1x90x180".parse::<GridChoice>().unwrap(),
            GridChoice::Sizes([90, 1, 90, 180])
        );
        assert_eq!(
            "small".parse::<GridChoice>().unwrap(),
            GridChoice::Preset(Preset::Small)
        );
        assert!(matches!(
            "90x1x90".parse::<GridChoice>(),
            Err(Error::InvalidArgument { .. })
        ));
        assert_eq!(
            "adaptive".parse::<GridChoice>().unwrap(),
            GridChoice::Adaptive(None)
        );
        assert_eq!(
            "Adaptive:96x48x25".parse::<GridChoice>().unwrap(),
            GridChoice::Adaptive(Some([96, 48, 25]))
        );
        for bad in ["adaptive:96x48", "adaptivex", "adaptive:", "adaptive:axbxc"] {
            assert!(
                matches!(
                    bad.parse::<GridChoice>(),
                    Err(Error::InvalidArgument { .. })
                ),
                "{bad}"
            );
        }
    }

    #[test]
    fn targets_parse_like_convert() {
        assert_eq!(
            BakeTarget::parse("a.btdb#x", None, false).unwrap(),
            BakeTarget::db("a.btdb", "x")
        );
        assert_eq!(
            BakeTarget::parse("a.btdb", None, false).unwrap(),
            BakeTarget::file("a.btdb")
        );
        assert_eq!(
            BakeTarget::parse("a.tbl", None, false).unwrap(),
            BakeTarget::Raw("a.tbl".into())
        );
        assert!(matches!(
            BakeTarget::parse("a.btdb#", None, false),
            Err(Error::InvalidArgument { ref name, .. }) if name == "output"
        ));
    }

    #[test]
    fn file_db_and_raw_targets_give_the_same_table() {
        let d = tmp("targets");
        let spec = r#"{"model":"cook_torrance","m":0.4,"ks":0.5}"#;
        let req = BakeRequest::new(spec)
            .preset(Preset::Small)
            .codec(codec("f32", None, None, None, false).unwrap());
        let file = d.join("ct.btdb").to_str().unwrap().to_owned();
        let dbp = d.join("many.btdb").to_str().unwrap().to_owned();
        let raw = d.join("ct.tbl").to_str().unwrap().to_owned();
        let r1 = req.run(&BakeTarget::file(&file)).unwrap();
        let merl = d.join("ct.binary").to_str().unwrap().to_owned();
        let rm = req.run(&BakeTarget::Merl(merl.clone())).unwrap();
        assert!(rm.merl_cells && rm.output == merl);
        assert!(crate::measured::MerlBrdf::open(&merl).is_ok());
        let r2 = req.run(&BakeTarget::db(&dbp, "ct")).unwrap();
        let r3 = req.run(&BakeTarget::Raw(raw.clone())).unwrap();
        assert_eq!(r1.name, "ct");
        assert_eq!(r2.output, format!("{dbp}#ct"));
        assert_eq!(r1.info["values"], r2.info["values"]);
        assert_eq!(r1.values, r3.values);
        let a = crate::source::open_table(&file, &OpenOptions::default())
            .unwrap()
            .to_table()
            .unwrap();
        let b = crate::source::open_table(&format!("{dbp}#ct"), &OpenOptions::default())
            .unwrap()
            .to_table()
            .unwrap();
        let c = Table::open_raw(&raw).unwrap();
        assert_eq!(a.values(), b.values());
        assert_eq!(a.values(), c.values());
        // A second add of the same name is refused; with replace it succeeds.
        assert!(req.run(&BakeTarget::db(&dbp, "ct")).is_err());
        let replace = BakeTarget::Db {
            path: dbp.clone(),
            name: "ct".into(),
            replace: true,
        };
        req.run(&replace).unwrap();
    }

    #[test]
    fn provenance_and_accuracy_are_reported() {
        let d = tmp("prov");
        let spec = r#"{"model":"lambert","kd":0.3}"#;
        let out = d.join("l.btdb").to_str().unwrap().to_owned();
        let r = BakeRequest::new(spec)
            .preset(Preset::Small)
            .accuracy(2000)
            .run(&BakeTarget::file(&out))
            .unwrap();
        assert_eq!(r.info["source"]["kind"], "model");
        let acc = r.accuracy.unwrap();
        assert_eq!(acc.pairs, 2000);
        // log16 ≤ 1e-3 relative on a constant: the error is the codec's bound at most.
        assert!(acc.max_rel <= 1e-3, "{acc:?}");
    }

    /// The accuracy report reads the table it wrote by the output's path and the table's name,
    /// never through a `DB#NAME` string: such a string is looked up whole first (a file named
    /// `l.btdb#l` is read as itself, `store::name`), so a file of that name beside the output —
    /// here a table of kd = 0.9 — was what the report measured (relative error 2).
    #[test]
    fn the_accuracy_report_reads_the_written_table_by_its_path() {
        let d = tmp("hash");
        let path = |f: &str| d.join(f).to_str().unwrap().to_owned();
        let decoy = path("decoy.btdb");
        let other = BakeRequest::new(r#"{"model":"lambert","kd":0.9}"#).preset(Preset::Small);
        other.run(&BakeTarget::file(&decoy)).unwrap();
        let req = BakeRequest::new(r#"{"model":"lambert","kd":0.3}"#)
            .preset(Preset::Small)
            .accuracy(2000);
        for (target, beside) in [
            (BakeTarget::file(path("l.btdb")), "l.btdb#l"),
            // A `#` in the output file's own name (table `x`).
            (BakeTarget::file(path("x.btdb#x")), "x.btdb#x#x"),
            (BakeTarget::db(path("db.btdb"), "m"), "db.btdb#m"),
        ] {
            std::fs::copy(&decoy, path(beside)).unwrap();
            let r = req.run(&target).unwrap();
            let acc = r.accuracy.unwrap();
            // log16 ≤ 1e-3 relative on a constant, as above.
            assert!(acc.max_rel <= 1e-3, "{target:?}: {acc:?}");
        }
    }

    /// The report's file info (what Python's `bake` and `convert` return) is read from the path
    /// written: a file named `db.btdb#m` beside the database is what the string `db.btdb#m`
    /// names as a SOURCE (`info` of it reads that file), not the entry the bake wrote.
    #[test]
    fn the_reports_file_info_is_of_the_path_written() {
        let d = tmp("info");
        let path = |f: &str| d.join(f).to_str().unwrap().to_owned();
        let req = BakeRequest::new(r#"{"model":"lambert","kd":0.3}"#).preset(Preset::Small);
        req.run(&BakeTarget::file(path("decoy.btdb"))).unwrap();
        std::fs::copy(path("decoy.btdb"), path("db.btdb#m")).unwrap();
        let r = req.run(&BakeTarget::db(path("db.btdb"), "m")).unwrap();
        assert_eq!(r.output, path("db.btdb#m"));
        let as_source = crate::store::info::file_info(&r.output).unwrap();
        assert_eq!(as_source["tables"][0]["name"], "decoy");
        let info = r.output_info().unwrap();
        assert_eq!(info["file"], path("db.btdb"));
        assert_eq!(info["tables"][0]["name"], "m");
        assert_eq!(info["tables"].as_array().map(Vec::len), Some(1));
        // A single-table file: every table of it; a table built in memory: nothing.
        let f = req.run(&BakeTarget::file(path("x.btdb#x"))).unwrap();
        assert_eq!(f.output_info().unwrap()["file"], path("x.btdb#x"));
        let (_, mem) = req.table(&Silent).unwrap();
        assert!(mem.output_info().unwrap().is_null());
    }

    #[test]
    fn an_explicit_symmetry_the_source_breaks_is_refused_unless_forced() {
        let d = tmp("sym");
        // The original Phong is not reciprocal.
        let spec = r#"{"model":"phong","ks":0.5,"n":20}"#;
        let out = d.join("p.btdb").to_str().unwrap().to_owned();
        let req = BakeRequest::new(spec)
            .preset(Preset::Small)
            .symmetry("isotropic,reciprocal".parse::<SymmetryChoice>().unwrap());
        assert!(matches!(
            req.run(&BakeTarget::file(&out)),
            Err(Error::Symmetry { .. })
        ));
        let mut forced = req.clone();
        forced.force = true;
        let r = forced.run(&BakeTarget::file(&out)).unwrap();
        assert!(r.forced.is_some());
    }

    #[test]
    fn a_model_asked_to_store_f_r_cos_out_bakes_on_the_default_grid() {
        // f_r cos θo cannot fold by reciprocity: the plan drops the fold (and calibrates the
        // table), and the preset's check must not bake a reciprocal grid of it first (it
        // failed with "a grid storing it cannot fold by reciprocity").
        let req =
            BakeRequest::new(r#"{"model": "lambert", "kd": 0.25}"#).quantity(Quantity::FrCosOut);
        let (table, _) = req.table(&Silent).unwrap();
        assert_eq!(table.grid().quantity(), Quantity::FrCosOut);
        assert!(!table.grid().symmetry().reciprocal);
    }

    #[test]
    fn a_default_bake_that_keeps_a_preset_missing_the_albedo_says_so() {
        // GGX α = 3e-4: the medium preset's table is 52 % bright in albedo at 89°, and neither
        // other candidate is taken (the adaptive table's and the calibrated preset's errors over
        // random pairs are larger). The preset stays, but not without a word.
        let spec = r#"{"model": "ggx", "alpha": 3e-4}"#;
        let d = tmp("missed");
        let req = BakeRequest::new(spec);
        let (_, r) = req.table(&Silent).unwrap();
        let note = r.symmetry_note.unwrap_or_default();
        assert!(note.contains("missed the albedo"), "{note:?}");
        let out = d.join("g.btdb").to_str().unwrap().to_owned();
        let r = req.run(&BakeTarget::file(&out)).unwrap();
        let note = r.symmetry_note.unwrap_or_default();
        assert!(note.contains("missed the albedo"), "{note:?}");
    }
}
