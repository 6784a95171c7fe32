//! The prediction loop encoder and decoder share ([`run`]), and the 16-bit residual codes and
//! escapes it reads and writes.

use super::{Log16Params, to_log};
use crate::codec::filter::{self, Filter, Layout, Spatial, Word};

/// What the prediction loop runs on: grid indices (`i64`, wrapping, version 2) or
/// reconstructions (`f64`, version 1).
pub(super) trait State: Copy {
    fn add(self, o: Self) -> Self;
    fn sub(self, o: Self) -> Self;
}

impl State for f64 {
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self + o
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self - o
    }
}

impl State for i64 {
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.wrapping_add(o)
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self.wrapping_sub(o)
    }
}

/// The prediction loop shared by encoder and decoder. `step_fn(i, c, p)` returns the state of
/// point `i` (of channel `c`, which is `i % channels`: rows start at multiples of the channel
/// count) given its prediction `p`; `lo` predicts the first point of the chunk.
#[inline(always)]
pub(super) fn run<T: State>(
    n: usize,
    layout: Layout,
    filter: Filter,
    lo: T,
    r: &mut [T],
    mut step_fn: impl FnMut(usize, usize, T) -> T,
) {
    let ch = layout.channels;
    let row = layout.channels * layout.inner;
    let spatial = filter.spatial();
    let chan = filter.channel() && ch > 1;
    let linear_first = filter.linear_first();
    for (s, len, up) in filter::rows(n, layout) {
        let mut base_prev = lo;
        let mut c = 0usize;
        for j in 0..len {
            let i = s + j;
            let sp = if linear_first && c == 0 {
                Spatial::Linear
            } else {
                spatial
            };
            let base = if sp == Spatial::None {
                lo
            } else if j >= ch {
                match sp {
                    Spatial::Plane if up => r[i - ch].add(r[i - row]).sub(r[i - row - ch]),
                    Spatial::Linear if j >= 2 * ch => r[i - ch].add(r[i - ch].sub(r[i - 2 * ch])),
                    _ => r[i - ch],
                }
            } else if s >= row {
                r[i - row]
            } else {
                lo
            };
            let p = if chan && c != 0 {
                base.add(r[i - 1].sub(base_prev))
            } else {
                base
            };
            // The next channel's prediction continues from this channel's own-axis prediction
            // (for `LinearDeltaChannel`, the first channel's `Delta` one).
            let base = if linear_first && c == 0 {
                if j >= ch {
                    r[i - ch]
                } else if s >= row {
                    r[i - row]
                } else {
                    lo
                }
            } else {
                base
            };
            base_prev = base;
            r[i] = step_fn(i, c, p);
            c += 1;
            if c == ch {
                c = 0;
            }
        }
    }
}

/// The zigzagged 16-bit code of residual `q` (its low 16 bits when it does not fit).
pub(super) fn to_code(q: i64) -> u16 {
    (q as i16 as u16).zigzag()
}

pub(super) fn from_code(c: u16) -> i16 {
    c.unzigzag() as i16
}

/// The grid index of an escaped value `v` predicted as `p`, as encoder and decoder both form it:
/// the residual is `code`'s 16 bits plus the multiple of 2^16 that brings the index nearest to
/// `v`'s own `(L − lo) / step`. That estimate is within ½ + ε of the encoder's index, so the
/// result is exactly that index on any platform whose `ln` is off by less than 2^15 steps.
pub(super) fn resolve(p: i64, code: u16, v: f32, lo: f64, params: &Log16Params) -> i64 {
    let q16 = from_code(code) as i64;
    let ka = (to_log(v as f64, params.floor) - lo) / params.step;
    let m = ((ka - p as f64 - q16 as f64) / 65536.0).round() as i64;
    p.wrapping_add(q16).wrapping_add(m.wrapping_mul(65536))
}
