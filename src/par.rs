//! The thread pool the library's parallel work runs on, safe across `fork`.
//!
//! rayon's global pool is created once per process and its worker threads do not survive
//! `fork(2)`: a child forked after the parent used the pool (Python's `multiprocessing` with the
//! `fork` start method, the default on Linux before 3.14) inherits a pool whose threads do not
//! exist, and its first parallel call waits for them forever. So the library never uses the
//! global pool: every parallel section runs inside [`install`], on a pool that belongs to the
//! current process. A forked child notices that its process id is not the one the pool was
//! built in and builds a fresh pool for itself; the parent's pool is left alone (its threads
//! are gone in the child, and tearing it down would wait for them).
//!
//! Inside [`install`] rayon's parallel iterators use that pool, nested calls included; a call
//! from one of its own workers runs in place. Outside the library, `par_iter` still means the
//! global pool.

use std::sync::atomic::{AtomicPtr, Ordering};

/// The names of the pool's threads start with this.
const WORKER_PREFIX: &str = "brdftab-par-";

/// True for the name of one of the library pool's threads.
pub fn is_worker_name(name: &str) -> bool {
    name.starts_with(WORKER_PREFIX)
}

/// A pool and the process it was built in.
struct Owned {
    pid: u32,
    pool: rayon::ThreadPool,
}

/// The current pool (leaked on purpose: a pool is never dropped, see the module docs).
static POOL: AtomicPtr<Owned> = AtomicPtr::new(std::ptr::null_mut());

/// The pool of this process, built on first use (and again in a forked child).
pub fn pool() -> &'static rayon::ThreadPool {
    let pid = std::process::id();
    let cur = POOL.load(Ordering::Acquire);
    // SAFETY: a non-null POOL points to a leaked `Owned` that is never freed.
    if let Some(o) = unsafe { cur.as_ref() }
        && o.pid == pid
    {
        return &o.pool;
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .thread_name(|i| format!("{WORKER_PREFIX}{i}"))
        .build()
        .unwrap_or_else(|_| {
            // No thread could be started: one worker is what the calling thread would do.
            rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .expect("a pool of one thread")
        });
    let new = Box::into_raw(Box::new(Owned { pid, pool }));
    match POOL.compare_exchange(cur, new, Ordering::AcqRel, Ordering::Acquire) {
        // SAFETY: `new` was just leaked and is never freed.
        Ok(_) => &unsafe { &*new }.pool,
        Err(other) => {
            // Another thread built one first; use it (ours was never shared).
            // SAFETY: `new` came from Box::into_raw above and nobody else saw it.
            drop(unsafe { Box::from_raw(new) });
            // SAFETY: as above, a published pool is never freed.
            match unsafe { other.as_ref() } {
                Some(o) if o.pid == pid => &o.pool,
                _ => self::pool(),
            }
        }
    }
}

/// Runs `f` (which may use rayon's parallel iterators) on this process's pool.
pub fn install<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    pool().install(f)
}

/// The number of threads parallel sections use.
pub fn threads() -> usize {
    pool().current_num_threads()
}

#[cfg(test)]
mod tests {
    use rayon::prelude::*;

    #[test]
    fn installs_run_on_the_library_pool() {
        let s: u64 = super::install(|| (0..1000u64).into_par_iter().sum());
        assert_eq!(s, 499_500);
        let name = super::install(|| std::thread::current().name().map(str::to_owned));
        assert!(name.is_some_and(|n| super::is_worker_name(&n)));
        assert!(super::threads() >= 1);
    }
}
