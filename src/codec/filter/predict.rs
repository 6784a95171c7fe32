//! The prediction filters themselves, forward and inverse, row by row: the inverse runs on
//! the decoding of every chunk, so it stays with the forward filter it mirrors.

use super::{Filter, Layout, Spatial, Word};

/// Rows of the array: (start, length, whether the row above is in the same plane).
pub(crate) fn rows(n: usize, layout: Layout) -> impl Iterator<Item = (usize, usize, bool)> {
    let row = layout.row().max(1);
    let next = layout.next.max(1);
    (0..n.div_ceil(row)).map(move |r| {
        let s = r * row;
        (s, row.min(n - s), r % next != 0)
    })
}

/// Filters one row `words[s..s + len]` into `out` (zigzagged residuals).
#[inline]
fn forward_row<W: Word>(
    words: &[W],
    s: usize,
    len: usize,
    up: bool,
    layout: Layout,
    filter: Filter,
    out: &mut [W],
) {
    let ch = layout.channels.min(len);
    let row = layout.row();
    let cur = &words[s..s + len];
    // First point of the row: predicted by the row above (any plane), else stored as is.
    for j in 0..ch {
        out[j] = if s >= row {
            cur[j].wsub(words[s - row + j])
        } else {
            cur[j]
        };
    }
    match filter.spatial() {
        Spatial::Plane if up => {
            let prev = &words[s - row..s - row + len];
            for j in ch..len {
                out[j] = cur[j].wsub(cur[j - ch]).wsub(prev[j].wsub(prev[j - ch]));
            }
        }
        Spatial::Linear => {
            for j in ch..len.min(2 * ch) {
                out[j] = cur[j].wsub(cur[j - ch]);
            }
            for j in 2 * ch..len {
                let d = cur[j - ch].wsub(cur[j - 2 * ch]);
                out[j] = cur[j].wsub(cur[j - ch]).wsub(d);
            }
        }
        _ => {
            for j in ch..len {
                out[j] = cur[j].wsub(cur[j - ch]);
            }
        }
    }
    if filter.channel() && layout.channels > 1 {
        let c = layout.channels;
        for p in out[..len].chunks_mut(c) {
            for k in (1..p.len()).rev() {
                p[k] = p[k].wsub(p[k - 1]);
            }
        }
    }
    if filter.linear_first() {
        for j in (2 * ch..len).step_by(layout.channels) {
            let d = cur[j - ch].wsub(cur[j - 2 * ch]);
            out[j] = cur[j].wsub(cur[j - ch]).wsub(d);
        }
    }
    for o in &mut out[..len] {
        *o = o.zigzag();
    }
}

/// Applies `filter` to `words`, returning zigzagged residuals.
pub fn forward<W: Word>(words: &[W], layout: Layout, filter: Filter) -> Vec<W> {
    let mut out = vec![W::default(); words.len()];
    if filter == Filter::None {
        out.copy_from_slice(words);
        return out;
    }
    for (s, len, up) in rows(words.len(), layout) {
        forward_row(words, s, len, up, layout, filter, &mut out[s..s + len]);
    }
    out
}

/// Inverts [`forward`] in place: residuals in, words out.
pub fn inverse<W: Word>(words: &mut [W], layout: Layout, filter: Filter) {
    if filter == Filter::None {
        return;
    }
    let row = layout.row();
    for (s, len, up) in rows(words.len(), layout) {
        let ch = layout.channels.min(len);
        let (done, rest) = words.split_at_mut(s);
        let cur = &mut rest[..len];
        for w in cur.iter_mut() {
            *w = w.unzigzag();
        }
        if filter.linear_first() {
            inverse_linear_first(
                cur,
                (s >= row).then(|| &done[s - row..s - row + len]),
                layout,
            );
            continue;
        }
        if filter.channel() && layout.channels > 1 {
            for p in cur.chunks_mut(layout.channels) {
                for k in 1..p.len() {
                    p[k] = p[k].wadd(p[k - 1]);
                }
            }
        }
        if s >= row {
            let prev = &done[s - row..s - row + len];
            for j in 0..ch {
                cur[j] = cur[j].wadd(prev[j]);
            }
            if filter.spatial() == Spatial::Plane && up {
                for j in ch..len {
                    cur[j] = cur[j].wadd(prev[j].wsub(prev[j - ch]));
                }
            }
        }
        if filter.spatial() == Spatial::Linear {
            for j in ch..len.min(2 * ch) {
                cur[j] = cur[j].wadd(cur[j - ch]);
            }
            for j in 2 * ch..len {
                let d = cur[j - ch].wsub(cur[j - 2 * ch]);
                cur[j] = cur[j].wadd(cur[j - ch]).wadd(d);
            }
        } else {
            for j in ch..len {
                cur[j] = cur[j].wadd(cur[j - ch]);
            }
        }
    }
}

/// Inverts `LinearDeltaChannel` on one row of residuals `cur` (unzigzagged), point by point: a
/// channel's `Delta` residual follows from the previous channel's, which is known only once that
/// channel is decoded. `up` is the row above, if any.
fn inverse_linear_first<W: Word>(cur: &mut [W], up: Option<&[W]>, layout: Layout) {
    let c = layout.channels;
    let len = cur.len();
    for s in (0..len).step_by(c) {
        let pc = c.min(len - s);
        // The Delta prediction of channel k of this point.
        let base = |cur: &[W], k: usize| {
            if s >= c {
                cur[s + k - c]
            } else {
                up.map_or(W::default(), |u| u[s + k])
            }
        };
        let mut d = if s >= 2 * c {
            let p = cur[s - c].wadd(cur[s - c].wsub(cur[s - 2 * c]));
            cur[s] = cur[s].wadd(p);
            cur[s].wsub(base(cur, 0))
        } else {
            let d = cur[s];
            cur[s] = d.wadd(base(cur, 0));
            d
        };
        for k in 1..pc {
            d = cur[s + k].wadd(d);
            cur[s + k] = d.wadd(base(cur, k));
        }
    }
}

/// Appends to `out` the residuals of every `every`-th row (starting with row 1 when there are
/// more than `every` rows, else every row): a sample of what `filter` would leave.
pub(crate) fn forward_sample<W: Word>(
    words: &[W],
    layout: Layout,
    filter: Filter,
    every: usize,
    out: &mut Vec<W>,
) {
    let every = every.max(1);
    let all = words.len() <= every.saturating_mul(layout.row());
    for (k, (s, len, up)) in rows(words.len(), layout).enumerate() {
        if !all && k % every != 1 {
            continue;
        }
        let at = out.len();
        out.resize(at + len, W::default());
        if filter == Filter::None {
            out[at..].copy_from_slice(&words[s..s + len]);
        } else {
            forward_row(words, s, len, up, layout, filter, &mut out[at..]);
        }
    }
}
