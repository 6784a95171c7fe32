//! Quantizers: f32 values to words and back.
//!
//! - **f32**: the bit patterns, lossless.
//! - **f16**: IEEE half precision (round to nearest). Values beyond ±65504 are refused with a
//!   hint rather than turned into infinities.
//! - **log16** lives in [`super::log16`] (quantization and prediction are one loop there).
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
    words
        .reinterpret_cast::<half::f16>()
        .convert_to_f32_slice(out);
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
        let e = to_f16(&[0.0, 0.0, f32::NAN]).unwrap_err().to_string();
        assert!(e.contains("index 2") && e.contains("NaN"), "{e}");
    }
}
