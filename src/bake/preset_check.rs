//! The check a model's default bake makes before it keeps the medium preset: does the preset's
//! table meet the source's directional albedo ([`PRESET_ALBEDO_TOLERANCE`])? If not, which table
//! is taken instead ([`Checked`], [`Fallback`]). Its own file because it is the part of planning
//! that bakes: the preset's table, and the candidates that may replace it (the adaptive one
//! through [`BakeRequest::table_of`], as a request with an error target, which this check skips).

use std::time::Instant;

use crate::analysis::accuracy::{Region, Weight, compare_region_with};
use crate::analysis::fidelity::AlbedoError;
use crate::brdf::Brdf;
use crate::error::Result;
use crate::progress::{Progress, Quiet, Stage};
use crate::source::{self, SourceKind};
use crate::table::calibration::{
    ANISOTROPIC_AZIMUTHS, AlbedoReference, CalibrationOptions, calibrate_with,
};
use crate::table::presets::Preset;
use crate::table::{BakeOptions, Param, Quantity, Table, TabulatedBrdf};

use super::BakeRequest;
use super::choices::{GridChoice, SymmetryChoice};
use super::report::BakeReport;

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

/// How far from the source over [`PRESET_CHECK_PAIRS`] random pairs (relative RMSE of
/// f_r cos θi cos θo, over the whole hemisphere) a model's medium-preset table may be before
/// the check tries the adaptive table of [`MODEL_FALLBACK_TARGET_ERROR`] although the preset
/// meets the albedo: 1.5 × that target. The preset's θh nodes resolve a lobe a degree or two
/// wide only so far — the reciprocal Phong at n = 1000: 0.61 % (its adaptive table 0.06 %),
/// Blinn-Phong at n = 1000: 0.33 % (0.22 %) —, and the albedo check does not see it. Weighted
/// by both cosines because that RMS is finite for every model (f_r cos θi alone has none for
/// Cook-Torrance, whose f_r grows like 1/cos² θ on the grazing mirror: over 20 000 pairs its
/// estimate is a lottery). The adaptive table is taken where it is closer on this figure,
/// meets the albedo and is not worse beyond [`PRESET_CHECK_RMSE_SLACK`] on the check's own
/// weight; the lobes it serves and the others (GGX α ≥ 0.05, Oren-Nayar, a Lambert + GGX
/// sum: 0.09–0.26 %) keep their presets without that extra bake.
pub const PRESET_RMSE_TOLERANCE: f64 = 0.003;

/// The error target of a model's default bake when its preset table misses the albedo
/// ([`PRESET_ALBEDO_TOLERANCE`]): 0.2 % relative RMSE, as the Mitsuba plugin's JIT tables of
/// models (`brdftab.mitsuba.MODEL_TARGET_ERROR`), calibrated. A lobe too sharp for it gets the
/// largest adaptive grid (GGX α = 0.002: 2.2 % within 80°, 0.4 % albedo, against the preset's
/// 26 % and 14 %).
pub const MODEL_FALLBACK_TARGET_ERROR: f64 = 0.002;

/// The table a model's default bake takes instead of the medium preset's
/// ([`BakeRequest::preset_misses`]).
pub(super) enum Fallback {
    /// The adaptive, calibrated table of [`MODEL_FALLBACK_TARGET_ERROR`]: the bake runs as the
    /// request with that target would.
    Adaptive,
    /// The medium preset's table, calibrated (this one, as the check baked it).
    CalibratedPreset(Box<Table>),
}

/// What the preset's check ([`BakeRequest::preset_misses`]) decided.
pub(super) enum Checked {
    /// The check does not apply to this request.
    Unchecked,
    /// The preset's table meets the albedo (and the error over random pairs, or no adaptive
    /// table comes closer): the table the check baked, and its bake's stats
    /// (the bake takes it as its own instead of baking the same grid again).
    Kept(Box<(Table, crate::table::fill::BakeStats)>),
    /// Another table instead, and why.
    Instead(Fallback, String),
    /// The preset's table misses the albedo and no other table was taken: the preset's table
    /// is baked as without the check, and the note says by how much it misses.
    Missed(String),
}

/// Whether a candidate's error over random pairs `r` is within [`PRESET_CHECK_RMSE_SLACK`] of
/// the preset's `rp` (any error up to 1 % passes).
fn within_slack(r: f64, rp: f64) -> bool {
    r <= (rp * (1.0 + PRESET_CHECK_RMSE_SLACK)).max(0.01)
}

