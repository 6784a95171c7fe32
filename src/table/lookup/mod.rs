//! Interpolated lookup in stored values: nearest and multilinear.
//!
//! A lookup maps the pair to canonical stored coordinates
//! ([`canonical_coords`]), then per stored axis to nodes and
//! weights ([`StoredAxis::nearest`], [`StoredAxis::linear`]): clamped on θ axes and folded φ
//! axes, wrapping on periodic φ axes. Linear interpolation visits the 2^k corners of the cell
//! (k = axes whose weight is not 0, so axes of size 1 and exact node coordinates cost nothing)
//! and accumulates weight × the node's values for every channel — λ is innermost, so one set of
//! weights serves all channels. Corners of a packed `inout` (reciprocal) table below the
//! diagonal are replaced by their reciprocal node. Nothing here allocates.

use glam::DVec3;

use crate::table::grid::{Grid, Layout, Param, StoredAxis};
use crate::table::symmetry::{
    Symmetry, canonical_coords, canonical_coords_fast, canonical_corner_inout,
};

mod cube;
mod interp;

pub use cube::{Cube, Prepared};
pub use interp::Interp;

/// Everything a lookup needs from the grid, copied into a compact form.
#[derive(Debug, Clone)]
pub struct Lookup {
    param: Param,
    sym: Symmetry,
    axes: [StoredAxis; 4],
    shape: [usize; 4],
    packed: bool,
    channels: usize,
    /// Full φo size (for reciprocal corners of packed inout tables).
    n3_full: usize,
}

impl Lookup {
    /// Lookup state for `grid`.
    pub fn new(grid: &Grid) -> Lookup {
        let l: &Layout = grid.layout();
        Lookup {
            param: grid.param(),
            sym: grid.symmetry(),
            axes: grid.stored_axes().clone(),
            shape: l.shape,
            packed: l.packed,
            channels: l.channels,
            n3_full: grid.axes()[3].size,
        }
    }

    /// Number of channels.
    pub fn channels(&self) -> usize {
        self.channels
    }

    #[inline(always)]
    fn offset(&self, idx: [usize; 4]) -> (usize, usize) {
        let [a, p, b, q] = if self.packed {
            canonical_corner_inout(self.sym, idx, self.n3_full)
        } else {
            idx
        };
        let (b0, nb) = if self.packed {
            (a, self.shape[2] - a)
        } else {
            (0, self.shape[2])
        };
        (a, ((p * nb + (b - b0)) * self.shape[3] + q) * self.channels)
    }

