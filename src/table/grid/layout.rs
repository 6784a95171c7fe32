//! The stored layout of a grid's values ([`Layout`]): the row-major order over the stored axes
//! and λ, and its chunks.

use serde::Serialize;
use std::ops::Range;

/// The stored layout: a row-major array over the four stored axes and λ (innermost), split into
/// chunks = slabs of axis 0. With `packed` (inout reciprocity) only θ2 ≥ θ1 is stored: chunk a
/// holds axis-2 indices a..n, so its size is (n − a)·s1·s3·c.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Layout {
    /// Stored axis sizes.
    pub shape: [usize; 4],
    /// Upper-triangle packing of (axis 0, axis 2).
    pub packed: bool,
    /// Number of channels (values per node).
    pub channels: usize,
    /// Start offset (in values) of each chunk, plus the total at the end.
    chunk_starts: Vec<usize>,
}

impl Layout {
    pub(super) fn new(shape: [usize; 4], packed: bool, channels: usize) -> Layout {
        let [n0, s1, n2, s3] = shape;
        let mut starts = Vec::with_capacity(n0 + 1);
        let mut acc = 0usize;
        for a in 0..n0 {
            starts.push(acc);
            let rows = if packed { n2.saturating_sub(a) } else { n2 };
            acc += s1 * rows * s3 * channels;
        }
        starts.push(acc);
        Layout {
            shape,
            packed,
            channels,
            chunk_starts: starts,
        }
    }

    /// Total number of stored values.
    pub fn len(&self) -> usize {
        *self.chunk_starts.last().unwrap_or(&0)
    }

    /// True when nothing is stored (never for a valid grid).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of chunks (= size of stored axis 0).
    pub fn chunk_count(&self) -> usize {
        self.shape[0]
    }

    /// The value range of chunk `i` in the whole array.
    pub fn chunk_range(&self, i: usize) -> Range<usize> {
        self.chunk_starts[i]..self.chunk_starts[i + 1]
    }

    /// Number of values in chunk `i`.
    pub fn chunk_len(&self, i: usize) -> usize {
        self.chunk_starts[i + 1] - self.chunk_starts[i]
    }

    /// Number of axis-2 indices stored in chunk `a` and the first one.
    #[inline]
    pub fn rows2(&self, a: usize) -> (usize, usize) {
        if self.packed {
            (a, self.shape[2] - a)
        } else {
            (0, self.shape[2])
        }
    }

    /// Offset of node `[a, p, b, q]` (its channel 0) inside chunk `a`, or `None` when the node
    /// is not stored (out of range, or b < a when packed).
    #[inline]
    pub fn offset_in_chunk(&self, idx: [usize; 4]) -> Option<usize> {
        let [a, p, b, q] = idx;
        let [n0, s1, _, s3] = self.shape;
        let (b0, nb) = self.rows2(a.min(n0.saturating_sub(1)));
        if a >= n0 || p >= s1 || b < b0 || b - b0 >= nb || q >= s3 {
            return None;
        }
        Some(((p * nb + (b - b0)) * s3 + q) * self.channels)
    }

    /// Offset of node `[a, p, b, q]` (its channel 0) in the whole array.
    pub fn offset(&self, idx: [usize; 4]) -> Option<usize> {
        Some(self.chunk_starts[idx[0].min(self.shape[0])] + self.offset_in_chunk(idx)?)
    }

    /// The node of row `r` of chunk `a` (a row = all axis-3 nodes × channels for one (p, b)).
    pub fn row_node(&self, a: usize, r: usize) -> (usize, usize) {
        let (b0, nb) = self.rows2(a);
        (r / nb, b0 + r % nb)
    }

    /// Number of rows in chunk `a`.
    pub fn rows_in_chunk(&self, a: usize) -> usize {
        self.shape[1] * self.rows2(a).1
    }

    /// Every stored node `[a, p, b, q]` in the stored order: chunk by chunk, row by row, axis 3
    /// innermost, so node k's values are `k·c..(k + 1)·c` of the whole array.
    pub fn stored_nodes(&self) -> impl Iterator<Item = [usize; 4]> + '_ {
        (0..self.chunk_count()).flat_map(move |a| {
            (0..self.rows_in_chunk(a)).flat_map(move |r| {
                let (p, b) = self.row_node(a, r);
                (0..self.shape[3]).map(move |q| [a, p, b, q])
            })
        })
    }
}
