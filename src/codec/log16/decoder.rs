//! The log16 decoder ([`decode`]): the prediction repeated over the codes, escapes taken from
//! their exact values. Table lookups wait on it, so it stays one function.

use super::predict::{from_code, resolve, run};
use super::{Log16Params, from_log, to_log, value_at};
use crate::codec::filter::{Filter, Layout};

/// Decodes codes into `out` (same length), given the chunk's escapes (sorted, in range) and
/// its per-channel grid origins (`anchors`, one per channel of `layout`; empty for chunks of
/// version 1 and 2, whose grid starts at `params.lo`).
pub fn decode(
    codes: &[u16],
    params: &Log16Params,
    layout: Layout,
    filter: Filter,
    escapes: &[(u32, f32)],
    anchors: &[f64],
    out: &mut [f32],
) {
    let n = codes.len();
    let mut e = escapes.iter().peekable();
    let (lo, step, floor) = (params.lo, params.step, params.floor);
    let mut escaped = |i: usize| match e.peek() {
        Some(&&(k, v)) if k as usize == i => {
            e.next();
            Some(v)
        }
        _ => None,
    };
    if !anchors.is_empty() {
        // Chunk version 3: per-channel origins, index 0 is exactly 0.
        let mut state = vec![0i64; n];
        run(n, layout, filter, 0i64, &mut state, |i, c, p| {
            let lo = anchors.get(c).copied().unwrap_or(0.0);
            if let Some(v) = escaped(i) {
                out[i] = v;
                return resolve(p, codes[i], v, lo, params);
            }
            let k = p.wrapping_add(from_code(codes[i]) as i64);
            out[i] = value_at(k, lo, step, floor);
            k
        });
    } else if params.grid {
        let mut state = vec![0i64; n];
        run(n, layout, filter, 0i64, &mut state, |i, _, p| {
            if let Some(v) = escaped(i) {
                out[i] = v;
                return resolve(p, codes[i], v, lo, params);
            }
            let k = p.wrapping_add(from_code(codes[i]) as i64);
            out[i] = from_log(lo + k as f64 * step, floor);
            k
        });
    } else {
        // Chunk version 1: an escaped value continues the prediction from its exact L.
        let mut r = vec![0.0f64; n];
        run(n, layout, filter, lo, &mut r, |i, _, p| {
            if let Some(v) = escaped(i) {
                out[i] = v;
                return to_log(v as f64, floor);
            }
            let rec = p + from_code(codes[i]) as f64 * step;
            out[i] = from_log(rec, floor);
            rec
        });
    }
}
