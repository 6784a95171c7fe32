//! How a request bakes a given source: the [`Plan`] — the grid, the symmetry and whether it
//! is verified, the error-target search, the albedo to calibrate to — and the rules behind it
//! (which sources get an adaptive grid, what a table stores, when a measurement's bilateral
//! symmetry is assumed). Deciding only: the bakes are in `memory` and `run`.

use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::progress::{Progress, Silent};
use crate::source::{self, SourceKind};
use crate::table::adaptive;
use crate::table::calibration::{AlbedoReference, CalibrationOptions};
use crate::table::presets::Preset;
use crate::table::target::{self, TargetSearch};
use crate::table::warp::WarpVar;
use crate::table::{Grid, Mapping, Param, Quantity, Symmetry, symmetry};

use super::BakeRequest;
use super::choices::{GridChoice, SymmetryChoice};

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

impl BakeRequest {
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
        if self.grid == GridChoice::Merl && sym.bilateral {
            // A bilateral fold stores φd on nodes at the cells' edges ([0, π/2], `Edges`), not
            // at their centres: a nearest lookup read the neighbouring cell on half of each and
            // the values were not the cells' (a reciprocal Phong's table was 1.1 % off the
            // value at its cell's centre at the median, 17 % at worst). The MERL grid keeps its
            // 180 φd cells.
            sym.bilateral = false;
            note = Some(format!(
                "{}the MERL grid keeps its φd cells: using {sym}",
                note.map(|n| format!("{n}; ")).unwrap_or_default()
            ));
        }
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
        // A measurement's table (f_r cos θo, not reciprocal) is calibrated to its albedo; a
        // model's f_r cos θi cos θo table is not merely for being non-reciprocal (the original
        // Phong's medium table was pinned to factors 0.68–1.01 and got worse: 0.095 → 0.134 %
        // over random pairs): the preset check decides for models, as for any preset.
        let albedo = if self.calibrate
            && ((quantity == Quantity::FrCosOut && !sym.reciprocal)
                || self.calibrates_model_table())
        {
            progress.note("integrating the source's albedo");
            Some(AlbedoReference::new_with(
                src,
                &CalibrationOptions::default(),
                progress,
            )?)
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
                None => self.resolve_grid_with(src, sym, progress)?,
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
    /// a model's default check finds one off ([`PRESET_ALBEDO_TOLERANCE`](super::PRESET_ALBEDO_TOLERANCE)).
    pub(super) fn calibrates_model_table(&self) -> bool {
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
        self.resolve_grid_with(src, sym, &Silent)
    }

    /// [`resolve_grid`](Self::resolve_grid), asking `progress` to stop while an adaptive
    /// grid's warps are fitted.
    fn resolve_grid_with(
        &self,
        src: &dyn Brdf,
        sym: Symmetry,
        progress: &dyn Progress,
    ) -> Result<Grid> {
        let ch = src.channels().clone();
        if self.adaptive() {
            let nodes = match self.grid {
                GridChoice::Adaptive(Some(n)) => n,
                _ => adaptive::DEFAULT_NODES,
            };
            if self.param.is_some_and(|p| p != Param::HalfDiff) {
                return Err(Error::arg("grid", "an adaptive grid is halfdiff"));
            }
            let opts = self.adaptive_options(src, nodes);
            return adaptive::adaptive_grid_with(src, sym, &opts, progress);
        }
        match self.grid {
            GridChoice::Merl => {
                if self.param.is_some_and(|p| p != Param::HalfDiff) {
                    return Err(Error::arg(
                        "param",
                        "the MERL grid is halfdiff (θh, θd, φd cells)",
                    ));
                }
                Grid::merl(ch).with_symmetry(sym)
            }
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
    pub(super) fn keeps_merl_cells(&self) -> bool {
        self.target_error.is_none()
            && source::classify(&self.source) == SourceKind::Merl
            && matches!(self.grid, GridChoice::Default | GridChoice::Merl)
            && self.param.is_none_or(|p| p == Param::HalfDiff)
            && self.supersample == 1
    }
}
