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
//!     .run(&BakeTarget::file(&out))?;
//! assert_eq!(report.name, "lambert");
//! assert_eq!(report.info["codec"]["quant"], "log16");
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// One concern per file; the public names are re-exported here, so every path stays
// `bake::NAME`:
// - choices: what a request asks for (grid, symmetry, target), parsed from host strings;
// - plan: how a request bakes a given source (grid, symmetry, calibration, error target);
// - preset_check: whether a model's default medium table meets its albedo, and what replaces it;
// - memory: baking into memory (`table`, `table_of`);
// - run: baking to a file or database entry (`run`, `run_with`);
// - report: what a bake reports (`BakeReport`, `Accuracy`);
// - codec: the codec hosts bake with;
// - rgl: converting a source to an RGL `.bsdf` file.
mod choices;
mod codec;
mod memory;
mod plan;
mod preset_check;
mod report;
mod rgl;
mod run;

pub use self::codec::{codec, default_codec};
pub use choices::{BakeTarget, GridChoice, SymmetryChoice};
pub use plan::{
    MEASURED_BILATERAL_TOLERANCE, MEASURED_GRAZING_FACTOR, MEASURED_TARGET_ERROR, Plan,
};
pub use preset_check::{
    MODEL_FALLBACK_TARGET_ERROR, PRESET_ALBEDO_TOLERANCE, PRESET_CHECK_PAIRS,
    PRESET_CHECK_RMSE_SLACK, PRESET_CHECK_THETAS_DEG, PRESET_RMSE_TOLERANCE,
};
pub use report::{Accuracy, BakeReport};
pub use rgl::{Converted, to_rgl};
pub(crate) use run::refuse_name_conflict;
pub use run::{source_stem, stem};

use crate::codec::Codec;
use crate::spectrum::Channels;
use crate::table::presets::Preset;
use crate::table::{Interp, Param, Quantity, symmetry};

/// Everything a bake decides, in one place. Builder-style setters; `new(source)` starts from the
/// defaults every host shares (grid [`GridChoice::Default`], symmetry detected at 1e-3, codec
/// log16 ≤ 1e-3 at zstd level 6).
#[derive(Debug, Clone)]
pub struct BakeRequest {
    /// The SOURCE (see [`crate::source`]: a file name need not be UTF-8).
    pub source: std::ffi::OsString,
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
    /// The table's name (default: the output file's stem); a [`BakeTarget::Db`] names its
    /// table itself.
    pub name: Option<String>,
    /// Samples per stored axis and cell (box prefilter; 1 = node values).
    pub supersample: usize,
    /// Channels for model specs and RGL files (`None`: the source's own).
    pub channels: Option<Channels>,
    /// Random pairs for the accuracy report of the written table against its source (0 = none).
    pub accuracy_pairs: usize,
    /// Interpolation of the accuracy report (`None`: the table's own,
    /// [`Interp::default_for`] its grid — nearest on MERL cells, linear otherwise — as every
    /// host opens it).
    pub accuracy_interp: Option<Interp>,
    /// Pick the smallest adaptive grid whose table meets this error (relative RMSE of
    /// f_r cos θi cos θo within 80°; [`crate::table::target`]) instead of fixed node counts.
    /// Applies to adaptive grids: RGL files by default, any isotropic bilateral source with
    /// [`GridChoice::Adaptive`]`(None)` or [`GridChoice::Default`].
    pub target_error: Option<f64>,
    /// What the table stores (`None`: [`Quantity::FrCosOut`] for measured sources, RGL files
    /// and MERL files resampled to an error target, [`Quantity::FrCosCos`] for models whose f_r
    /// is unbounded at the horizon ([`Brdf::grows_at_horizon`](crate::brdf::Brdf::grows_at_horizon)), [`Quantity::Fr`] otherwise;
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
    /// Checks the fields a caller may have set directly (the request layer checks its settings
    /// too, but a `BakeRequest` is public): a NaN or negative symmetry tolerance detected no
    /// symmetry and silently baked an unreduced table.
    pub(crate) fn validate(&self) -> crate::Result<()> {
        let t = self.symmetry_tolerance;
        if !(t >= 0.0 && t.is_finite()) {
            return Err(crate::Error::arg(
                "symmetry_tolerance",
                format!("{t}: expected a finite tolerance ≥ 0"),
            ));
        }
        if let Some(c) = &self.channels {
            c.validate()?;
        }
        if self.supersample == 0 {
            return Err(crate::Error::arg(
                "supersample",
                "0: at least 1 sample per cell",
            ));
        }
        Ok(())
    }

    /// A request with the defaults for `source`.
    pub fn new(source: impl AsRef<std::ffi::OsStr>) -> BakeRequest {
        BakeRequest {
            source: source.as_ref().to_owned(),
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
            accuracy_interp: None,
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

    /// Reports the accuracy of the written table on `pairs` random pairs: a bake that writes
    /// ([`run`](Self::run)) measures it; an in-memory one ([`table`](Self::table),
    /// [`table_of`](Self::table_of)) does not — call [`Accuracy::measure`] on its table.
    pub fn accuracy(mut self, pairs: usize) -> BakeRequest {
        self.accuracy_pairs = pairs;
        self
    }
}

/// A fresh directory for a test's files (`bake-NAME` under the temporary directory).
#[cfg(test)]
fn tmp(name: &str) -> crate::testkit::TempDir {
    crate::testkit::TempDir::new(&format!("bake-{name}"))
}
