//! Baking into memory: [`BakeRequest::table`] and [`BakeRequest::table_of`] give the table and
//! what the bake did, writing nothing — the plan carried out, after the preset's check. The
//! written bakes ([`BakeRequest::run`]) take their in-memory tables from here.

use std::time::Instant;

use crate::brdf::Brdf;
use crate::error::Result;
use crate::progress::{Progress, Stage};
use crate::source::{self, OpenOptions};
use crate::table::calibration::calibrate_with;
use crate::table::{BakeOptions, Table};

use super::BakeRequest;
use super::plan::Plan;
use super::preset_check::{Checked, Fallback, MODEL_FALLBACK_TARGET_ERROR, with_note};
use super::report::BakeReport;

impl BakeRequest {
    /// Opens the source as the request says.
    pub fn open_source(&self) -> Result<Box<dyn Brdf + Send + Sync>> {
        let opts = OpenOptions {
            channels: self.channels.clone(),
            ..OpenOptions::default()
        };
        let src = source::open_with(&self.source, &opts)?;
        crate::table::fill::tabulable(src.as_ref())?;
        Ok(src)
    }

    /// Bakes into memory: the table and what the bake did.
    pub fn table(&self, progress: &dyn Progress) -> Result<(Table, BakeReport)> {
        let src = self.open_source()?;
        self.table_of(src.as_ref(), progress)
    }

    /// Bakes an already opened source (for callers that also use it, e.g. to compare). `src` is
    /// what is sampled; the request's SOURCE string still says what kind of source it is (a
    /// model spec, a measured file, a table), which chooses the default grid, the stored
    /// quantity and the calibration — so for a `Brdf` of your own, name it as what it is
    /// (e.g. `BakeRequest::new("{}")` for a model) or set the grid.
    pub fn table_of(&self, src: &dyn Brdf, progress: &dyn Progress) -> Result<(Table, BakeReport)> {
        self.validate()?;
        crate::table::fill::tabulable(src)?;
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

    /// [`table_of`](Self::table_of) without the preset's check.
    pub(super) fn table_unchecked(
        &self,
        src: &dyn Brdf,
        progress: &dyn Progress,
    ) -> Result<(Table, BakeReport)> {
        let t0 = Instant::now();
        if self.keeps_merl_cells() {
            let merl = crate::measured::MerlBrdf::open(&self.source)?;
            // The file's own cells only when `src` is that file (`table_of` may be handed
            // another source under a `.binary` name: it baked the file instead).
            if merl.describe() == src.describe() {
                let table = merl.to_table();
                let report = self.report_for(src, table.grid(), None, t0, true);
                return Ok((table, report));
            }
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
            let cancel = || progress.cancelled();
            let opts = self.bake_options(&set, &cancel, force);
            crate::table::bake(bake_src, &grid, &opts)?
        };
        // A lazily read table source whose chunk failed gave zeros: refuse them.
        src.health()?;
        if let Some(a) = &albedo {
            let _stage = Stage::begin(progress, "calibrating albedo", 0);
            table = calibrate_with(table, a, progress)?;
            src.health()?;
        }
        let grid = table.grid().clone();
        let mut report = self.report_for(src, &grid, note, t0, false);
        report.forced = r.forced.filter(|_| !assumed);
        report.target = search;
        Ok((table, report))
    }

    pub(super) fn bake_options<'a>(
        &self,
        set: crate::table::fill::Progress<'a>,
        cancel: &'a (dyn Fn() -> bool + Sync),
        force: bool,
    ) -> BakeOptions<'a> {
        BakeOptions {
            supersample: self.supersample,
            force,
            tolerance: self.symmetry_tolerance,
            progress: Some(set),
            cancel: Some(cancel),
            ..BakeOptions::default()
        }
    }
}
