//! Quantizers: f32 values to words and back.
//!
//! - **f32**: the bit patterns, lossless.
//! - **f16**: IEEE half precision (round to nearest). Values beyond ±65504 are refused with a
//!   hint rather than turned into infinities.
//! - **log16**: 16-bit codes of `ln(|v| + floor)` with a step derived from a relative tolerance,
//!   guaranteeing for *every* value `|v̂ − v| ≤ tol · max(|v|, floor)` (see [`Log16Params`]).
//!
//! NaN (and ±∞) are refused by every quantizer, naming the index.

use crate::error::{Error, Result};

/// Checks that every value is finite, naming the first offending index.
pub fn check_finite(data: &[f32]) -> Result<()> {
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        return Err(Error::Encode {
            msg: format!(
                "value at index {i} is {} (tables must hold finite numbers)",
                data[i]
            ),
        });
    }
    Ok(())
}

/// f32 → f16 bits, refusing values outside the f16 range.
pub fn to_f16(data: &[f32]) -> Result<Vec<u16>> {
    use half::slice::HalfFloatSliceExt;
    check_finite(data)?;
    let max = half::f16::MAX.to_f32();
    if let Some(i) = data.iter().position(|v| v.abs() > max) {
        return Err(Error::Encode {
            msg: format!(
                "value {} at index {i} exceeds the f16 range (±{max}); use codec log16 (relative \
                 error bound, any magnitude) or f32",
                data[i]
            ),
        });
    }
    let mut h = vec![half::f16::ZERO; data.len()];
    h.convert_from_f32_slice(data);
    Ok(h.iter().map(|x| x.to_bits()).collect())
}

/// f16 bits → f32.
pub fn from_f16(words: &[u16], out: &mut [f32]) {
    use half::slice::HalfBitsSliceExt;
    use half::slice::HalfFloatSliceExt;
    words.reinterpret_cast::<half::f16>().convert_to_f32_slice(out);
}

/// Largest 16-bit code used by log16.
pub const LOG16_MAX_CODE: u32 = 65535;
/// Smallest tolerance log16 accepts (below it f32 rounding alone would approach the bound).
pub const LOG16_MIN_TOL: f64 = 1e-6;
/// Smallest floor log16 uses (keeps `ln(floor)` well inside f64).
pub const LOG16_MIN_FLOOR: f64 = 1e-30;
/// When the floor is chosen automatically it may not exceed this fraction of the chunk's largest
/// magnitude; otherwise the tolerance is too tight for 16 bits and encoding fails.
pub const LOG16_MAX_AUTO_FLOOR_RATIO: f64 = 1e-3;

/// The per-chunk parameters of log16, stored in the chunk header.
///
/// A value `v ≥ 0` is coded as `q = round((ln(v + floor) − lo) / step)` and decoded as
/// `v̂ = max(0, exp(lo + q·step) − floor)`, so `|v̂ − v| ≤ (v + floor)(e^{step/2} − 1)`. With
/// `step = 2·ln(1 + tol)·0.98` that is at most `0.98·tol·(v + floor)`, within the bound
/// `tol·max(v, floor)` wherever `v ≥ 50·floor` — which, with the automatically chosen floor
/// (around 1e-28 of the chunk's maximum), is every value but exact zeros and the near-zero
/// crumbs next to them. The encoder therefore decodes every value and checks the bound; values
/// that fail it (negatives, magnitudes close to the floor, anything f32 rounding pushes over) go
/// to an exact escape list. The guarantee holds for every value by construction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Log16Params {
    /// ln of the smallest coded magnitude plus floor.
    pub lo: f64,
    /// Code step in ln units.
    pub step: f64,
    /// The absolute floor: below it the error is bounded by `tol·floor`.
    pub floor: f64,
}

impl Log16Params {
    /// Decodes one code.
    #[inline]
    pub fn decode(&self, q: u16) -> f32 {
        let v = (self.lo + q as f64 * self.step).exp() - self.floor;
        if v > 0.0 { v as f32 } else { 0.0 }
    }

    /// Checks parameters read from a file.
    pub fn valid(&self) -> bool {
        self.lo.is_finite()
            && self.step.is_finite()
            && self.step > 0.0
            && self.floor.is_finite()
            && self.floor > 0.0
            && (self.lo + LOG16_MAX_CODE as f64 * self.step).is_finite()
    }
}

/// The result of log16 quantization.
#[derive(Debug, Clone)]
pub struct Log16 {
    /// One code per value (escaped positions hold a filler code).
    pub codes: Vec<u16>,
    /// The chunk's parameters.
    pub params: Log16Params,
    /// Positions stored exactly (strictly increasing) and their values.
    pub escapes: Vec<(u32, f32)>,
}

/// The log16 step for tolerance `tol`.
pub fn log16_step(tol: f64) -> f64 {
    2.0 * tol.ln_1p() * 0.98
}

