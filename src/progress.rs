//! One progress type for every long operation of the library.
//!
//! Baking, converting, rendering, the accuracy suite and fitting can take seconds to minutes. The
//! library reports how far they are through [`Progress`] and never prints: the CLI maps it to an
//! indicatif bar (on a terminal only), the Python package to a callback, and the C ABI to
//! nothing. [`Silent`] is the do-nothing implementation.

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