/// `why` before the bake's own note, if it has one.
pub(super) fn with_note(why: String, note: Option<String>) -> String {
    match note {
        Some(n) => format!("{why}; {n}"),
        None => why,
    }
}

impl BakeRequest {
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
    /// the bake's note says by how much it misses). A preset table that meets the albedo but
    /// is further than [`PRESET_RMSE_TOLERANCE`] from the source over those random pairs is
    /// replaced by the adaptive table (isotropic, bilateral sources) where that is closer and
    /// meets the albedo too.
    pub(super) fn preset_misses(&self, src: &dyn Brdf, progress: &dyn Progress) -> Result<Checked> {
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
        let cancel = || progress.cancelled();
        let opts = BakeOptions {
            tolerance: self.symmetry_tolerance,
            force: self.force || self.symmetry == SymmetryChoice::Declared,
            cancel: Some(&cancel),
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
        let albedo = |t: &dyn Brdf| {
            crate::progress::check(progress)?;
            crate::analysis::fidelity::albedo_error(t, src, &fid)
        };
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
        let rmse_weighted = |t: &dyn Brdf, w: Weight| {
            let whole = Region::Cap(std::f64::consts::FRAC_PI_2);
            compare_region_with(t, src, PRESET_CHECK_PAIRS, 1, whole, w, progress)
                .map(|a| a.rel_rmse)
        };
        let rmse = |t: &dyn Brdf| rmse_weighted(t, weight);
        // The error of the whole-hemisphere f_r cos θi cos θo ([`PRESET_RMSE_TOLERANCE`]).
        let rmse_cc = |t: &dyn Brdf| rmse_weighted(t, Weight::CosInCosOut);
        let plain = TabulatedBrdf::from_table(preset.clone());
        let e = albedo(&plain)?;
        if e.worst <= PRESET_ALBEDO_TOLERANCE {
            let pc = rmse_cc(&plain)?;
            if pc <= PRESET_RMSE_TOLERANCE || !(sym.isotropic && sym.bilateral) {
                return Ok(Checked::Kept(Box::new((preset, stats))));
            }
            // The albedo is met but not the error over random pairs: only finer nodes help
            // (a calibration would rescale what the nodes miss).
            let rp = rmse(&plain)?;
            drop(plain);
            let (adaptive, _) = self
                .clone()
                .target_error(MODEL_FALLBACK_TARGET_ERROR)
                .table_of(src, &Quiet(progress))?;
            let adaptive = TabulatedBrdf::from_table(adaptive);
            let (a, ac, r) = (albedo(&adaptive)?, rmse_cc(&adaptive)?, rmse(&adaptive)?);
            if ac < pc && a.worst <= PRESET_ALBEDO_TOLERANCE && within_slack(r, rp) {
                let why = format!(
                    "the medium preset's table was {:.2} % off over random pairs: baked to an \
                     error target of {} % instead ({:.2} %)",
                    100.0 * pc,
                    100.0 * MODEL_FALLBACK_TARGET_ERROR,
                    100.0 * ac
                );
                return Ok(Checked::Instead(Fallback::Adaptive, why));
            }
            return Ok(Checked::Kept(Box::new((preset, stats))));
        }
        let rp = rmse(&plain)?;
        drop(plain);
        let mut best: Option<(Fallback, AlbedoError)> = None;
        let mut consider = |f: Fallback, a: AlbedoError, r: f64| {
            if a.worst < best.as_ref().map_or(e.worst, |b| b.1.worst) && within_slack(r, rp) {
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
                .table_of(src, &Quiet(progress))?;
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
            let reference = AlbedoReference::new_with(src, &copts, progress)?;
            let calibrated = calibrate_with(preset, &reference, progress)?;
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
    pub(super) fn reuse_checked(
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

    /// The report of a default bake that took the medium preset's table, calibrated.
    pub(super) fn calibrated_preset_report(
        &self,
        src: &dyn Brdf,
        table: &Table,
        why: String,
        t0: Instant,
    ) -> BakeReport {
        let (_, note) = self.resolve_symmetry(src);
        self.report_for(src, table.grid(), Some(with_note(why, note)), t0, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::{BakeTarget, tmp};
    use crate::progress::Silent;

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
