//! Where a [`TabulatedBrdf`]'s values come from: its chunks loaded on first touch (or all at
//! once), the packed array of a table with a kernel, load failures kept sticky, and the
//! memory all of it holds (see the parent module's docs).

use std::sync::Arc;
use std::sync::atomic::Ordering;

use super::{TabulatedBrdf, set_aside_negatives};
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::table::kernel::Packed;

impl TabulatedBrdf {
    /// The message of the first chunk-load error a lookup met, if any (see the module docs).
    pub fn load_error(&self) -> Option<String> {
        self.health().err().map(|e| e.to_string())
    }

    /// Keeps the first chunk-load error and marks the table failed (sticky).
    #[cold]
    pub(super) fn record_failure(&self, e: Error) {
        if let Ok(mut first) = self.error.lock() {
            first.get_or_insert(e);
        }
        self.failed.store(true, Ordering::Release);
    }

    /// Loads every chunk now; returns the first failing chunk's own error (asking the loader
    /// again for a chunk a lookup already found broken, so its error keeps its variant).
    pub fn load_all(&self) -> Result<()> {
        for i in 0..self.chunks.len() {
            if self.chunk(i).len() != self.grid.layout().chunk_len(i) {
                self.fetch(i)?;
            }
        }
        Ok(())
    }

    /// Number of chunks currently loaded.
    pub fn loaded_chunks(&self) -> usize {
        if let Some(p) = self.packed.get()
            && !p.is_empty()
        {
            return self.chunks.len();
        }
        self.chunks.iter().filter(|c| c.get().is_some()).count()
    }

    /// Bytes this table holds in memory now: decoded values (what a lookup reads) and, once
    /// built, the importance sampler's structure.
    pub fn resident_bytes(&self) -> usize {
        let f = std::mem::size_of::<f32>();
        let packed = self.packed.get().map_or(0, |p| p.bytes());
        let chunks: usize = self
            .chunks
            .iter()
            .filter_map(|c| c.get())
            .map(|c| c.len() * f)
            .sum();
        let unmeasured: usize = self
            .unmeasured
            .iter()
            .filter_map(|u| u.get())
            .map(|u| u.len() * std::mem::size_of::<(u32, f32)>())
            .sum();
        let sampler = self.sampler.get().map_or(0, |s| s.memory_bytes());
        packed + chunks + unmeasured + sampler
    }

    /// All chunks in one packed array (tables with a kernel), decoded on first use (without
    /// keeping the f32 chunks); empty when a chunk could not be loaded (the error is recorded,
    /// lookups give 0).
    ///
    /// The array's size is the file's word until its chunks decode: it is reserved fallibly,
    /// as [`StoredTable::read_all`](crate::store::StoredTable::read_all) reserves an eager
    /// open's (a size beyond memory is an error, not an abort), and filled as chunks decode, a
    /// window of them at a time side by side ([`TabulatedBrdf::fetch_window`]), so a file that
    /// claims more than its chunks hold fails at its first window.
    #[cold]
    pub(super) fn load_packed(&self) -> Packed {
        let l = self.grid.layout();
        let mut all = Vec::new();
        // Room for the padding: an exact kernel keeps this array as it is.
        if all.try_reserve_exact(l.len() + Packed::PAD).is_err() {
            self.record_failure(Error::format(
                &self.description,
                Some("values"),
                None,
                format!(
                    "{} values ({:.1} GB of f32) do not fit in memory",
                    l.len(),
                    l.len() as f64 * 4e-9
                ),
            ));
            return Packed::empty();
        }
        // Chunks decoded at a time: the eager read's rule (enough for the pool, at most a 32nd
        // of the table held twice while it decodes).
        let n = l.chunk_count();
        let window = (2 * crate::par::threads()).min(n / 32).max(1);
        for first in (0..n).step_by(window) {
            let range = first..(first + window).min(n);
            for (a, got) in range.clone().zip(self.fetch_window(range)) {
                match got {
                    // Loaded already (by a nearest lookup, say).
                    None => match self.chunks[a].get() {
                        Some(c) if c.len() == l.chunk_len(a) => all.extend_from_slice(c),
                        // A chunk that failed to load (its error is recorded).
                        _ => return Packed::empty(),
                    },
                    Some(Ok(mut v)) => {
                        let _ = self.unmeasured[a].set(set_aside_negatives(&mut v, self.project));
                        all.extend_from_slice(&v);
                    }
                    Some(Err(e)) => {
                        self.record_failure(e);
                        return Packed::empty();
                    }
                }
            }
        }
        match &self.kernel {
            Some(k) => Packed::for_kernel_owned(k, all),
            None => Packed::empty(),
        }
    }

