//! The values a kernel's lookups read: [`Packed`], f16 codes scaled by a power of two (adaptive
//! tables) or exact f32 (resampled fixed mappings), each followed by the zero padding that a
//! row's last four-value load reads into.
//!
//! Why a file of its own: the storage format and its rounding bound are one decision, made
//! and tested here. The blends ([`super::blend`]) and the eight-lane path ([`super::x8`]) read
//! the fields directly, in the hot path: they are `pub(super)`, the kernel's reach and no wider.

use super::Kernel;

/// A kernel table's values as its lookups read them: f16, scaled by a power of two.
///
/// Half the bytes of f32, so a measured material's table (≈ 0.9 MB) stays in a core's L2
/// cache, and a corner row (two φd corners × RGB) is 12 bytes. The scale 2^e puts the largest
/// magnitude in [2^14, 2^15), well inside f16's range. The rounding costs at most 2^-11 of a
/// value (f16's half ulp) down to 2^-28 of the largest, far below a measured table's
/// interpolation error; below that f16's subnormals keep an absolute step of at most 2^-38 of
/// the largest, and only values under half of it read 0. (Flushing everything below 2^-28 to 0 cut
/// the tails of sharp lobes: an adaptive table of GGX α = 0.02 holds 3.7e6 at its grazing mirror
/// nodes, so values below 0.014 vanished, and lookups near such nodes jumped between 0.0063 and
/// 0.0108 — the model's 0.0098 — as values moved within their rounding.) Every code expands
/// exactly with `F4::from_f16_normal` or F16C, also in a host thread that flushes subnormal
/// inputs to zero (`simd::f16_bits_to_f32`).
/// Negative values are kept: a table of a [`Quantity`] other than f_r extrapolates its nodes beyond the
/// horizon below 0 (`table::horizon`); an f_r table's negative values (unmeasured cells) are
/// set aside by [`TabulatedBrdf`] before they reach here.
///
/// Small tables whose kernel resamples a fixed mapping ([`Kernel::exact_values`]) keep f32
/// values instead ([`Packed::exact`]): such a table is what a user baked on a grid of their own
/// choosing, and while it fits in L2 its lookups give the stored values at the nodes exactly
/// at no cost in speed.
///
/// [`Quantity`]: crate::table::grid::Quantity
/// [`TabulatedBrdf`]: crate::table::TabulatedBrdf
#[derive(Debug, Clone)]
pub struct Packed {
    /// The codes, then [`PACK_PAD`] zeros (a row's second four-value load reads past its end);
    /// empty for exact values.
    pub(super) bits: Box<[u16]>,
    /// Exact values (f32), then [`PACK_PAD`] zeros; empty for codes.
    pub(super) full: Box<[f32]>,
    /// 2^−e: multiplies the blended scaled values (exact; 1 for exact values).
    pub(super) unscale: f32,
}

/// Zero codes after a [`Packed`] table's values.
pub(super) const PACK_PAD: usize = 4;

impl Packed {
    /// Packs `values` (non-finite ones become 0).
    pub fn new(values: &[f32]) -> Packed {
        let max = values
            .iter()
            .filter(|x| x.is_finite())
            .fold(0f32, |m, &x| m.max(x.abs()));
        // max · 2^e ∈ [2^14, 2^15): e = 14 − ⌊log2 max⌋, read off max's exponent bits (exact);
        // within f32's normal exponents.
        let e = if max >= f32::MIN_POSITIVE {
            (14 - (((max.to_bits() >> 23) & 0xff) as i32 - 127)).clamp(-120, 120)
        } else if max > 0.0 {
            120
        } else {
            0
        };
        let pow2 = |e: i32| f32::from_bits(((e + 127) as u32) << 23);
        let scale = pow2(e);
        let bits = values
            .iter()
            .map(|&v| {
                let x = v * scale;
                if x.is_finite() {
                    half::f16::from_f32(x).to_bits()
                } else {
                    0
                }
            })
            .chain(std::iter::repeat_n(0, PACK_PAD))
            .collect();
        Packed {
            bits,
            full: Box::new([]),
            unscale: pow2(-e),
        }
    }

    /// `values` as they are (f32; non-finite ones become 0).
    pub fn exact(values: &[f32]) -> Packed {
        let mut v = Vec::with_capacity(values.len() + PACK_PAD);
        v.extend_from_slice(values);
        Packed::exact_owned(v)
    }

