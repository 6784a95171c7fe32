//! log16: error-bounded 16-bit coding of values in the log domain, with prediction.
//!
//! Each value `v` is mapped to `L = g(v)`, where `g` is logarithmic above the floor `F` and
//! linear below it, odd in `v` and C¹ at `|v| = F`:
//!
//! ```text
//! g(v) = v / F                          for |v| ≤ F
//! g(v) = sign(v) · (1 + ln(|v| / F))    for |v| > F
//! ```
//!
//! so a uniform step in `L` is a relative step above the floor and an absolute one below it,
//! and negative values (measured data has them) are coded like positive ones.
//!
//! Each `L` is rounded to the grid `lo + k·step` (`lo` = 0): `k = round((L − lo) / step)`, an
//! integer of any size. A predictor `P` of `k` from earlier points (previous point along the
//! innermost axis, the extrapolation `2·left − left-left`, or the planar `left + up − up-left`,
//! optionally plus the previous channel's prediction error — the same family as [`Filter`]) runs
//! in exact integer arithmetic, and the residual `q = k − P` is stored as a zigzagged 16-bit code.
//! Decoding repeats the prediction, `k = P + q`, and gives `v̂ = g⁻¹(lo + k·step)`. There is no
//! limit on the dynamic range of a chunk: a residual that does not fit 16 bits costs one escape
//! (below). Because `k` does
//! not depend on the predictor, the encoder quantizes once and tries predictors on integers
//! (cheap), and `L = 0` (`v = 0`) decodes to exactly 0; a value below `step/2` in `L` decodes to 0
//! rather than to the other sign.
//!
//! **Anchored grids (chunk version 3).** A grid from 0 puts a constant up to half a step from
//! the nearest grid point, so a Lambert table decoded 5.7e-4 (relative) off kd. From version 3
//! each channel `c` has its own origin `lo_c` ([`Encoded::anchors`], |lo_c| ≤ step/2) chosen so
//! that the channel's most common value `m` is a grid point, `g(m) = lo_c + k_m·step`, checked
//! to round back to `m` bit for bit: constant chunks and the value a chunk repeats most decode
//! exactly, and index 0 still decodes to exactly 0. The most common value is found with a
//! Misra–Gries pass (4 counters: anything above a fifth of the channel is found) and one exact
//! recount; with no repeated value, or one within half a step of 0, the origin is 0. Residuals,
//! predictors and the bound below are unchanged: the grid is only shifted.
//!
//! Chunk version 1 formed the reconstructions in f64 *inside* the prediction loop
//! (`R = P + round((L − P)/step)·step`, DPCM as in the SZ compressors). With the second-order
//! predictor that loop amplifies the rounding noise around zero so that thousands of tiny values
//! decode with the wrong sign and must be stored exactly; on the grid the noise is the same and
//! the sign comes for free. Version-1 chunks still decode ([`Log16Params::grid`] = false).
//!
//! # The guarantee
//!
//! `|lo + k·step − L| ≤ step/2` gives `|v̂ − v| ≤ (v + floor)(e^{step/2} − 1)`; with
//! `step = 2·ln(1 + tol)·0.98` that is at most `0.98·tol·(v + floor)`, inside the bound
//! `tol·max(v, floor)` except for values within a factor ~50 of the floor. The encoder therefore
//! decodes every value exactly as the decoder will and checks the bound; a value that misses it
//! — or would decode with the other sign, or whose residual does not fit 16 bits — is stored
//! exactly in an escape list. Its residual's low 16 bits are stored all the same, and the decoder
//! takes the rest from the exact value (the multiple of 2^16 that lands nearest its `L`), so the
//! decoder's `k` — hence every later prediction — equals the encoder's, in integers, on every
//! platform. So **every** decoded value satisfies
//! `|v̂ − v| ≤ tol·max(|v|, floor)` and has the sign of `v` (a non-negative table never decodes
//! to a negative value, which a BRDF must not return).
//!
//! The floor is `1e-7 ×` the chunk's largest magnitude unless given explicitly (absolute), and is
//! stored in the chunk header: below it the error bound is absolute (`tol·floor`).
//!
//! Decoding uses `exp`/`ln` from the platform's libm; results are deterministic on a platform and
//! may differ in the last ulp across platforms (well inside the 2% margin of the bound).

