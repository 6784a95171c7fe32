//! What the foreign-language hosts (the C ABI, the Python extension) share at their boundary.
//!
//! [`catch_quietly`] runs a call under `catch_unwind` so that no panic crosses into C or Python,
//! and keeps the panic *quiet*: Rust's default hook prints `thread '…' panicked at …` and,
//! with `RUST_BACKTRACE` set, a backtrace on the host's stderr — noise in a renderer's log for
//! an error the caller already receives as `-1` or an exception. The first call installs a
//! panic hook that stays silent on a thread inside a [`catch_quietly`] call and on the
//! library's pool threads ([`crate::par`]: a panic in a batch's worker unwinds into the
//! caller's catch), and defers to the previous hook otherwise, so panics elsewhere in the
//! process print as before. The bookkeeping is a thread-local counter: no shared atomic is
//! written per call (C renderers call from many threads at once).

use std::any::Any;
use std::cell::Cell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Once;

static HOOK: Once = Once::new();

thread_local! {
    /// Depth of [`catch_quietly`] calls on this thread.
    static DEPTH: Cell<u32> = const { Cell::new(0) };
}

fn install_hook() {
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let guarded = DEPTH.try_with(|d| d.get() > 0).unwrap_or(false);
            let worker = std::thread::current()
                .name()
                .is_some_and(crate::par::is_worker_name);
            if !guarded && !worker {
                previous(info);
            }
        }));
    });
}

/// Decrements this thread's depth when the call ends, however it ends.
struct Active;

impl Drop for Active {
    fn drop(&mut self) {
        let _ = DEPTH.try_with(|d| d.set(d.get().saturating_sub(1)));
    }
}

/// Runs `f`; a panic becomes `Err` with the panic's message, printed nowhere.
pub fn catch_quietly<R>(f: impl FnOnce() -> R) -> Result<R, String> {
    install_hook();
    DEPTH.with(|d| d.set(d.get() + 1));
    let _active = Active;
    catch_unwind(AssertUnwindSafe(f)).map_err(panic_message)
}

/// The message of a caught panic (`&str` or `String` payloads; "unknown panic" otherwise).
pub fn panic_message(p: Box<dyn Any + Send>) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_its_message() {
        assert_eq!(catch_quietly(|| 7), Ok(7));
        let e = catch_quietly(|| -> u8 { panic!("boom {}", 1) }).unwrap_err();
        assert_eq!(e, "boom 1");
        assert_eq!(DEPTH.with(|d| d.get()), 0);
    }
}
