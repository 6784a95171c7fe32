//! One progress type for every long operation of the library.
//!
//! Baking, converting, rendering, the accuracy suite and fitting can take seconds to minutes. The
//! library reports how far they are through [`Progress`] and never prints: the CLI maps it to an
//! indicatif bar (on a terminal only), the Python package to a callback, and the C ABI to
//! nothing. [`Silent`] is the do-nothing implementation.
//!
//! It is also how a host stops one: [`Progress::cancelled`] is asked between units of work (a
//! row of a bake's values, a grid of an error-target search, a start of a fit), and an
//! operation that finds it true returns [`Error::Cancelled`]. Python's bake, convert and fit
//! answer it from Ctrl-C; the library learns nothing of where the request comes from.

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