use super::filter::{self, Filter, Layout, Spatial, Word};
use crate::error::{Error, Result};

/// The per-chunk parameters of log16, stored in the chunk header.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Log16Params {
    /// The origin of the grid (0, i.e. `v = 0`; version 3 adds per-channel origins,
    /// [`Encoded::anchors`]); version 1: the prediction for the first point.
    pub lo: f64,
    /// Quantization step of the residuals, in ln units.
    pub step: f64,
    /// The absolute floor: below it the error is bounded by `tol·floor`.
    pub floor: f64,
    /// Reconstructions on the integer grid `lo + k·step` (chunk version 2); `false`: formed in
    /// f64 inside the prediction loop (version 1, decoded for old files).
    pub grid: bool,
}

impl Log16Params {
    /// Checks parameters read from a file.
    pub fn valid(&self) -> bool {
        self.lo.is_finite()
            && self.step.is_finite()
            && self.step > 0.0
            && self.floor.is_finite()
            && self.floor > 0.0
    }
}

/// Smallest tolerance accepted (below it f32 rounding alone approaches the bound).
pub const MIN_TOL: f64 = 1e-6;
/// Smallest floor used.
pub const MIN_FLOOR: f64 = 1e-30;
/// Default floor as a fraction of the chunk's largest magnitude.
pub const FLOOR_RATIO: f64 = 1e-7;

/// The residual step for tolerance `tol`.
pub fn step(tol: f64) -> f64 {
    2.0 * tol.ln_1p() * 0.98
}

/// The result of encoding a chunk.
#[derive(Debug, Clone)]
pub struct Encoded {
    /// Predictor used.
    pub filter: Filter,
    /// Zigzagged residual codes (at escaped positions: the residual's low 16 bits).
    pub codes: Vec<u16>,
    /// Chunk parameters.
    pub params: Log16Params,
    /// Exactly stored values: (index, value), indices strictly increasing.
    pub escapes: Vec<(u32, f32)>,
    /// The grid origin of each channel (chunk version 3, see [the module docs](self)): channel
    /// `c`'s grid is `anchors[c] + k·step` and index 0 decodes to exactly 0. Empty: the grid is
    /// `params.lo + k·step` for every channel (version 2).
    pub anchors: Vec<f64>,
}

/// The most frequent value of channel `c` (every `ch`-th value of `data` from `c`) and how
/// often it occurs: a Misra–Gries pass with [`HEAVY`] counters (which finds every value making
/// up more than 1/(HEAVY + 1) of the channel), then an exact count of the strongest candidate.
/// `None` when no value occurs twice.
fn most_common(data: &[f32], c: usize, ch: usize) -> Option<(f32, usize)> {
    let mut keys = [0u32; HEAVY];
    let mut count = [0usize; HEAVY];
    'values: for v in data.iter().skip(c).step_by(ch) {
        let b = v.to_bits();
        for j in 0..HEAVY {
            if count[j] > 0 && keys[j] == b {
                count[j] += 1;
                continue 'values;
            }
        }
        for j in 0..HEAVY {
            if count[j] == 0 {
                keys[j] = b;
                count[j] = 1;
                continue 'values;
            }
        }
        for n in &mut count {
            *n -= 1;
        }
    }
    let j = (0..HEAVY).max_by_key(|&j| count[j])?;
    if count[j] == 0 {
        return None;
    }
    let n = data
        .iter()
        .skip(c)
        .step_by(ch)
        .filter(|v| v.to_bits() == keys[j])
        .count();
    (n >= 2).then(|| (f32::from_bits(keys[j]), n))
}

/// Counters of [`most_common`].
const HEAVY: usize = 4;

/// The grid origin that puts `m` on the grid: `lo = g(m) − k_m·step` with `k_m` the nearest
/// index, so `|lo| ≤ step/2` and `g⁻¹(lo + k_m·step)` rounds back to `m` exactly; 0 when `m` is
/// within half a step of 0 (index 0 decodes to 0 anyway) or when that round trip misses `m`.
fn anchor(m: f32, floor: f64, step: f64) -> f64 {
    let l = to_log(m as f64, floor);
    let km = (l / step).round();
    if km == 0.0 {
        return 0.0;
    }
    let lo = l - km * step;
    if from_log(lo + km * step, floor).to_bits() == m.to_bits() {
        lo
    } else {
        0.0
    }
}

