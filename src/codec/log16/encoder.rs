//! The log16 encoder ([`encode`]): each channel's grid anchored on its most common value, the
//! values quantized once, a predictor chosen, and every value checked against the bound.

use super::predict::{from_code, resolve, run, to_code};
use super::{
    Encoded, FLOOR_RATIO, Log16Params, MIN_FLOOR, MIN_TOL, from_log, step, to_log, value_at,
};
use crate::codec::filter::{Filter, Layout};
use crate::error::{Error, Result};

/// The most frequent value of channel `c` (every `ch`-th value of `data` from `c`) and how
/// often it occurs: a Misra–Gries pass with [`HEAVY`] counters (which finds every value making
/// up more than 1/(HEAVY + 1) of the channel), then an exact count of the strongest candidate.
/// `None` when no value occurs twice.
pub(super) fn most_common(data: &[f32], c: usize, ch: usize) -> Option<(f32, usize)> {
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
