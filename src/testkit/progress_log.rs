//! [`ProgressLog`]: a [`Progress`] that records what it was told.

use std::sync::Mutex;

use crate::progress::Progress;

/// Records every call (`begin WHAT TOTAL`, `set DONE`, `end`), so a test can check what a long
/// operation reported.
#[derive(Debug, Default)]
pub struct ProgressLog(Mutex<Vec<String>>);

impl ProgressLog {
    /// The calls so far, in order.
    pub fn calls(&self) -> Vec<String> {
        self.0.lock().map(|v| v.clone()).unwrap_or_default()
    }

    fn push(&self, s: String) {
        if let Ok(mut v) = self.0.lock() {
            v.push(s);
        }
    }
}

impl Progress for ProgressLog {
    fn begin(&self, what: &str, total: u64) {
        self.push(format!("begin {what} {total}"));
    }
    fn set(&self, done: u64) {
        self.push(format!("set {done}"));
    }
    fn end(&self) {
        self.push("end".into());
    }
}