/// `g⁻¹(lo + k·step)` on an anchored grid: index 0 is exactly 0.
#[inline(always)]
fn value_at(k: i64, lo: f64, step: f64, floor: f64) -> f32 {
    if k == 0 {
        0.0
    } else {
        from_log(lo + k as f64 * step, floor)
    }
}

/// What the prediction loop runs on: grid indices (`i64`, wrapping, version 2) or
/// reconstructions (`f64`, version 1).
trait State: Copy {
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
fn run<T: State>(
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
fn to_code(q: i64) -> u16 {
    (q as i16 as u16).zigzag()
}

fn from_code(c: u16) -> i16 {
    c.unzigzag() as i16
}

/// The grid index of an escaped value `v` predicted as `p`, as encoder and decoder both form it:
/// the residual is `code`'s 16 bits plus the multiple of 2^16 that brings the index nearest to
/// `v`'s own `(L − lo) / step`. That estimate is within ½ + ε of the encoder's index, so the
/// result is exactly that index on any platform whose `ln` is off by less than 2^15 steps.
fn resolve(p: i64, code: u16, v: f32, lo: f64, params: &Log16Params) -> i64 {
    let q16 = from_code(code) as i64;
    let ka = (to_log(v as f64, params.floor) - lo) / params.step;
    let m = ((ka - p as f64 - q16 as f64) / 65536.0).round() as i64;
    p.wrapping_add(q16).wrapping_add(m.wrapping_mul(65536))
}

/// Encodes `data` with relative tolerance `tol` (see the module docs for the guarantee).
/// `floor`: absolute floor, or `None` for `1e-7 ×` the chunk's largest magnitude. `filter`: force
/// a predictor, or `None` to pick one ([`choose`](super::choose::choose) on the grid indices).
pub fn encode(
    data: &[f32],
    layout: Layout,
    tol: f64,
    floor: Option<f64>,
    filter: Option<Filter>,
) -> Result<Encoded> {
    super::quantize::check_finite(data)?;
    if !(tol.is_finite() && (MIN_TOL..=0.5).contains(&tol)) {
        return Err(Error::Encode {
            msg: format!(
                "log16 tolerance {tol} is outside [{MIN_TOL}, 0.5]; use codec f32 for lossless storage"
            ),
        });
    }
    if let Some(f) = floor
        && !(f.is_finite() && f > 0.0)
    {
        return Err(Error::Encode {
            msg: format!("log16 floor {f} must be a positive number"),
        });
    }
    if data.len() > u32::MAX as usize {
        return Err(Error::Encode {
            msg: "log16 chunks hold at most 2^32 - 1 values".into(),
        });
    }
    let amax = data.iter().fold(0.0f64, |m, v| m.max(v.abs() as f64));
    let floor = floor.unwrap_or((amax * FLOOR_RATIO).max(MIN_FLOOR));
    let params = Log16Params {
        lo: 0.0,
        step: step(tol),
        floor,
        grid: true,
    };
    let n = data.len();
    let inv = 1.0 / params.step;
    // Each channel's grid goes through its most common value, so a constant chunk — a Lambert
    // table — and the value a chunk repeats most decode exactly.
    let ch = layout.channels.max(1);
    let anchors: Vec<f64> = (0..ch)
        .map(|c| most_common(data, c, ch).map_or(0.0, |(m, _)| anchor(m, floor, params.step)))
        .collect();
    // Grid index of every value, and whether it decodes within the bound and with its sign: both
    // independent of the predictor. |L| ≤ 1 + ln(f32::MAX / MIN_FLOOR) < 160, so |k| < 1e8.
    let mut k = Vec::with_capacity(n);
    let mut ok = Vec::with_capacity(n);
    for (i, &v) in data.iter().enumerate() {
        let lo = anchors[i % ch];
        let kt = ((to_log(v as f64, floor) - lo) * inv).round();
        let back = value_at(kt as i64, lo, params.step, floor) as f64;
        let a = v as f64;
        // Sign-preserving: a non-negative value (a BRDF) must never decode negative.
        let same_sign = if a >= 0.0 { back >= 0.0 } else { back <= 0.0 };
        ok.push(same_sign && (back - a).abs() <= tol * a.abs().max(floor));
        k.push(kt as i64);
    }
    // Residuals of the indices as wrapped 16-bit words equal the true ones whenever those fit.
    let filter = filter.unwrap_or_else(|| {
        let words: Vec<u16> = k.iter().map(|&x| x as u16).collect();
        super::choose::choose(&words, layout)
    });

    let mut codes = vec![0u16; n];
    let mut escapes = Vec::new();
    let mut state = vec![0i64; n];
    run(n, layout, filter, 0i64, &mut state, |i, c, p| {
        let q = k[i].wrapping_sub(p);
        let code = to_code(q);
        codes[i] = code;
        if q == from_code(code) as i64 && ok[i] {
            return k[i];
        }
        escapes.push((i as u32, data[i]));
        let r = resolve(p, code, data[i], anchors[c], &params);
        debug_assert_eq!(r, k[i]);
        r
    });
    if escapes.len() > n / 2 && n >= 16 {
        let neg = escapes.iter().filter(|e| e.1 < 0.0).count();
        return Err(Error::Encode {
            msg: format!(
                "log16 would store {} of {n} values exactly ({neg} negative): the data are too \
                 rough for tolerance {tol}; loosen the tolerance or use f16/f32",
                escapes.len()
            ),
        });
    }
    Ok(Encoded {
        filter,
        codes,
        params,
        escapes,
        anchors,
    })
}

/// `g(v)` (see the module docs).
#[inline]
pub fn to_log(v: f64, floor: f64) -> f64 {
    let a = v.abs();
    if a <= floor {
        v / floor
    } else {
        (1.0 + (a / floor).ln()).copysign(v)
    }
}

/// `g⁻¹(y)` as f32.
#[inline]
pub fn from_log(y: f64, floor: f64) -> f32 {
    let a = y.abs();
    (if a <= 1.0 {
        y * floor
    } else {
        (floor * (a - 1.0).exp()).copysign(y)
    }) as f32
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn decoded(q: &Encoded, layout: Layout) -> Vec<f32> {
        let mut out = vec![0.0; q.codes.len()];
        decode(
            &q.codes, &q.params, layout, q.filter, &q.escapes, &q.anchors, &mut out,
        );
        out
    }

    proptest! {
        /// Without escapes, log16's prediction loop is the integer filter of the same id applied
        /// to the grid indices: the chooser's proxy is exact, and the two implementations agree.
        #[test]
        fn codes_are_the_filter_residuals_of_the_grid_indices(
            n in 0usize..400, ch in 1usize..5, inner in 1usize..12, next in 1usize..4,
            f in 0u8..8, freq in 0.01f32..0.5, tol in prop_oneof![Just(1e-3), Just(1e-2)],
        ) {
            let data: Vec<f32> = (0..n).map(|k| 1.0 + 0.5 * (k as f32 * freq).sin()).collect();
            let layout = Layout::new(ch, inner, next);
            let filter = Filter::from_u8(f).unwrap();
            let q = encode(&data, layout, tol, None, Some(filter)).unwrap();
            prop_assert!(q.escapes.is_empty());
            let k: Vec<u16> = data
                .iter()
                .enumerate()
                .map(|(i, &v)| {
                    let lo = q.anchors[i % ch];
                    ((to_log(v as f64, q.params.floor) - lo) / q.params.step).round() as i64 as u16
                })
                .collect();
            let mut want = filter::forward(&k, layout, filter);
            if filter == Filter::None {
                want.iter_mut().for_each(|w| *w = w.zigzag());
            }
            prop_assert_eq!(&q.codes, &want);
            for (a, b) in data.iter().zip(decoded(&q, layout)) {
                prop_assert!((a - b).abs() as f64 <= tol * (*a as f64));
            }
        }

        /// Every filter keeps the bound and the sign, on data with zeros, tiny values of both
        /// signs around the floor, and jumps larger than 16-bit residuals (tolerance 1e-5).
        #[test]
        fn every_filter_keeps_the_bound_and_the_sign(
            data in proptest::collection::vec(prop_oneof![
                Just(0.0f32), -1e-6f32..1e-6, 0.5f32..2.0, 1e20f32..1e30, -1e3f32..-1e-3,
            ], 0..200),
            ch in 1usize..4, inner in 1usize..10, f in 0u8..8,
            tol in prop_oneof![Just(1e-5), Just(1e-3), Just(0.1)],
        ) {
            let layout = Layout::new(ch, inner, 3);
            let filter = Filter::from_u8(f).unwrap();
            let q = match encode(&data, layout, tol, Some(1e-4), Some(filter)) {
                Ok(q) => q,
                Err(e) => {
                    prop_assert!(e.to_string().contains("exactly"), "{}", e);
                    return Ok(());
                }
            };
            for (a, b) in data.iter().zip(decoded(&q, layout)) {
                let (a, b) = (*a as f64, b as f64);
                prop_assert!((a - b).abs() <= tol * a.abs().max(1e-4), "{} -> {}", a, b);
                prop_assert!(a * b >= 0.0, "{} -> {} changed sign", a, b);
            }
        }
    }

    #[test]
    fn zero_and_values_far_below_the_floor_decode_to_exactly_zero_without_escapes() {
        let v: Vec<f32> = (0..300)
            .map(|i| match i % 3 {
                0 => 0.0,
                1 => 1e-14 * (i as f32),
                _ => 1.0 + (i as f32 * 0.01).sin(),
            })
            .collect();
        let layout = Layout::new(3, 20, 5);
        for filter in Filter::ALL {
            let q = encode(&v, layout, 1e-3, None, Some(filter)).unwrap();
            assert!(q.escapes.is_empty(), "{filter:?}: {:?}", q.escapes);
            let out = decoded(&q, layout);
            for (i, (a, b)) in v.iter().zip(&out).enumerate() {
                if i % 3 != 2 {
                    assert_eq!(*b, 0.0, "{filter:?} [{i}]: {a} -> {b}");
                }
            }
        }
    }

    #[test]
    fn an_overflowing_residual_escapes_and_later_values_recover() {
        // Tolerance 1e-5 and an explicit floor of 1e-30: the first value (predicted from 0) and
        // the jumps to and from 1e30 are millions of steps, far beyond a 16-bit residual. Those
        // three are escaped; the decoder recovers their exact grid index, so the rest is coded.
        let mut v = vec![1.0f32; 60];
        v[30] = 1e30;
        let q = encode(&v, Layout::FLAT, 1e-5, Some(1e-30), Some(Filter::Delta)).unwrap();
        let at: Vec<u32> = q.escapes.iter().map(|e| e.0).collect();
        assert_eq!(at, [0, 30, 31]);
        assert!(q.codes[1..30].iter().all(|&c| c == 0));
        let out = decoded(&q, Layout::FLAT);
        for (a, b) in v.iter().zip(&out) {
            assert!(((a - b).abs() as f64) <= 1e-5 * *a as f64, "{a} -> {b}");
        }
    }

    #[test]
    fn nan_is_refused_naming_the_index() {
        let e = encode(&[0.0, 0.0, f32::NAN], Layout::FLAT, 1e-3, None, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("index 2") && e.contains("NaN"), "{e}");
    }

    #[test]
    fn negatives_are_coded_within_the_bound() {
        let v = [1.0, -0.5, 2.0, -1e-9, -3e5];
        let q = encode(&v, Layout::FLAT, 1e-3, None, None).unwrap();
        let mut out = [0.0; 5];
        decode(
            &q.codes,
            &q.params,
            Layout::FLAT,
            q.filter,
            &q.escapes,
            &q.anchors,
            &mut out,
        );
        for (a, b) in v.iter().zip(&out) {
            assert!(
                ((a - b).abs() as f64) <= 1e-3 * (a.abs() as f64).max(q.params.floor),
                "{a} {b}"
            );
        }
    }

    #[test]
    fn mapping_is_monotone_and_inverts() {
        let f = 1e-3;
        let mut prev = f64::NEG_INFINITY;
        for k in -2000..2000 {
            let v = (k as f64 / 100.0).sinh() * 1e-3;
            let y = to_log(v, f);
            assert!(y > prev);
            prev = y;
            assert!((from_log(y, f) as f64 - v).abs() <= 1e-6 * v.abs().max(f));
        }
    }

    #[test]
    fn rough_data_fails_clearly() {
        // Alternating ±1e30 / tiny at a tight tolerance: residuals overflow 16 bits.
        let v: Vec<f32> = (0..100)
            .map(|i| if i % 2 == 0 { 1e30 } else { -1e30 })
            .collect();
        let e = encode(&v, Layout::FLAT, 1e-6, Some(1e-30), Some(Filter::Delta))
            .unwrap_err()
            .to_string();
        assert!(e.contains("exactly"), "{e}");
    }

    #[test]
    fn smooth_data_gives_small_residuals() {
        let v: Vec<f32> = (0..1000)
            .map(|i| (-(i as f32 - 500.0).powi(2) / 5e4).exp())
            .collect();
        let q = encode(&v, Layout::new(1, 100, 10), 1e-3, None, None).unwrap();
        let small = q.codes.iter().filter(|&&c| c <= 8).count();
        assert!(small > 850, "{small}");
        let mut out = vec![0.0; v.len()];
        decode(
            &q.codes,
            &q.params,
            Layout::new(1, 100, 10),
            q.filter,
            &q.escapes,
            &q.anchors,
            &mut out,
        );
        for (a, b) in v.iter().zip(&out) {
            assert!((a - b).abs() as f64 <= 1e-3 * (*a as f64).max(q.params.floor));
        }
    }
}

#[cfg(test)]
mod anchor_tests {
    use super::*;

    fn round_trip(data: &[f32], layout: Layout, tol: f64) -> (Encoded, Vec<f32>) {
        let q = encode(data, layout, tol, None, None).unwrap();
        let mut out = vec![0.0; data.len()];
        decode(
            &q.codes, &q.params, layout, q.filter, &q.escapes, &q.anchors, &mut out,
        );
        (q, out)
    }

    /// A constant chunk per channel (a Lambert table) decodes bit for bit, without escapes, at
    /// every tolerance, for channels up to 10^7 apart (the floor is 10^-7 of the largest value;
    /// far below it the bound is absolute and a value may decode to 0).
    #[test]
    fn constant_channels_decode_exactly() {
        for kd in [[0.1f32, 0.2, 0.3], [1e-6, 3.0e-5, 7.5], [4.0e4, 0.5, 1e-3]] {
            let data: Vec<f32> = (0..3 * 90 * 46).map(|i| kd[i % 3]).collect();
            for tol in [1e-3, 1e-2, 0.1] {
                let (q, out) = round_trip(&data, Layout::new(3, 46, 90), tol);
                assert!(q.escapes.is_empty(), "{kd:?} {tol}");
                for (a, b) in data.iter().zip(&out) {
                    assert_eq!(a.to_bits(), b.to_bits(), "{kd:?} tol {tol}");
                }
            }
        }
    }

    /// The value a channel repeats most decodes exactly amid others (here 40 % of the values;
    /// Misra–Gries with 4 counters finds anything above 20 %), zeros stay exactly 0, and every
    /// other value keeps the bound.
    #[test]
    fn the_most_common_value_and_zero_decode_exactly() {
        let mut rng = crate::rng::Pcg32::new(9);
        let rec = 0.123_456_79f32;
        let data: Vec<f32> = (0..5000)
            .map(|_| match rng.next_u32() % 10 {
                0..=3 => rec,
                4 => 0.0,
                _ => 1e-3 + rng.next_f64() as f32,
            })
            .collect();
        let tol = 1e-3;
        let (q, out) = round_trip(&data, Layout::new(1, 100, 50), tol);
        assert_ne!(q.anchors[0], 0.0);
        for (a, b) in data.iter().zip(&out) {
            if *a == rec || *a == 0.0 {
                assert_eq!(a.to_bits(), b.to_bits());
            } else {
                assert!(((a - b).abs() as f64) <= tol * (*a as f64), "{a} {b}");
            }
        }
    }

    #[test]
    fn most_common_counts_exactly_and_needs_a_repeat() {
        assert_eq!(most_common(&[1.0, 2.0, 3.0], 0, 1), None);
        assert_eq!(
            most_common(&[1.0, 2.0, 1.0, 2.0, 1.0], 0, 1),
            Some((1.0, 3))
        );
        // Channel 1 of an interleaved pair.
        assert_eq!(
            most_common(&[5.0, 7.0, 6.0, 7.0, 5.0, 8.0], 1, 2),
            Some((7.0, 2))
        );
        assert_eq!(most_common(&[], 0, 1), None);
    }
}