    /// [`Packed::exact`] of values the caller gives up, kept in their own allocation: a table's
    /// one array is not copied into a second (the first lookup of a 70 MB table peaked at
    /// twice its size, an eager open at three times).
    pub fn exact_owned(mut values: Vec<f32>) -> Packed {
        for v in &mut values {
            if !v.is_finite() {
                *v = 0.0;
            }
        }
        // Exactly the padding more: a doubled capacity would be shrunk (copied) into the box.
        values.reserve_exact(PACK_PAD);
        values.extend_from_slice(&[0.0; PACK_PAD]);
        Packed {
            bits: Box::new([]),
            full: values.into_boxed_slice(),
            unscale: 1.0,
        }
    }

    /// `values` as `kernel` reads them: exact or f16 codes ([`Kernel::exact_values`]).
    pub fn for_kernel(kernel: &Kernel, values: &[f32]) -> Packed {
        if kernel.exact_values() {
            Packed::exact(values)
        } else {
            Packed::new(values)
        }
    }

    /// [`Packed::for_kernel`] of values the caller gives up: exact values keep their allocation
    /// ([`Packed::exact_owned`]; reserve [`Packed::PAD`] more for no reallocation).
    pub fn for_kernel_owned(kernel: &Kernel, values: Vec<f32>) -> Packed {
        if kernel.exact_values() {
            Packed::exact_owned(values)
        } else {
            Packed::new(&values)
        }
    }

    /// The zeros after the values: a vector given to [`Packed::exact_owned`] with this much
    /// spare capacity is not reallocated.
    pub const PAD: usize = PACK_PAD;

    /// No values (a table that could not be loaded: every lookup gives 0).
    pub fn empty() -> Packed {
        Packed {
            bits: Box::new([]),
            full: Box::new([]),
            unscale: 1.0,
        }
    }

    /// The exact values ([`Packed::exact`]; empty for codes), without the padding.
    pub fn exact_values(&self) -> &[f32] {
        let n = self.full.len().saturating_sub(PACK_PAD);
        &self.full[..n]
    }

    /// Number of values (0 for [`Packed::empty`]).
    pub fn len(&self) -> usize {
        (self.bits.len() + self.full.len()).saturating_sub(PACK_PAD)
    }

    /// Whether no values are held.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.bits.len() * std::mem::size_of::<u16>() + self.full.len() * std::mem::size_of::<f32>()
    }

    /// Value `i` as lookups see it (0 beyond the end).
    pub fn get(&self, i: usize) -> f32 {
        if i >= self.len() {
            return 0.0;
        }
        self.scaled(i) * self.unscale
    }

    /// The scaled value of code `i` (0 beyond the end).
    #[inline(always)]
    pub(super) fn scaled(&self, i: usize) -> f32 {
        if !self.full.is_empty() {
            return self.full.get(i).copied().unwrap_or(0.0);
        }
        self.bits
            .get(i)
            .map_or(0.0, |&b| half::f16::from_bits(b).to_f32())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    #[test]
    fn packed_values_round_to_f16_within_half_an_ulp() {
        for peak in [1e-3f32, 0.7, 3.0e4, 1.0e7] {
            let mut r = Pcg32::new(5);
            let v: Vec<f32> = (0..20_000)
                .map(|i| match i {
                    0 => peak,
                    1 => -0.5 * peak,
                    2 => f32::NAN,
                    // log-uniform over 2^-40 .. 1 of the peak
                    _ => peak * 2f32.powf(-40.0 * r.next_f64() as f32),
                })
                .collect();
            let p = Packed::new(&v);
            assert_eq!(p.len(), v.len());
            // Negative values are kept (extrapolated nodes beyond the horizon), non-finite ones
            // and those past the end read 0.
            assert_eq!((p.get(2), p.get(v.len())), (0.0, 0.0));
            assert!((p.get(1) + 0.5 * peak).abs() <= 0.5 * peak * 2f32.powi(-11));
            // The scale puts the peak in [2^14, 2^15): f16's subnormal step 2^-24 is then at
            // most 2^-38 of the peak.
            let step = peak * 2f32.powi(-38);
            for (i, &x) in v.iter().enumerate().skip(3).chain([(0, &peak)]) {
                let y = p.get(i);
                if x >= peak * 2f32.powi(-28) {
                    // f16 keeps 11 significant bits: round to nearest is within 2^-11.
                    assert!((y - x).abs() <= x * 2f32.powi(-11), "{x} {y} (peak {peak})");
                } else {
                    // Subnormal codes: within half a step (values below it read 0).
                    assert!((y - x).abs() <= 0.5 * step, "{x} {y} (peak {peak})");
                }
            }
        }
        assert!(Packed::new(&[]).is_empty() && Packed::empty().is_empty());
        assert_eq!(Packed::new(&[0.0; 3]).get(1), 0.0);
    }
}
