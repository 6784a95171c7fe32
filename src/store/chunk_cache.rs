//! The decoded chunks an open file keeps ([`ChunkCache`]), shared by its tables and bounded in
//! memory.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// A thread-safe cache of decoded chunks with a memory bound (least recently used out).
pub struct ChunkCache {
    budget: usize,
    inner: Mutex<CacheInner>,
}

/// A decoded chunk and its last use.
type Entry = (Arc<[f32]>, u64);

#[derive(Default)]
struct CacheInner {
    map: HashMap<(usize, usize), Entry>,
    bytes: usize,
    tick: u64,
}

impl ChunkCache {
    /// A cache holding at most `budget` bytes of decoded values.
    pub fn new(budget: usize) -> ChunkCache {
        ChunkCache {
            budget,
            inner: Mutex::new(CacheInner::default()),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, CacheInner> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    pub(super) fn get(&self, t: usize, i: usize) -> Option<Arc<[f32]>> {
        let mut g = self.lock();
        g.tick += 1;
        let tick = g.tick;
        g.map.get_mut(&(t, i)).map(|(v, last)| {
            *last = tick;
            v.clone()
        })
    }

    pub(super) fn put(&self, t: usize, i: usize, v: Arc<[f32]>) {
        let size = v.len() * 4;
        let mut g = self.lock();
        g.tick += 1;
        let tick = g.tick;
        if let Some((old, _)) = g.map.insert((t, i), (v, tick)) {
            g.bytes -= old.len() * 4;
        }
        g.bytes += size;
        while g.bytes > self.budget && g.map.len() > 1 {
            let oldest = g
                .map
                .iter()
                .filter(|(k, _)| **k != (t, i))
                .min_by_key(|(_, (_, last))| *last)
                .map(|(k, _)| *k);
            match oldest {
                Some(k) => {
                    let (old, _) = g.map.remove(&k).expect("present");
                    g.bytes -= old.len() * 4;
                }
                None => break,
            }
        }
    }

    /// Bytes of decoded values currently cached.
    pub fn bytes(&self) -> usize {
        self.lock().bytes
    }
}
