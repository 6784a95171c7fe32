//! One progress type for every long operation of the library.
//!
//! Baking, converting, rendering, the accuracy suite and fitting can take seconds to minutes. The
//! library reports how far they are through [`Progress`] and never prints: the CLI maps it to an
//! indicatif bar (on a terminal only), the Python package to nothing but a stop, and the C
//! ABI's `_monitored` calls to the host's progress monitor. [`Silent`] is the do-nothing
//! implementation.
//!
//! It is also how a host stops one: [`Progress::cancelled`] is asked between units of work (a
//! row of a bake's values, a grid of an error-target search, a start of a fit), and an
//! operation that finds it true returns [`Error::Cancelled`] and writes nothing. Every step of
//! a bake, a conversion and a fit up to its output's commit asks within ~0.3 s of work
//! (BENCHMARKS.md, session 42).
//! Python's bake, bake_cached, convert and fit answer it from Ctrl-C, a C host from its
//! monitor's 0; the library learns nothing of where the request comes from.

use crate::error::Error;

/// Receives progress reports. Every method has an empty default, so an implementation overrides
/// only what it shows. Calls may come from several threads (hence `Sync`).
pub trait Progress: Sync {
    /// A stage starts: `what` names it (e.g. `"baking"`), `total` is its number of units
    /// (values, pixels, sources), 0 when unknown.
    fn begin(&self, what: &str, total: u64) {
        let _ = (what, total);
    }

    /// `done` units of the current stage are finished (monotone within a stage).
    fn set(&self, done: u64) {
        let _ = done;
    }

    /// What the current stage is working on now (e.g. the source being measured); shown beside
    /// the stage's name where there is room.
    fn note(&self, what: &str) {
        let _ = what;
    }

    /// The current stage is over (successfully or not).
    fn end(&self) {}

    /// True when the host wants the operation stopped: it then returns [`Error::Cancelled`]
    /// soon after (within one unit of work per thread). Asked from any thread, often.
    fn cancelled(&self) -> bool {
        false
    }
}

/// `Err(`[`Error::Cancelled`]`)` when `p` asks to stop.
pub fn check(p: &dyn Progress) -> crate::error::Result<()> {
    if p.cancelled() {
        Err(Error::Cancelled)
    } else {
        Ok(())
    }
}

/// Shows nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

/// Shows nothing of an inner operation's stages but passes on the host's request to stop: for
/// work inside a stage of its own (the `.bsdf` writer's trial slices, the preset check's
/// candidate bake), whose bars would interleave with the caller's.
pub(crate) struct Quiet<'a>(pub(crate) &'a dyn Progress);

impl Progress for Quiet<'_> {
    fn cancelled(&self) -> bool {
        self.0.cancelled()
    }
}

impl Progress for Silent {}

impl<P: Progress + ?Sized> Progress for &P {
    fn begin(&self, what: &str, total: u64) {
        (**self).begin(what, total)
    }
    fn set(&self, done: u64) {
        (**self).set(done)
    }
    fn note(&self, what: &str) {
        (**self).note(what)
    }
    fn end(&self) {
        (**self).end()
    }
    fn cancelled(&self) -> bool {
        (**self).cancelled()
    }
}

/// A stage of a [`Progress`] that ends when dropped, so an early return through `?` still ends
/// it (for long operations built on the library, e.g. the CLI's renders and reports).
pub struct Stage<'a>(&'a dyn Progress);

impl<'a> Stage<'a> {
    /// Begins a stage on `p`.
    pub fn begin(p: &'a dyn Progress, what: &str, total: u64) -> Stage<'a> {
        p.begin(what, total);
        Stage(p)
    }
}

impl Drop for Stage<'_> {
    fn drop(&mut self) {
        self.0.end();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::testkit::ProgressLog as Log;

    /// Cancelled from the `after`-th question on.
    struct CancelAfter {
        asked: std::sync::atomic::AtomicUsize,
        after: usize,
    }

    impl Progress for CancelAfter {
        fn cancelled(&self) -> bool {
            self.asked
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed)
                >= self.after
        }
    }

    fn cancel_after(after: usize) -> CancelAfter {
        CancelAfter {
            asked: Default::default(),
            after,
        }
    }

