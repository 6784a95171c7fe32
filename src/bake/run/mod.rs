//! Baking to a file or a database entry: [`BakeRequest::run`] writes the table with its
//! provenance — streaming chunks into the file where it can — and reports what it wrote;
//! [`stem`] names a table after its file.

use std::time::Instant;

use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::progress::{Progress, Silent, Stage};
use crate::source;
use crate::spectrum::Channels;
use crate::store::{TableHeader, Writer, db, tables};
use crate::table::{Grid, Interp, Quantity, Table, TabulatedBrdf, bake_chunks};

use super::BakeRequest;
use super::choices::BakeTarget;
use super::plan::Plan;
use super::preset_check::{Checked, Fallback, MODEL_FALLBACK_TARGET_ERROR, with_note};
use super::report::{Accuracy, BakeReport};

mod names;
mod staging;

pub(crate) use names::refuse_name_conflict;
pub use names::{source_stem, stem};
use staging::Staging;

impl BakeRequest {
    /// Bakes and writes to `target` with provenance; returns what the bake did and what `info`
    /// reports of the written table. Chunks stream into the file as they are baked (bounded
    /// memory), except for raw targets and MERL cells, which are built in memory.
    pub fn run(&self, target: &BakeTarget) -> Result<BakeReport> {
        self.run_with(target, &Silent)
    }

    /// [`run`](Self::run), reporting progress.
    pub fn run_with(&self, target: &BakeTarget, progress: &dyn Progress) -> Result<BakeReport> {
        self.validate()?;
        // A table file named like a measured file would not open again as a table.
        if let BakeTarget::File(p) | BakeTarget::Raw(p) = target {
            crate::source::check_table_output(p)?;
        }
        // An output that is not a regular file (a FIFO, a device, a directory), before any
        // work and before a database there is read.
        crate::files::check_output(&crate::files::resolve_links(target.path())?)?;
        self.refuse_overwrite(target)?;
        let name = match (target, &self.name) {
            (BakeTarget::Db { name, .. }, setting) => {
                refuse_name_conflict(setting.as_deref(), name)?;
                name.clone()
            }
            (_, Some(n)) => n.clone(),
            (t, None) => stem(t.path()),
        };
        // Before any work (and before a `File` target's old file is removed): a table name
        // the store would refuse ([`crate::store::name`]).
        if matches!(target, BakeTarget::File(_) | BakeTarget::Db { .. }) {
            crate::store::name::check("name", &name)?;
        }
        // An existing name without `replace` is refused before the bake, not after it.
        if let BakeTarget::Db {
            path,
            replace: false,
            ..
        } = target
        {
            db::refuse_duplicate(path, &name)?;
        }
        if let BakeTarget::File(path) = target {
            db::refuse_dropping_tables(path)?;
        }
        let src = self.open_source()?;
        // The accuracy report's bound, before the table is written: a request over it wrote
        // the table (replacing an old one) and then failed.
        if self.accuracy_pairs > 0 {
            crate::analysis::accuracy::check_pairs(self.accuracy_pairs, src.channels().len())?;
        }
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
            crate::progress::check(progress)?;
            src.health()?;
            merl.write(path)?;
            let mut report =
                self.report_for(src.as_ref(), &Grid::merl(Channels::Rgb), None, t0, true);
            report.name = stem(path);
            report.output = path.display().to_string();
            report.written = Some(target.clone());
            return Ok(report);
        }
        let provenance = source::provenance(&self.source, src.as_ref())?;
        let built = |checked: Option<(Table, BakeReport)>| match checked {
            Some(c) => Ok(c),
            None => self.table_unchecked(src.as_ref(), progress),
        };
        // The accuracy report is measured before the output is committed, so that a stop
        // asked during it (seconds for a conversion's 200 000 pairs) leaves the output as it
        // was: the table as stored (the codec's rounding included) is measured in a staging
        // file beside the output, renamed (or imported) into place once measured. A raw
        // table's f32 values are the table's own, measured in memory.
        let pairs = self.accuracy_pairs;
        let measure = |tab: TabulatedBrdf| -> Result<Accuracy> {
            let interp = self
                .accuracy_interp
                .unwrap_or_else(|| Interp::default_for(tab.grid()));
            Accuracy::measure_with(&tab.with_interp(interp), src.as_ref(), pairs, progress)
        };
        let (mut report, accuracy) = match target {
            BakeTarget::Raw(path) => {
                let (table, r) = built(checked)?;
                let a = (pairs > 0)
                    .then(|| measure(TabulatedBrdf::from_table(table.clone())))
                    .transpose()?;
                table.save_raw(path)?;
                (r, a)
            }
            // Tables built whole before they are written: MERL cells, and calibrated tables
            // (the calibration needs every value; measured and adaptive tables are small).
            _ if checked.is_some()
                || self.keeps_merl_cells()
                || self.effective_quantity(src.as_ref()) != Quantity::Fr
                || self.calibrates_model_table() =>
            {
                let (table, r) = built(checked)?;
                if pairs > 0 {
                    // Measured as stored (the codec's rounding included), in a staging file.
                    let staging = Staging::beside(target.path())?;
                    tables::save_file(staging.path(), &name, provenance, &table, self.codec)?;
                    drop(table);
                    let stored =
                        crate::store::tables::open_brdf_at(staging.path(), Some(&name), false)?;
                    let a = measure(stored)?;
                    staging.commit(target, &name, progress)?;
                    (r, Some(a))
                } else {
                    match target {
                        BakeTarget::Db { path, replace, .. } => tables::save_with(
                            path, &name, provenance, &table, self.codec, *replace, progress,
                        )?,
                        // Replaced atomically, as a streamed bake replaces it: a write that
                        // fails (a value the codec cannot hold, a full disk) leaves the old
                        // file as it was.
                        t => tables::save_file(t.path(), &name, provenance, &table, self.codec)?,
                    }
                    (r, None)
                }
            }
            _ if pairs > 0 => {
                let staging = Staging::beside(target.path())?;
                let file = BakeTarget::File(staging.path().to_path_buf());
                let r = self.stream(src.as_ref(), &file, &name, provenance, progress)?;
                let a = measure(crate::store::tables::open_brdf_at(
                    file.path(),
                    Some(&name),
                    false,
                )?)?;
                staging.commit(target, &name, progress)?;
                (r, Some(a))
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
            BakeTarget::Db { path, .. } => format!("{}#{name}", path.display()),
            t => t.path().display().to_string(),
        };
        report.written = Some(target.clone());
        if matches!(target, BakeTarget::File(_) | BakeTarget::Db { .. }) {
            report.info = crate::store::info::table_info(target.path(), &name)?;
        }
        report.accuracy = accuracy;
        Ok(report)
    }

    /// Refuses a target that is the source's own file (`convert p.bsdf p.bsdf`, `bake t.btdb
    /// -o t.btdb`): the write would replace the source with its resample. Another entry of the
    /// database a `DB#NAME` source reads is fine (the source entry is kept as it is).
    fn refuse_overwrite(&self, target: &BakeTarget) -> Result<()> {
        if let BakeTarget::Db { name, .. } = target
            && let Ok((_, Some(entry))) = crate::store::name::parse_input_os("source", &self.source)
            && entry != name
        {
            return Ok(());
        }
        crate::files::refuse_input(target.path(), &[&self.source])
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
        let cancel = || progress.cancelled();
        let opts = self.bake_options(&set, &cancel, force);
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
            BakeTarget::Db { path, replace, .. } => {
                db::put_with(path, header, *replace, progress, write)?
            }
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

#[cfg(test)]
mod tests;
