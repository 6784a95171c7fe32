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

use super::filter::Filter;
use super::{choose, quantize};

#[cfg(test)]
mod anchor_tests;
mod decoder;
mod encoder;
mod predict;
#[cfg(test)]
mod tests;

pub use decoder::decode;
pub use encoder::encode;

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

/// `g⁻¹(lo + k·step)` on an anchored grid: index 0 is exactly 0.
#[inline(always)]
fn value_at(k: i64, lo: f64, step: f64, floor: f64) -> f32 {
    if k == 0 {
        0.0
    } else {
        from_log(lo + k as f64 * step, floor)
    }
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