    /// A bake, a conversion and a fit asked to stop return `Error::Cancelled` and write
    /// nothing; a bake that is never asked to stop asks along the way (rows of values).
    #[test]
    fn cancelled_operations_stop_and_write_nothing() {
        use crate::request;
        let dir = crate::testkit::TempDir::new("cancel");
        let spec = r#"{"model": "ggx", "alpha": 0.2}"#;
        let small: request::BakeSettings = request::from_json(r#"{"preset": "small"}"#).unwrap();
        let never = cancel_after(usize::MAX);
        let out = dir.file("whole.btdb");
        request::bake(spec, &out, &small, &never).unwrap();
        let asked = never.asked.load(std::sync::atomic::Ordering::Relaxed);
        assert!(asked > 100, "asked {asked} times");
        for after in [0, 1, asked / 2] {
            let out = dir.file(&format!("t{after}.btdb"));
            let r = request::bake(spec, &out, &small, &cancel_after(after));
            assert!(matches!(r, Err(Error::Cancelled)), "after {after}: {r:?}");
            assert!(!std::path::Path::new(&out).exists(), "{out}");
        }
        let bsdf = dir.file("t.bsdf");
        let r = request::convert(spec, &bsdf, &Default::default(), &cancel_after(0));
        assert!(matches!(r, Err(Error::Cancelled)), "{:?}", r.map(|_| ()));
        assert!(!std::path::Path::new(&bsdf).exists());
        let r = request::fit(spec, "ggx", &Default::default(), &cancel_after(0));
        assert!(matches!(r, Err(Error::Cancelled)), "{:?}", r.map(|_| ()));
    }

    /// Cancelled from the first report that starts with `trigger` on (`begin WHAT`,
    /// `end WHAT`, `note WHAT`), once `grace` questions after it have been answered no; keeps
    /// the reports made after it.
    struct CancelAt {
        trigger: &'static str,
        grace: usize,
        asked: std::sync::atomic::AtomicUsize,
        on: std::sync::atomic::AtomicBool,
        stages: std::sync::Mutex<Vec<String>>,
        after: std::sync::Mutex<Vec<String>>,
    }

    impl CancelAt {
        fn new(trigger: &'static str) -> CancelAt {
            Self::after(trigger, 0)
        }
        fn after(trigger: &'static str, grace: usize) -> CancelAt {
            CancelAt {
                trigger,
                grace,
                asked: Default::default(),
                on: Default::default(),
                stages: Default::default(),
                after: Default::default(),
            }
        }
        fn event(&self, e: String) {
            use std::sync::atomic::Ordering::Relaxed;
            if self.on.load(Relaxed) {
                self.after.lock().unwrap().push(e);
            } else if e.starts_with(self.trigger) {
                self.on.store(true, Relaxed);
            }
        }
        /// Whether the operation reported a report starting with `what` after the stop.
        fn went_on_to(&self, what: &str) -> bool {
            self.after
                .lock()
                .unwrap()
                .iter()
                .any(|e| e.starts_with(what))
        }
    }

    impl Progress for CancelAt {
        fn begin(&self, what: &str, _total: u64) {
            self.stages.lock().unwrap().push(what.to_owned());
            self.event(format!("begin {what}"));
        }
        fn end(&self) {
            let what = self.stages.lock().unwrap().pop().unwrap_or_default();
            self.event(format!("end {what}"));
        }
        fn note(&self, what: &str) {
            self.event(format!("note {what}"));
        }
        fn cancelled(&self) -> bool {
            use std::sync::atomic::Ordering::Relaxed;
            self.on.load(Relaxed) && self.asked.fetch_add(1, Relaxed) >= self.grace
        }
    }

    /// `r` is `Error::Cancelled` and the directory `dir` holds no file (neither the output
    /// nor a temporary or staging file).
    fn stopped_leaving_nothing<T: std::fmt::Debug>(
        r: crate::Result<T>,
        dir: &crate::testkit::TempDir,
    ) {
        assert!(matches!(r, Err(Error::Cancelled)), "{r:?}");
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert!(left.is_empty(), "left {left:?}");
    }

    fn rosaline() -> std::path::PathBuf {
        crate::measured::data::rgl_file("satin_rosaline_rgb.bsdf").unwrap_or_else(|e| panic!("{e}"))
    }

    /// Each step of a measured file's bake that ran to its end with a stop pending (0.8 s of
    /// albedo calibration that then wrote the table; the source's albedo and the warps, a
    /// second each before the search asked) stops within it and writes nothing.
    #[test]
    fn a_measured_bake_stops_in_each_of_its_steps() {
        use crate::request;
        let src = rosaline();
        for (trigger, next) in [
            (
                "note integrating the source's albedo",
                Some("begin searching grid"),
            ),
            (
                "note fitting warps",
                Some("note evaluating the source on the rule"),
            ),
            ("note evaluating the source on the rule", Some("note ")),
            // The old code finished the calibration and wrote the table.
            ("begin calibrating albedo", None),
        ] {
            let dir = crate::testkit::TempDir::new("cancel_measured");
            let p = CancelAt::new(trigger);
            let r = request::bake(&src, dir.file("t.btdb"), &Default::default(), &p);
            if let Some(next) = next {
                assert!(!p.went_on_to(next), "{trigger}: went on to {next}");
            }
            stopped_leaving_nothing(r, &dir);
        }
        // Past the transports of both directions (one question per node each), in the rounds
        // of the fit (up to 2000, 0.5-0.8 s, which asked nothing).
        let nodes = crate::table::calibration::CalibrationOptions::default().nodes;
        let dir = crate::testkit::TempDir::new("cancel_measured");
        let p = CancelAt::after("begin calibrating albedo", 2 * nodes);
        let r = request::bake(&src, dir.file("t.btdb"), &Default::default(), &p);
        stopped_leaving_nothing(r, &dir);
    }

    /// A conversion's accuracy report (2 s for 2 M pairs, after the table was written) stops
    /// when asked and leaves no output: the table is measured before it is committed.
    #[test]
    fn a_conversions_accuracy_report_stops_and_writes_nothing() {
        use crate::request;
        let spec = r#"{"model": "ggx", "alpha": 0.2}"#;
        let s: request::ConvertSettings = request::from_json(r#"{"preset": "small"}"#).unwrap();
        for out in ["t.btdb", "db.btdb#t"] {
            let dir = crate::testkit::TempDir::new("cancel_accuracy");
            let r = request::convert(spec, dir.file(out), &s, &CancelAt::new("end baking"));
            stopped_leaving_nothing(r.map(|_| ()), &dir);
        }
        // Measured in a staging file, then committed: the report and the table as before.
        let dir = crate::testkit::TempDir::new("cancel_accuracy");
        for out in ["t.btdb", "db.btdb#t"] {
            let out = dir.file(out);
            let r = request::convert(spec, &out, &s, &Silent).unwrap();
            let request::ConvertOutput::Table { report, .. } = r else {
                panic!("{out}: not a table")
            };
            let a = report.accuracy.expect("an accuracy report");
            assert!(a.rel_rmse > 0.0 && a.rel_rmse < 0.05, "{a:?}");
            crate::open(&out).unwrap();
        }
        let mut left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        left.sort();
        // A conversion's `.btdb` output is a database of one table (hence its writer's lock file).
        assert_eq!(left, [".db.btdb.lock", ".t.btdb.lock", "db.btdb", "t.btdb"]);
    }

    /// The `.bsdf` writer stops while it places an anisotropic source's azimuths (12 s that
    /// ran to their end) and during the written file's report, writing nothing.
    #[test]
    fn the_bsdf_writer_stops_in_its_placement_and_report() {
        use crate::request;
        let ward = r#"{"model": "ward", "ks": 0.5, "alpha_x": 0.1, "alpha_y": 0.3}"#;
        let dir = crate::testkit::TempDir::new("cancel_bsdf");
        let p = CancelAt::new("begin placing azimuths");
        let r = request::convert(ward, dir.file("w.bsdf"), &Default::default(), &p);
        assert!(
            !p.went_on_to("begin sampling"),
            "went on to sample the values"
        );
        stopped_leaving_nothing(r.map(|_| ()), &dir);
        let lambert = r#"{"model": "lambert", "kd": 0.5}"#;
        let r = request::convert(
            lambert,
            dir.file("l.bsdf"),
            &Default::default(),
            &CancelAt::new("end sampling"),
        );
        stopped_leaving_nothing(r.map(|_| ()), &dir);
    }

    /// Waiting for a cached table that another writer holds the lock of stops when asked (it
    /// blocked until the lock was released).
    #[test]
    fn waiting_for_a_cache_lock_stops_when_asked() {
        let dir = crate::testkit::TempDir::new("cancel_lock");
        let spec = r#"{"model": "lambert", "kd": 0.5}"#;
        let s = crate::request::BakeSettings::default();
        let path = dir.join(format!("{}.btdb", crate::cache::key(spec, &s).unwrap()));
        let _held = crate::store::db::lock(&path).unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let d = dir.path().to_path_buf();
        std::thread::spawn(move || {
            let r = crate::cache::bake_cached_with(spec, &s, Some(&d), false, &cancel_after(3));
            let _ = tx.send(r.map(|c| c.path));
        });
        let r = rx.recv_timeout(std::time::Duration::from_secs(20));
        assert!(matches!(r, Ok(Err(Error::Cancelled))), "{r:?}");
        assert!(!path.exists());
    }

    /// A bake into `DB#NAME` while another writer holds the database's lock stops when asked:
    /// it blocked in the lock (until the other writer was done; a streamed bake into the same
    /// database holds it for the whole bake) without asking.
    #[test]
    fn a_bake_into_a_locked_database_stops_when_asked() {
        use crate::request;
        let dir = crate::testkit::TempDir::new("cancel_db_lock");
        let db = dir.join("lib.btdb");
        let _held = crate::store::db::lock(&db).unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let target = format!("{}#lambert", db.display());
        std::thread::spawn(move || {
            let spec = r#"{"model": "lambert", "kd": 0.5}"#;
            // The stop comes once the bake's stage has begun: after the plan, at the lock.
            let stop = CancelAt::new("begin baking");
            let small: request::BakeSettings =
                request::from_json(r#"{"preset": "small"}"#).unwrap();
            let r = request::bake(spec, &target, &small, &stop);
            let _ = tx.send(r.map(|_| ()));
        });
        let r = rx.recv_timeout(std::time::Duration::from_secs(20));
        assert!(matches!(r, Ok(Err(Error::Cancelled))), "{r:?}");
        assert!(!db.exists(), "no database written");
    }

    #[test]
    fn a_stage_ends_on_early_return() {
        let log = Log::default();
        let run = |fail: bool| -> Result<(), ()> {
            let _s = Stage::begin(&log, "x", 2);
            log.set(1);
            if fail {
                return Err(());
            }
            log.set(2);
            Ok(())
        };
        assert!(run(true).is_err());
        assert_eq!(log.calls(), ["begin x 2", "set 1", "end"]);
    }
}