/// Quantizes `data` with relative tolerance `tol`; `floor` pins the absolute floor, `None` lets
/// the encoder choose the smallest floor for which the chunk's dynamic range fits in 16 bits.
pub fn to_log16(data: &[f32], tol: f64, floor: Option<f64>) -> Result<Log16> {
    check_finite(data)?;
    if !(tol.is_finite() && (LOG16_MIN_TOL..=0.5).contains(&tol)) {
        return Err(Error::Encode {
            msg: format!(
                "log16 tolerance {tol} is outside [{LOG16_MIN_TOL}, 0.5]; use codec f32 for \
                 lossless storage"
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
    let step = log16_step(tol);
    let span = (LOG16_MAX_CODE - 1) as f64 * step; // one code of slack for rounding
    // Range of the magnitudes we code (negatives go to the escape list).
    let (mut amin, mut amax) = (f64::INFINITY, 0.0f64);
    for &v in data {
        if v >= 0.0 {
            amin = amin.min(v as f64);
            amax = amax.max(v as f64);
        }
    }
    if !amin.is_finite() {
        amin = 0.0;
    }
    // Smallest floor with ln((amax + F) / (amin + F)) <= span.
    let es = span.exp();
    let needed = if es.is_finite() {
        ((amax - amin * es) / (es - 1.0)).max(0.0)
    } else {
        0.0
    };
    let floor = match floor {
        Some(f) => {
            if needed > f {
                return Err(Error::Encode {
                    msg: format!(
                        "log16 tolerance {tol} is too tight for 16 bits over this chunk's range \
                         [{amin:.3e}, {amax:.3e}] with floor {f:.3e}: it needs a floor of at \
                         least {needed:.3e}; loosen the tolerance, raise the floor, or use f32"
                    ),
                });
            }
            f
        }
        None => {
            let f = needed.max(LOG16_MIN_FLOOR).max(amax * 1e-30);
            if needed > LOG16_MAX_AUTO_FLOOR_RATIO * amax {
                return Err(Error::Encode {
                    msg: format!(
                        "log16 tolerance {tol} is too tight for 16 bits over this chunk's range \
                         [{amin:.3e}, {amax:.3e}]: the relative bound would hold only above \
                         {needed:.3e}; loosen the tolerance, give an explicit floor, or use f32"
                    ),
                });
            }
            f
        }
    };
    let params = Log16Params {
        lo: (amin + floor).ln(),
        step,
        floor,
    };
    let inv = 1.0 / step;
    let mut codes = vec![0u16; data.len()];
    let mut escapes = Vec::new();
    let mut last = 0u16;
    for (i, (&v, c)) in data.iter().zip(codes.iter_mut()).enumerate() {
        let a = v as f64;
        let mut ok = false;
        if a >= 0.0 {
            let q = (((a + floor).ln() - params.lo) * inv).round();
            if (0.0..=LOG16_MAX_CODE as f64).contains(&q) {
                let q = q as u16;
                let back = params.decode(q) as f64;
                if (back - a).abs() <= tol * a.max(floor) {
                    *c = q;
                    last = q;
                    ok = true;
                }
            }
        }
        if !ok {
            *c = last; // keeps the code stream smooth for the predictor
            escapes.push((i as u32, v));
        }
    }
    Ok(Log16 {
        codes,
        params,
        escapes,
    })
}

/// Decodes log16 codes into `out` (escapes are applied by the caller).
pub fn from_log16(codes: &[u16], params: &Log16Params, out: &mut [f32]) {
    for (o, &q) in out.iter_mut().zip(codes) {
        *o = params.decode(q);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f16_refuses_out_of_range_with_a_hint() {
        let e = to_f16(&[1.0, 70000.0]).unwrap_err().to_string();
        assert!(e.contains("index 1") && e.contains("log16"), "{e}");
    }

    #[test]
    fn nan_is_refused_naming_the_index() {
        for r in [
            to_f16(&[0.0, 0.0, f32::NAN]).map(|_| ()),
            to_log16(&[0.0, 0.0, f32::NAN], 1e-3, None).map(|_| ()),
        ] {
            let e = r.unwrap_err().to_string();
            assert!(e.contains("index 2") && e.contains("NaN"), "{e}");
        }
    }

    #[test]
    fn log16_too_tight_fails_clearly() {
        let e = to_log16(&[0.0, 1e6], 1e-6, Some(1e-3)).unwrap_err().to_string();
        assert!(e.contains("too tight"), "{e}");
    }

    #[test]
    fn log16_negatives_escape_exactly() {
        let q = to_log16(&[1.0, -0.5, 2.0, -1e-9], 1e-3, None).unwrap();
        assert_eq!(q.escapes, vec![(1, -0.5), (3, -1e-9)]);
    }
}
