//! The library's [`brdftab::Progress`] as an indicatif bar: shown on a terminal, silent when
//! stderr is not one (pipes, CI logs).

use std::io::IsTerminal;
use std::sync::Mutex;

use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar per stage; nothing at all when stderr is not a terminal.
pub struct Bar {
    template: &'static str,
    bar: Mutex<Option<ProgressBar>>,
    /// (prefix set by the command, name of the current stage).
    label: Mutex<(String, String)>,
    visible: bool,
}

impl Bar {
    /// A bar with indicatif template `template` (`{msg}` is the stage's name).
    pub fn new(template: &'static str) -> Bar {
        Bar {
            template,
            bar: Mutex::new(None),
            label: Mutex::new((String::new(), String::new())),
            visible: std::io::stderr().is_terminal(),
        }
    }

    /// Shows `prefix` before the stage names of the stages that follow (e.g. a source's name).
    pub fn prefix(&self, prefix: &str) {
        self.lock_label().0 = prefix.to_owned();
    }

    fn lock_label(&self) -> std::sync::MutexGuard<'_, (String, String)> {
        self.label.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn message(&self, note: &str) -> String {
        let l = self.lock_label();
        [l.0.as_str(), l.1.as_str(), note]
            .iter()
            .filter(|s| !s.is_empty())
            .copied()
            .collect::<Vec<_>>()
            .join(" ")
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
        self.lock_label().1 = what.to_owned();
        let msg = self.message("");
        self.with(|b| {
            // A stage of unknown length (0 units) spins, with what it is on and how many done.
            let bar = if total == 0 {
                let bar = ProgressBar::new_spinner();
                bar.set_style(
                    ProgressStyle::with_template("{spinner} {msg} ({pos} done, {elapsed})")
                        .unwrap_or_else(|_| ProgressStyle::default_spinner()),
                );
                bar.enable_steady_tick(std::time::Duration::from_millis(120));
                bar
            } else {
                let bar = ProgressBar::new(total);
                bar.set_style(
                    ProgressStyle::with_template(template)
                        .unwrap_or_else(|_| ProgressStyle::default_bar())
                        .progress_chars("=> "),
                );
                bar
            };
            bar.set_message(msg);
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

    fn note(&self, what: &str) {
        let msg = self.message(what);
        self.with(|b| {
            if let Some(b) = b {
                b.set_message(msg);
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
