//! Baking to a file or a database entry: [`BakeRequest::run`] writes the table with its
//! provenance — streaming chunks into the file where it can — and reports what it wrote;
//! [`stem`] names a table after its file.

use std::path::Path;
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
                    staging.commit(target, &name)?;
                    (r, Some(a))
                } else {
                    match target {
                        BakeTarget::Db { path, replace, .. } => {
                            tables::save(path, &name, provenance, &table, self.codec, *replace)?
                        }
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
                staging.commit(target, &name)?;
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

/// A streamed table written beside its output before it is measured (removed when dropped
/// unless committed): a stop during the accuracy report leaves the output as it was.
struct Staging(std::path::PathBuf);

impl Staging {
    /// Beside the file `output` names (where it is a link, beside its target, which the
    /// commit renames over: the same file system).
    fn beside(output: &Path) -> Result<Staging> {
        let out = crate::files::resolve_links(output)?;
        Ok(Staging(crate::files::temp_path(&out)?))
    }

    /// The staging file's path.
    fn path(&self) -> &Path {
        &self.0
    }

    /// Moves the measured table into `target`: renamed over a file, imported (its chunks
    /// copied as they are) into a database.
    fn commit(self, target: &BakeTarget, name: &str) -> Result<()> {
        match target {
            BakeTarget::Db { path, replace, .. } => {
                let store = crate::store::Store::open(&self.0)?;
                db::import(path, &store, name, name, *replace)
            }
            t => {
                let out = crate::files::resolve_links(t.path())?;
                crate::files::rename_over(&self.0, &out).map_err(|e| Error::io(&out, e))
            }
        }
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// A `name` setting beside a `DB#NAME` output must repeat NAME: which one the user meant is
/// unknown, and taking either silently wrote a table the other road could not find. The rule of
/// a bake and of [`crate::request::save_table`] (`brdftab import`, Python's `Table.save`).
///
/// # Errors
/// [`Error::InvalidArgument`] naming `name` when `setting` is another name than `db_name`.
pub(crate) fn refuse_name_conflict(setting: Option<&str>, db_name: &str) -> Result<()> {
    match setting {
        Some(n) if n != db_name => Err(Error::arg(
            "name",
            format!(
                "{n:?} conflicts with the output's table name {db_name:?} (DB#NAME names the \
                 table itself: drop the name setting or make them agree)"
            ),
        )),
        _ => Ok(()),
    }
}

/// A file name's stem, the default name of a table (`table` when it has none). `path` is a
/// path, not a `DB#NAME` (a SOURCE's file is [`crate::store::name::path_of`]); a `#` or `\` in
/// the stem (a file named `scan#2.bsdf`, or `a\b.bsdf` on Unix), which a table name cannot
/// hold, becomes `_`.
pub fn stem(path: impl AsRef<Path>) -> String {
    path.as_ref()
        .file_stem()
        .map(|s| s.to_string_lossy().replace(['#', '\\'], "_"))
        .unwrap_or_else(|| "table".into())
}

/// The default name of a table converted from SOURCE: the table's own name for `DB#NAME`, the
/// model's name for an inline spec (`lambert`; not a stem of the JSON text, cut at its last
/// `.`), else its file's [`stem`].
pub fn source_stem(source: impl AsRef<std::ffi::OsStr>) -> String {
    let source = source.as_ref();
    if let Some(s) = source.to_str()
        && s.trim_start().starts_with('{')
    {
        return crate::spec::ModelSpec::parse(s)
            .map_or_else(|_| "table".into(), |s| s.name().to_owned());
    }
    match crate::store::name::parse_input_os("source", source) {
        Ok((_, Some(name))) => name.to_owned(),
        Ok((path, None)) => stem(path),
        Err(_) => stem(Path::new(source)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::{SymmetryChoice, codec, tmp};
    use crate::source::OpenOptions;
    use crate::table::presets::Preset;

    /// A measured (accuracy-reporting) streamed bake through a link into a directory whose
    /// name is not UTF-8: the staging file goes beside the link's target, whose name is bytes,
    /// and is renamed over it; nothing is left beside the link.
    // Not on Apple's file systems, which refuse a name that is not UTF-8 (APFS: EILSEQ).
    #[cfg(all(unix, not(target_vendor = "apple")))]
    #[test]
    fn a_measured_bake_through_a_link_into_a_non_utf8_directory_is_staged_beside_its_target() {
        use std::os::unix::ffi::OsStrExt;
        let d = tmp("staging_non_utf8");
        let odd = d.join(std::ffi::OsStr::from_bytes(b"dir\xff"));
        std::fs::create_dir(&odd).unwrap();
        let link = d.join("t.btdb");
        std::os::unix::fs::symlink(odd.join("t.btdb"), &link).unwrap();
        let mut req = BakeRequest::new(r#"{"model":"ggx","alpha":0.3}"#).preset(Preset::Small);
        req.accuracy_pairs = 4096;
        let link = link.to_str().unwrap().to_owned();
        let r = req.run(&BakeTarget::file(&link)).unwrap();
        assert!(r.accuracy.is_some());
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert!(odd.join("t.btdb").is_file());
        crate::open(&link).unwrap();
        let mut left: Vec<_> = std::fs::read_dir(d.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        left.sort();
        assert_eq!(left.len(), 2, "{left:?}"); // the directory and the link, no staging file
        assert_eq!(std::fs::read_dir(&odd).unwrap().count(), 1);
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
        let rm = req.run(&BakeTarget::Merl(merl.clone().into())).unwrap();
        assert!(rm.merl_cells && rm.output == merl);
        assert!(crate::measured::MerlBrdf::open(&merl).is_ok());
        let r2 = req.run(&BakeTarget::db(&dbp, "ct")).unwrap();
        let r3 = req.run(&BakeTarget::Raw(raw.clone().into())).unwrap();
        assert_eq!(r1.name, "ct");
        assert_eq!(r2.output, format!("{dbp}#ct"));
        assert_eq!(r1.info["values"], r2.info["values"]);
        assert_eq!(r1.values, r3.values);
        let a = crate::source::open_table(&file, &OpenOptions::default())
            .unwrap()
            .to_table()
            .unwrap();
        let b = crate::source::open_table(format!("{dbp}#ct"), &OpenOptions::default())
            .unwrap()
            .to_table()
            .unwrap();
        let c = Table::open_raw(&raw).unwrap();
        assert_eq!(a.values(), b.values());
        assert_eq!(a.values(), c.values());
        // A second add of the same name is refused; with replace it succeeds.
        assert!(req.run(&BakeTarget::db(&dbp, "ct")).is_err());
        let replace = BakeTarget::Db {
            path: dbp.clone().into(),
            name: "ct".into(),
            replace: true,
        };
        req.run(&replace).unwrap();
    }

    #[test]
    fn a_bake_that_fails_to_write_leaves_the_old_file() {
        let d = tmp("failed_write");
        let out = d.join("keep.btdb").to_str().unwrap().to_owned();
        BakeRequest::new(r#"{"model":"lambert","kd":0.5}"#)
            .preset(Preset::Small)
            .run(&BakeTarget::file(&out))
            .unwrap();
        let before = std::fs::read(&out).unwrap();
        // f_r = 1e5 is beyond f16 (±65504): the encoding fails once the table is baked. The
        // default grid builds the table whole (the preset check's table), the small preset
        // streams it; neither may remove the old file first.
        let bright = r#"{"model":"lambert","kd":1e5}"#;
        let f16 = codec("f16", None, None, None, false).unwrap();
        for req in [
            BakeRequest::new(bright).codec(f16),
            BakeRequest::new(bright).preset(Preset::Small).codec(f16),
        ] {
            let e = req.run(&BakeTarget::file(&out)).unwrap_err();
            assert!(e.to_string().contains("f16"), "{e}");
            assert_eq!(std::fs::read(&out).unwrap(), before);
        }
    }

    #[test]
    fn an_adaptive_grid_too_large_for_memory_is_an_error_not_an_abort() {
        use crate::bake::GridChoice;
        for nodes in [
            [10_000_000, 8, 8],
            [usize::MAX, 4, 4],
            [8, 8, usize::MAX / 2],
        ] {
            let t0 = Instant::now();
            let e = BakeRequest::new(r#"{"model":"lambert","kd":0.5}"#)
                .grid(GridChoice::Adaptive(Some(nodes)))
                .table(&Silent)
                .map(|_| ())
                .unwrap_err();
            assert!(
                matches!(e, Error::InvalidArgument { ref name, .. } if name == "grid"),
                "{nodes:?}: {e}"
            );
            assert!(
                t0.elapsed().as_secs_f64() < 5.0,
                "{nodes:?}: refused only after work"
            );
        }
    }

    #[test]
    fn table_of_bakes_the_source_it_is_given_not_a_file_of_the_requests_name() {
        let d = tmp("table_of_merl_name");
        let merl = d.join("white.binary");
        let white = crate::open(r#"{"model":"lambert","kd":0.5}"#).unwrap();
        crate::measured::MerlBrdf::from_brdf(white.as_ref())
            .write(&merl)
            .unwrap();
        let dark = crate::open(r#"{"model":"lambert","kd":0.1}"#).unwrap();
        let (t, _) = BakeRequest::new(merl.to_str().unwrap())
            .table_of(dark.as_ref(), &Silent)
            .unwrap();
        let mut f = [0.0f32; 3];
        TabulatedBrdf::from_table(t).eval(glam::DVec3::Z, glam::DVec3::new(0.6, 0.0, 0.8), &mut f);
        assert!(f.iter().all(|&x| (x - 0.1).abs() < 1e-3), "{f:?}");
        // The file itself, handed over opened, still keeps its own cells.
        let file = crate::open(merl.to_str().unwrap()).unwrap();
        let (t, _) = BakeRequest::new(merl.to_str().unwrap())
            .table_of(file.as_ref(), &Silent)
            .unwrap();
        assert_eq!(
            t.grid(),
            crate::measured::MerlBrdf::open(&merl)
                .unwrap()
                .to_table()
                .grid()
        );
    }

    #[test]
    fn fields_set_directly_are_checked_as_the_settings_are() {
        for (t, ss, field) in [
            (f64::NAN, 1, "symmetry_tolerance"),
            (-1.0, 1, "symmetry_tolerance"),
            (1e-3, 0, "supersample"),
        ] {
            let mut r = BakeRequest::new(r#"{"model":"lambert","kd":0.5}"#).preset(Preset::Small);
            r.symmetry_tolerance = t;
            r.supersample = ss;
            let e = r.table(&Silent).map(|_| ()).unwrap_err();
            assert!(
                matches!(e, Error::InvalidArgument { ref name, .. } if name == field),
                "{e}"
            );
        }
    }

    #[test]
    fn a_converted_specs_default_name_is_its_model() {
        assert_eq!(source_stem(r#" {"model":"lambert","kd":0.3}"#), "lambert");
        assert_eq!(source_stem(r#"{"model":"ggx","alpha":0.1}"#), "ggx");
        assert_eq!(source_stem("{not json"), "table");
        assert_eq!(
            source_stem("data/rgl/paper_white_rgb.bsdf"),
            "paper_white_rgb"
        );
        assert_eq!(source_stem("lib.btdb#gold"), "gold");
    }

    /// A file's stem with a character no table name holds (`#`; `\`, a file name's character
    /// on Unix) names its table with `_` there, a name every platform opens.
    #[test]
    fn a_stem_holds_no_character_a_table_name_refuses() {
        assert_eq!(stem("scans/x#2.bsdf"), "x_2");
        #[cfg(unix)]
        assert_eq!(stem(r"scans/a\b.bsdf"), "a_b");
        crate::store::name::check("name", &stem(r"a\b#c.bsdf")).unwrap();
    }

    #[test]
    fn an_existing_name_is_refused_before_the_bake() {
        /// Counts the stages a bake begins.
        #[derive(Default)]
        struct Stages(std::sync::atomic::AtomicUsize);
        impl Progress for Stages {
            fn begin(&self, _: &str, _: u64) {
                self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
        }
        let d = tmp("duplicate_first");
        let db = d.join("lib.btdb").to_str().unwrap().to_owned();
        let req = BakeRequest::new(r#"{"model":"lambert","kd":0.5}"#).preset(Preset::Small);
        let target = |replace| BakeTarget::Db {
            path: db.clone().into(),
            name: "matte".into(),
            replace,
        };
        let stages = Stages::default();
        req.run_with(&target(false), &stages).unwrap();
        assert!(
            stages.0.into_inner() > 0,
            "the first bake reports its stages"
        );
        let before = std::fs::read(&db).unwrap();
        let stages = Stages::default();
        let e = req.run_with(&target(false), &stages).unwrap_err();
        assert!(
            matches!(e, Error::Duplicate { ref name, .. } if name == "matte"),
            "{e}"
        );
        assert_eq!(stages.0.into_inner(), 0, "refused before any stage began");
        assert_eq!(std::fs::read(&db).unwrap(), before);
        req.run(&target(true)).unwrap(); // replace still works
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

    /// The accuracy report of a table built whole is that of the table as written — the
    /// codec's rounding included — to the bit: measured in memory before the codec, a log16
    /// table at a 1e-2 tolerance read as if it were stored exactly.
    #[test]
    fn the_accuracy_report_of_a_table_built_whole_is_of_the_stored_table() {
        let d = tmp("as_stored");
        let req = BakeRequest::new(r#"{"model":"ggx","alpha":0.3}"#)
            .preset(Preset::Small)
            .quantity(Quantity::FrCosOut) // built whole before it is written
            .codec(codec("log16:1e-2", None, None, None, false).unwrap())
            .accuracy(2000);
        for target in [
            BakeTarget::file(d.join("t.btdb")),
            BakeTarget::db(d.join("db.btdb"), "t"),
        ] {
            let r = req.run(&target).unwrap();
            let got = r.accuracy.unwrap();
            let src = crate::open(r#"{"model":"ggx","alpha":0.3}"#).unwrap();
            let stored = tables::open_brdf_at(target.path(), Some("t"), false).unwrap();
            let interp = Interp::default_for(stored.grid());
            let want = Accuracy::measure(&stored.with_interp(interp), src.as_ref(), 2000).unwrap();
            assert_eq!(
                (got.rel_rmse, got.max_rel),
                (want.rel_rmse, want.max_rel),
                "{target:?}"
            );
        }
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
}
