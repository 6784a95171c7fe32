//! The library's [`brdftab::Progress`] as an indicatif bar: shown on a terminal, silent when
//! stderr is not one (pipes, CI logs).

use std::io::IsTerminal;
use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar per stage; nothing at all when stderr is not a terminal.
pub struct Bar {
    template: &'static str,
    bar: Mutex<Option<ProgressBar>>,
    visible: bool,
}

impl Bar {
    /// A bar with indicatif template `template` (`{msg}` is the stage's name).
    pub fn new(template: &'static str) -> Bar {
        Bar {
            template,
            bar: Mutex::new(None),
            visible: std::io::stderr().is_terminal(),
        }
    }

    /// The default look: stage name, bar, percentage, counts and ETA.
    pub fn values() -> Bar {
        Bar::new("{msg} {bar:40} {percent:>3}% {human_pos}/{human_len}, eta {eta}")
    }

    fn with(&self, f: impl FnOnce(&mut Option<ProgressBar>)) {
        if self.visible {
            f(&mut self.bar.lock().unwrap_or_else(|p| p.into_inner()));
        }
    }
}

impl brdftab::Progress for Bar {
    fn begin(&self, what: &str, total: u64) {
        let template = self.template;
        self.with(|b| {
            let bar = ProgressBar::new(total);
            bar.set_style(
                ProgressStyle::with_template(template)
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> "),
            );
            bar.set_message(what.to_owned());
            *b = Some(bar);
        });
    }

    fn set(&self, done: u64) {
        self.with(|b| {
            if let Some(b) = b {
                b.set_position(done);
            }
        });
    }

    fn end(&self) {
        self.with(|b| {
            if let Some(b) = b.take() {
                b.finish_and_clear();
            }
        });
    }
}
