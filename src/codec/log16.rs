//! log16: error-bounded 16-bit coding of values in the log domain, with prediction in the loop.
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
//! and negative values (measured data has them) are coded like positive ones. A predictor `P` (previous point along the
//! innermost axis, or the planar `left + up − up-left`, optionally plus the previous channel's
//! prediction error — the same family as [`Filter`]) is computed from the *reconstructed*
//! neighbours `R`, and the residual is quantized: `q = round((L − P) / step)`, `R = P + q·step`,
//! stored as a zigzagged 16-bit code. Decoding repeats the prediction and gives `v̂ = g⁻¹(R)`. Because the quantizer sits inside the prediction loop (DPCM, as
//! in the SZ compressors), smooth data leaves residual codes that are mostly 0 — far fewer bits
//! than quantizing first and predicting the noisy codes afterwards — and there is no limit on the
//! dynamic range of a chunk: only the *residual* must fit 16 bits.
//!
//! # The guarantee
//!
//! `|R − L| ≤ step/2` gives `|v̂ − v| ≤ (v + floor)(e^{step/2} − 1)`; with
//! `step = 2·ln(1 + tol)·0.98` that is at most `0.98·tol·(v + floor)`, inside the bound
//! `tol·max(v, floor)` except for values within a factor ~50 of the floor. The encoder therefore
//! decodes every value exactly as the decoder will and checks the bound; a value that misses it
//! — or would decode with the other sign, or whose residual does not fit 16 bits — is stored
//! exactly in an escape list (the decoder then continues the prediction from its exact `L`). So
//! **every** decoded value satisfies `|v̂ − v| ≤ tol·max(|v|, floor)` and has the sign of `v`
//! (a non-negative table never decodes to a negative value, which a BRDF must not return).
//!
//! The floor is `1e-7 ×` the chunk's largest magnitude unless given explicitly (absolute), and is
//! stored in the chunk header: below it the error bound is absolute (`tol·floor`).
//!
//! Decoding uses `exp`/`ln` from the platform's libm; results are deterministic on a platform and
//! may differ in the last ulp across platforms (well inside the 2% margin of the bound).

use super::filter::{self, Filter, Layout, Word};
use crate::error::{Error, Result};

/// The per-chunk parameters of log16, stored in the chunk header.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Log16Params {
    /// The prediction for the first point of a chunk (0, i.e. `v = 0`).
    pub lo: f64,
    /// Quantization step of the residuals, in ln units.
    pub step: f64,
    /// The absolute floor: below it the error is bounded by `tol·floor`.
    pub floor: f64,
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
    /// Zigzagged residual codes (0 at escaped positions).
    pub codes: Vec<u16>,
    /// Chunk parameters.
    pub params: Log16Params,
    /// Exactly stored values: (index, value), indices strictly increasing.
    pub escapes: Vec<(u32, f32)>,
}

/// The prediction loop shared by encoder and decoder. `step_fn(i, p)` returns the reconstructed
/// value of point `i` given its prediction `p`.
#[inline(always)]
fn run(
    n: usize,
    layout: Layout,
    filter: Filter,
    lo: f64,
    r: &mut [f64],
    mut step_fn: impl FnMut(usize, f64) -> f64,
) {
    let ch = layout.channels;
    let row = layout.channels * layout.inner;
    let (plane, chan) = (filter.plane(), filter.channel() && ch > 1);
    let none = filter == Filter::None;
    for (s, len, up) in filter::rows(n, layout) {
        let mut base_prev = 0.0;
        let mut c = 0usize;
        for j in 0..len {
            let i = s + j;
            let base = if none {
                lo
            } else if j >= ch {
                if plane && up {
                    r[i - ch] + r[i - row] - r[i - row - ch]
                } else {
                    r[i - ch]
                }
            } else if s >= row {
                r[i - row]
            } else {
                lo
            };
            let p = if chan && c != 0 {
                base + (r[i - 1] - base_prev)
            } else {
                base
            };
            base_prev = base;
            r[i] = step_fn(i, p);
            c += 1;
            if c == ch {
                c = 0;
            }
        }
    }
}

fn to_code(q: f64) -> Option<u16> {
    (q.abs() <= i16::MAX as f64).then(|| (q as i16 as u16).zigzag())
}

fn from_code(c: u16) -> f64 {
    c.unzigzag() as i16 as f64
}

/// Encodes `data` with relative tolerance `tol` (see the module docs for the guarantee).
/// `floor`: absolute floor, or `None` for `1e-7 ×` the chunk's largest magnitude. `filter`: force
/// a predictor, or `None` to pick the one with the cheapest residuals.
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
    };
    let n = data.len();
    let l: Vec<f64> = data.iter().map(|&v| to_log(v as f64, floor)).collect();
    let inv = 1.0 / params.step;
    let mut r = vec![0.0f64; n];

    // Choose the predictor by the size of its residual codes (no verification; cheap).
    let filter = filter.unwrap_or_else(|| {
        let mut best = (u64::MAX, Filter::None);
        for f in Filter::ALL {
            if f.channel() && layout.channels == 1 {
                continue;
            }
            let mut bits = 0u64;
            run(n, layout, f, params.lo, &mut r, |i, p| {
                let q = ((l[i] - p) * inv).round();
                match to_code(q) {
                    Some(c) => {
                        bits += c.bits() as u64 + 1;
                        p + q * params.step
                    }
                    None => {
                        bits += 64;
                        l[i]
                    }
                }
            });
            if bits < best.0 {
                best = (bits, f);
            }
        }
        best.1
    });

    let mut codes = vec![0u16; n];
    let mut escapes = Vec::new();
    run(n, layout, filter, params.lo, &mut r, |i, p| {
        let v = data[i];
        let q = ((l[i] - p) * inv).round();
        if let Some(c) = to_code(q) {
            let rec = p + q * params.step;
            let back = from_log(rec, floor) as f64;
            let a = v as f64;
            // Sign-preserving: a non-negative value (a BRDF) must never decode negative.
            let same_sign = if a >= 0.0 { back >= 0.0 } else { back <= 0.0 };
            if same_sign && (back - a).abs() <= tol * a.abs().max(floor) {
                codes[i] = c;
                return rec;
            }
        }
        escapes.push((i as u32, v));
        l[i]
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

/// Decodes codes into `out` (same length), given the chunk's escapes (sorted, in range).
pub fn decode(
    codes: &[u16],
    params: &Log16Params,
    layout: Layout,
    filter: Filter,
    escapes: &[(u32, f32)],
    out: &mut [f32],
) {
    let n = codes.len();
    let mut r = vec![0.0f64; n];
    let mut e = escapes.iter().peekable();
    let step = params.step;
    let floor = params.floor;
    run(n, layout, filter, params.lo, &mut r, |i, p| {
        if let Some(&&(k, v)) = e.peek()
            && k as usize == i
        {
            e.next();
            out[i] = v;
            return to_log(v as f64, floor);
        }
        let rec = p + from_code(codes[i]) * step;
        out[i] = from_log(rec, floor);
        rec
    });
}

#[cfg(test)]
mod tests {
    use super::*;

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
            &mut out,
        );
        for (a, b) in v.iter().zip(&out) {
            assert!((a - b).abs() as f64 <= 1e-3 * (*a as f64).max(q.params.floor));
        }
    }
}