    /// Chunks `range` from the loader (`None` for a chunk loaded already), decoded side by
    /// side on up to [`crate::par::threads`] scoped threads: the first lookup of a large
    /// preset's table decoded on one thread, 1.6× an eager open's time (session 40).
    ///
    /// Plain threads, not the library's rayon pool: this runs inside the initialization of the
    /// `packed` cell, and a pool worker that waits for its tasks steals others — another
    /// block of a batch of lookups of this table, whose wait on the same cell, on the same
    /// thread, would never end.
    pub(super) fn fetch_window(
        &self,
        range: std::ops::Range<usize>,
    ) -> Vec<Option<Result<Vec<f32>>>> {
        let get = |a: usize| self.chunks[a].get().is_none().then(|| self.fetch(a));
        let k = crate::par::threads().min(range.len());
        if k <= 1 {
            return range.map(get).collect();
        }
        let lost = |a: usize| {
            let msg = format!("chunk {a}: its decoding thread panicked");
            Some(Err(Error::format(
                &self.description,
                Some("values"),
                None,
                msg,
            )))
        };
        std::thread::scope(|s| {
            let share = |t: usize| range.clone().skip(t).step_by(k);
            let handles: Vec<_> = (0..k)
                .map(|t| {
                    let mine = share(t);
                    std::thread::Builder::new()
                        .spawn_scoped(s, move || mine.map(get).collect::<Vec<_>>())
                })
                .collect();
            let mut parts: Vec<std::vec::IntoIter<_>> = handles
                .into_iter()
                .enumerate()
                .map(|(t, h)| {
                    match h {
                        Ok(h) => h.join().unwrap_or_default(),
                        // No thread could be started: this one decodes its share.
                        Err(_) => share(t).map(get).collect(),
                    }
                    .into_iter()
                })
                .collect();
            range
                .clone()
                .enumerate()
                .map(|(i, a)| parts[i % k].next().unwrap_or_else(|| lost(a)))
                .collect()
        })
    }

    #[inline(always)]
    pub(super) fn packed(&self) -> &Packed {
        match self.packed.get() {
            Some(p) => p,
            None => self.packed.get_or_init(|| self.load_packed()),
        }
    }

    #[inline(always)]
    pub(super) fn chunk(&self, a: usize) -> &[f32] {
        if let Some(k) = &self.kernel
            && k.exact_values()
        {
            // The exact kernel's array is the chunks, contiguous: no second copy.
            let r = self.grid.layout().chunk_range(a);
            return self.packed().exact_values().get(r).unwrap_or(&[]);
        }
        match self.chunks.get(a) {
            Some(c) => match c.get() {
                Some(v) => v,
                None => self.load_chunk(a),
            },
            None => &[],
        }
    }

    /// The negative values chunk `a` holds as 0 (empty until it is loaded).
    pub(super) fn unmeasured_of(&self, a: usize) -> &[(u32, f32)] {
        self.unmeasured
            .get(a)
            .and_then(|u| u.get())
            .map_or(&[], |u| u)
    }

    #[cold]
    pub(super) fn load_chunk(&self, a: usize) -> &[f32] {
        self.chunks[a].get_or_init(|| match self.fetch(a) {
            Ok(mut v) => {
                let _ = self.unmeasured[a].set(set_aside_negatives(&mut v, self.project));
                v.into()
            }
            Err(e) => {
                self.record_failure(e);
                Arc::from([])
            }
        })
    }

    /// Chunk `a` from the loader, checked for length.
    pub(super) fn fetch(&self, a: usize) -> Result<Vec<f32>> {
        let want = self.grid.layout().chunk_len(a);
        let v = match &self.loader {
            Some(l) => l.load(a)?,
            None => return Err(Error::NotFound(format!("chunk {a}: no loader"))),
        };
        if v.len() != want {
            return Err(Error::format(
                "<table>",
                None,
                None,
                format!("chunk {a}: {} values loaded, {want} expected", v.len()),
            ));
        }
        Ok(v)
    }
}
