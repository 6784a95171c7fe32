//! A [`TabulatedBrdf`]'s nodes read back as stored ([`BakeSource::stored_node`]): a table
//! copied onto its own grid keeps its values, unmeasured ones included.

use super::TabulatedBrdf;
use crate::brdf::BakeSource;
use crate::geometry::HalfDiff;
use crate::table::grid::Param;

impl TabulatedBrdf {
    /// The node of stored coordinates `x` when `x` is one (to 1e-6 of a node spacing on every
    /// axis of size > 1).
    fn node_at(&self, x: [f64; 4]) -> Option<[usize; 4]> {
        let mut idx = [0usize; 4];
        for (d, ax) in self.grid.stored_axes().iter().enumerate() {
            if ax.size <= 1 {
                continue;
            }
            let s = ax.continuous(x[d]);
            let i = s.round();
            if !((s - i).abs() <= 1e-6) {
                return None;
            }
            let n = ax.size as f64;
            let i = if ax.periodic { i.rem_euclid(n) } else { i };
            if !(0.0..n).contains(&i) {
                return None;
            }
            idx[d] = i as usize;
        }
        Some(idx)
    }
}

impl BakeSource for TabulatedBrdf {
    /// The node at `hd` as stored, negative (unmeasured) values included, on `halfdiff` grids.
    fn stored_node(&self, hd: HalfDiff, out: &mut [f32]) -> bool {
        let c = self.lookup.channels();
        // A stored quantity other than f_r: such nodes are evaluated, not copied.
        if self.grid.param() != Param::HalfDiff || out.len() < c || self.finish {
            return false;
        }
        let x = crate::table::symmetry::canonical_half_diff(self.grid.symmetry(), hd);
        let Some(idx) = self.node_at(x) else {
            return false;
        };
        let Some(off) = self.grid.layout().offset_in_chunk(idx) else {
            return false;
        };
        let Some(v) = self.chunk(idx[0]).get(off..off + c) else {
            return false;
        };
        out[..c].copy_from_slice(v);
        let neg = self.unmeasured_of(idx[0]);
        let first = neg.partition_point(|e| (e.0 as usize) < off);
        for &(k, x) in neg[first..].iter().take_while(|e| (e.0 as usize) < off + c) {
            out[k as usize - off] = x;
        }
        true
    }
}