    /// Evaluates into `out[..channels]`; `chunk(a)` returns the values of chunk `a` (an empty
    /// slice when it could not be loaded: its corners then count as 0).
    #[inline]
    pub fn eval<'a>(
        &self,
        interp: Interp,
        wi: DVec3,
        wo: DVec3,
        out: &mut [f32],
        chunk: impl Fn(usize) -> &'a [f32],
    ) {
        let c = self.channels;
        let out = &mut out[..c];
        out.fill(0.0);
        let x = match interp {
            Interp::Nearest => canonical_coords(self.param, self.sym, wi, wo),
            Interp::Linear => canonical_coords_fast(self.param, self.sym, wi, wo),
        };
        let Some(x) = x else {
            return;
        };
        let ax = &self.axes;
        match interp {
            Interp::Nearest => {
                let idx = [
                    ax[0].nearest(x[0]),
                    ax[1].nearest(x[1]),
                    ax[2].nearest(x[2]),
                    ax[3].nearest(x[3]),
                ];
                let (a, off) = self.offset(idx);
                if let Some(v) = chunk(a).get(off..off + c) {
                    out.copy_from_slice(v);
                }
            }
            Interp::Linear => {
                let l = self.linear_nodes(x);
                if self.packed {
                    self.accumulate_packed(&l, out, chunk);
                } else if l[1].2 == 0.0 && c == 3 {
                    // Isotropic tables (axis 1 of size 1) and any lookup on an axis-1 node.
                    self.cube(&l, &chunk).gather::<3>(out);
                } else if l[1].2 == 0.0 && c == 1 {
                    self.cube(&l, &chunk).gather::<1>(out);
                } else {
                    match c {
                        1 => self.accumulate::<1>(&l, out, chunk),
                        3 => self.accumulate::<3>(&l, out, chunk),
                        _ => self.accumulate::<0>(&l, out, chunk),
                    }
                }
            }
        }
    }

    /// Multilinear accumulation for unpacked layouts: constant strides, one chunk per θ1 node.
    /// `N` > 0: exactly N channels, accumulated in registers; `N` = 0: any count, in `out`.
    #[inline(always)]
    fn accumulate<'a, const N: usize>(
        &self,
        l: &[(usize, usize, f32); 4],
        out: &mut [f32],
        chunk: impl Fn(usize) -> &'a [f32],
    ) {
        let c = self.channels;
        let s3 = self.shape[3];
        let (sp, sb) = (self.shape[2] * s3 * c, s3 * c);
        let m = |k: usize| if l[k].2 == 0.0 { 1 } else { 2 };
        let node = |k: usize, j: usize| if j == 0 { l[k].0 } else { l[k].1 };
        let w = |k: usize, j: usize| if j == 0 { 1.0 - l[k].2 } else { l[k].2 };
        let (m1, m2, m3) = (m(1), m(2), m(3));
        let mut acc = [0.0f32; N];
        for j0 in 0..m(0) {
            let w0 = w(0, j0);
            let data = chunk(node(0, j0));
            for j1 in 0..m1 {
                let w1 = w0 * w(1, j1);
                let o1 = node(1, j1) * sp;
                for j2 in 0..m2 {
                    let w2 = w1 * w(2, j2);
                    let o2 = o1 + node(2, j2) * sb;
                    for j3 in 0..m3 {
                        let wt = w2 * w(3, j3);
                        let off = o2 + node(3, j3) * c;
                        if N > 0 {
                            if let Some(v) = data.get(off..off + N) {
                                for k in 0..N {
                                    acc[k] += wt * v[k];
                                }
                            }
                        } else if let Some(v) = data.get(off..off + c) {
                            for (o, &x) in out.iter_mut().zip(v) {
                                *o += wt * x;
                            }
                        }
                    }
                }
            }
        }
        if N > 0 {
            out[..N].copy_from_slice(&acc);
        }
    }

    /// Nodes and weights of a linear lookup at canonical coordinates `x`, per stored axis.
    #[inline(always)]
    fn linear_nodes(&self, x: [f64; 4]) -> [(usize, usize, f32); 4] {
        let ax = &self.axes;
        [
            ax[0].linear(x[0]),
            ax[1].linear(x[1]),
            ax[2].linear(x[2]),
            ax[3].linear(x[3]),
        ]
    }

    /// The eight corners of a lookup on an unpacked layout with axis 1 on a node (always so
    /// for isotropic tables, where it has size 1); the caller checks both.
    #[inline(always)]
    fn cube<'a>(
        &self,
        l: &[(usize, usize, f32); 4],
        chunk: &impl Fn(usize) -> &'a [f32],
    ) -> Cube<'a> {
        let c = self.channels;
        let s3 = self.shape[3];
        let (sp, sb) = (self.shape[2] * s3 * c, s3 * c);
        let base = l[1].0 * sp;
        // A second θ1 node of weight 0 is not touched (it may be a chunk not yet decoded).
        let d0 = chunk(l[0].0);
        Cube {
            data: [d0, if l[0].2 == 0.0 { d0 } else { chunk(l[0].1) }],
            ob: [base + l[2].0 * sb, base + l[2].1 * sb],
            oq: [l[3].0 * c, l[3].1 * c],
            wa: [1.0 - l[0].2, l[0].2],
            wb: [1.0 - l[2].2, l[2].2],
            wq: [1.0 - l[3].2, l[3].2],
        }
    }

    /// The first phase of a linear lookup, for batches: coordinates, nodes and weights, without
    /// reading any stored value, so that a caller can prefetch the corners of several lookups
    /// before gathering them ([`Prepared::gather`]).
    #[inline]
    pub fn prepare<'a>(
        &self,
        wi: DVec3,
        wo: DVec3,
        chunk: impl Fn(usize) -> &'a [f32],
    ) -> Prepared<'a> {
        let c = self.channels;
        if self.packed || !(c == 3 || c == 1) {
            return Prepared::General;
        }
        let Some(x) = canonical_coords_fast(self.param, self.sym, wi, wo) else {
            return Prepared::Zero;
        };
        let l = self.linear_nodes(x);
        if l[1].2 != 0.0 {
            return Prepared::General;
        }
        Prepared::Cube(self.cube(&l, &chunk))
    }

    /// Multilinear accumulation for packed `inout` reciprocity: corners below the diagonal are
    /// replaced by their reciprocal node.
    fn accumulate_packed<'a>(
        &self,
        l: &[(usize, usize, f32); 4],
        out: &mut [f32],
        chunk: impl Fn(usize) -> &'a [f32],
    ) {
        let c = self.channels;
        let m = |k: usize| if l[k].2 == 0.0 { 1 } else { 2 };
        let node = |k: usize, j: usize| if j == 0 { l[k].0 } else { l[k].1 };
        let w = |k: usize, j: usize| if j == 0 { 1.0 - l[k].2 } else { l[k].2 };
        for j0 in 0..m(0) {
            let w0 = w(0, j0);
            for j1 in 0..m(1) {
                let w1 = w0 * w(1, j1);
                for j2 in 0..m(2) {
                    let w2 = w1 * w(2, j2);
                    for j3 in 0..m(3) {
                        let wt = w2 * w(3, j3);
                        let (a, off) =
                            self.offset([node(0, j0), node(1, j1), node(2, j2), node(3, j3)]);
                        if let Some(v) = chunk(a).get(off..off + c) {
                            for (o, &x) in out.iter_mut().zip(v) {
                                *o += wt * x;
                            }
                        }
                    }
                }
            }
        }
    }
}
