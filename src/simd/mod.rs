//! Four f32 lanes for the hot lookup paths: one SSE2 register on x86-64 (part of its baseline,
//! so always available), a plain array elsewhere. Each lane performs exactly the scalar IEEE
//! operation, so a path written with [`F4`] computes what the same scalar code computes.
//!
//! Why: the adaptive-table lookup ([`crate::table::kernel`]) does the same few operations on
//! its three axes (θh, θd, φd) and on three colour channels; on one register that is a third
//! of the instructions and one latency chain instead of three.

/// An f16's exponent bias (15) moved to an f32's (127), in an f32's exponent field.
const REBIAS: u32 = 112 << 23;

/// 2^-14, the smallest normal f16.
const SUBNORMAL_MAGIC: f32 = 6.103_515_6e-5;

/// A finite f16 (bits) as f32, exactly, with integer operations and one subtraction of normal
/// numbers — so that a host thread that flushes subnormal inputs to zero (x86's DAZ, Arm's
/// FZ: renderers set them for speed) still reads an f16 subnormal as its value. (The plain
/// way, the magnitude bits as an f32 times 2^112, hands the multiplier an f32 subnormal for
/// every f16 subnormal, and those read 0 under such a mode.) Normal f16s: the exponent
/// rebiased in the bits. Subnormals and ±0 (exponent bits 0): the mantissa m as the bits of
/// 2^-14 (1 + m 2^-10) minus 2^-14, which is m 2^-24 exactly.
/// (The x86-64 lanes do the same in SSE2; this scalar form serves other targets and the tests.)
#[cfg(any(test, not(target_arch = "x86_64")))]
#[inline(always)]
pub fn f16_bits_to_f32(h: u16) -> f32 {
    let x = h as u32;
    let mag = x & 0x7fff;
    let sub = mag & 0x7c00 == 0;
    let bits = (mag << 13) + REBIAS + if sub { 1 << 23 } else { 0 };
    let v = f32::from_bits(bits) - if sub { SUBNORMAL_MAGIC } else { 0.0 };
    f32::from_bits(v.to_bits() | ((x & 0x8000) << 16))
}

/// Four f32 lanes (see the module docs).
#[derive(Clone, Copy, Debug)]
pub struct F4(
    #[cfg(target_arch = "x86_64")] std::arch::x86_64::__m128,
    #[cfg(not(target_arch = "x86_64"))] [f32; 4],
);

// SAFETY (every `unsafe` block in this impl): SSE2 is part of the x86-64 baseline, so its
// intrinsics are always available; the only memory accesses are the unaligned 16-byte loads
// from slices checked to hold at least four values and stores into local four-lane arrays.
#[cfg(target_arch = "x86_64")]
#[allow(unused_unsafe)]
impl F4 {
    /// Lanes (a, b, c, d).
    #[inline(always)]
    pub fn new(a: f32, b: f32, c: f32, d: f32) -> F4 {
        unsafe { F4(std::arch::x86_64::_mm_set_ps(d, c, b, a)) }
    }
    /// The pairs (a, b, c) transposed: lanes (a₀, b₀, c₀, c₀) and (a₁, b₁, c₁, c₁) (three
    /// eight-byte loads and two shuffles).
    ///
    /// The loads are `_mm_loadl_epi64` (an unaligned read): a `[f32; 2]` is only four-byte
    /// aligned, and `_mm_load_sd`/`_mm_loadh_pd` dereference an `*const f64`, which requires
    /// eight (the kernel's knot lines sit at eight-byte addresses only because the allocator
    /// happens to place them so; Miri reports the typed read of a pair that is not).
    #[inline(always)]
    pub fn transpose_pairs(a: &[f32; 2], b: &[f32; 2], c: &[f32; 2]) -> (F4, F4) {
        use std::arch::x86_64::*;
        // SAFETY: each reference is to eight readable bytes, read by `_mm_loadl_epi64`, which
        // takes any alignment.
        unsafe {
            let pair =
                |p: &[f32; 2]| _mm_castsi128_ps(_mm_loadl_epi64(p.as_ptr() as *const __m128i));
            let x = _mm_movelh_ps(pair(a), pair(b));
            let y = pair(c);
            (
                F4(_mm_shuffle_ps::<0x08>(x, y)),
                F4(_mm_shuffle_ps::<0x5D>(x, y)),
            )
        }
    }
    /// The first four f16 values of `v` (bits), which must each be finite — ±0, normal or
    /// subnormal (as [`crate::table::kernel::Packed`] stores them) — in SSE2 operations
    /// ([`f16_bits_to_f32`] four at a time); exact for those values, whatever the thread's
    /// denormal modes. `None` if `v` holds fewer than four.
    #[inline(always)]
    pub fn from_f16_normal(v: &[u16]) -> Option<F4> {
        use std::arch::x86_64::*;
        if v.len() < 4 {
            return None;
        }
        // SAFETY: `v` holds at least four u16, the eight bytes read.
        unsafe {
            let h = _mm_loadl_epi64(v.as_ptr() as *const __m128i);
            let x = _mm_unpacklo_epi16(h, _mm_setzero_si128());
            let mag = _mm_and_si128(x, _mm_set1_epi32(0x7fff));
            let sign = _mm_slli_epi32::<16>(_mm_and_si128(x, _mm_set1_epi32(0x8000)));
            // All ones in the lanes of ±0 and subnormals (exponent bits 0).
            let sub = _mm_cmpeq_epi32(
                _mm_and_si128(mag, _mm_set1_epi32(0x7c00)),
                _mm_setzero_si128(),
            );
            let bits = _mm_add_epi32(
                _mm_add_epi32(_mm_slli_epi32::<13>(mag), _mm_set1_epi32(REBIAS as i32)),
                _mm_and_si128(sub, _mm_set1_epi32(1 << 23)),
            );
            let magic = _mm_and_si128(sub, _mm_set1_epi32(SUBNORMAL_MAGIC.to_bits() as i32));
            let m = _mm_sub_ps(_mm_castsi128_ps(bits), _mm_castsi128_ps(magic));
            Some(F4(_mm_or_ps(m, _mm_castsi128_ps(sign))))
        }
    }
    /// The first four f16 values of `v` (bits; any f16) with the F16C instruction; for the
    /// values [`F4::from_f16_normal`] takes, the same result. `None` if `v` holds fewer than
    /// four.
    ///
    /// # Safety
    /// The CPU must have F16C (`is_x86_feature_detected!("f16c")`).
    #[inline]
    #[target_feature(enable = "f16c")]
    pub fn from_f16_f16c(v: &[u16]) -> Option<F4> {
        use std::arch::x86_64::*;
        if v.len() < 4 {
            return None;
        }
        // SAFETY: `v` holds at least four u16, the eight bytes read; F16C is enabled here.
        unsafe {
            let h = _mm_loadl_epi64(v.as_ptr() as *const __m128i);
            Some(F4(_mm_cvtph_ps(h)))
        }
    }
    /// Every lane x.
    #[inline(always)]
    pub fn splat(x: f32) -> F4 {
        unsafe { F4(std::arch::x86_64::_mm_set1_ps(x)) }
    }
    /// The first four values of `v`, or `None` when it holds fewer.
    #[inline(always)]
    pub fn load(v: &[f32]) -> Option<F4> {
        if v.len() < 4 {
            return None;
        }
        Some(unsafe { F4(std::arch::x86_64::_mm_loadu_ps(v.as_ptr())) })
    }
    /// Lane-wise sum.
    #[inline(always)]
    fn add_lanes(self, o: F4) -> F4 {
        unsafe { F4(std::arch::x86_64::_mm_add_ps(self.0, o.0)) }
    }
    /// Lane-wise difference.
    #[inline(always)]
    fn sub_lanes(self, o: F4) -> F4 {
        unsafe { F4(std::arch::x86_64::_mm_sub_ps(self.0, o.0)) }
    }
    /// Lane-wise product.
    #[inline(always)]
    fn mul_lanes(self, o: F4) -> F4 {
        unsafe { F4(std::arch::x86_64::_mm_mul_ps(self.0, o.0)) }
    }
    /// Lane-wise quotient.
    #[inline(always)]
    fn div_lanes(self, o: F4) -> F4 {
        unsafe { F4(std::arch::x86_64::_mm_div_ps(self.0, o.0)) }
    }
    /// Lane-wise square root.
    #[inline(always)]
    pub fn sqrt(self) -> F4 {
        unsafe { F4(std::arch::x86_64::_mm_sqrt_ps(self.0)) }
    }
    /// Lane-wise minimum (`o` where either is NaN, as `minps`).
    #[inline(always)]
    pub fn min(self, o: F4) -> F4 {
        unsafe { F4(std::arch::x86_64::_mm_min_ps(self.0, o.0)) }
    }
    /// Lane-wise maximum (`o` where either is NaN, as `maxps`).
    #[inline(always)]
    pub fn max(self, o: F4) -> F4 {
        unsafe { F4(std::arch::x86_64::_mm_max_ps(self.0, o.0)) }
    }
    /// Truncation toward 0 of lanes in i32 range, and the truncated values as f32.
    #[inline(always)]
    pub fn trunc(self) -> ([i32; 4], F4) {
        use std::arch::x86_64::*;
        unsafe {
            let i = _mm_cvttps_epi32(self.0);
            let mut a = [0i32; 4];
            _mm_storeu_si128(a.as_mut_ptr() as *mut __m128i, i);
            (a, F4(_mm_cvtepi32_ps(i)))
        }
    }
    /// Whether any lane of `self` is ≥ the same lane of `o` (false for NaN lanes).
    #[inline(always)]
    pub fn any_ge(self, o: F4) -> bool {
        use std::arch::x86_64::*;
        unsafe { _mm_movemask_ps(_mm_cmpge_ps(self.0, o.0)) != 0 }
    }
    /// Every lane set to lane `L` (0..4).
    #[inline(always)]
    pub fn lane<const L: i32>(self) -> F4 {
        use std::arch::x86_64::*;
        // _MM_SHUFFLE(L, L, L, L) = L · 0b01010101.
        unsafe {
            match L {
                0 => F4(_mm_shuffle_ps::<0x00>(self.0, self.0)),
                1 => F4(_mm_shuffle_ps::<0x55>(self.0, self.0)),
                2 => F4(_mm_shuffle_ps::<0xAA>(self.0, self.0)),
                _ => F4(_mm_shuffle_ps::<0xFF>(self.0, self.0)),
            }
        }
    }
    /// Lanes `(a[L], a[L], b[L], b[L])`.
    #[inline(always)]
    pub fn pair_lanes<const L: i32>(a: F4, b: F4) -> F4 {
        use std::arch::x86_64::*;
        unsafe {
            match L {
                0 => F4(_mm_shuffle_ps::<0x00>(a.0, b.0)),
                1 => F4(_mm_shuffle_ps::<0x55>(a.0, b.0)),
                2 => F4(_mm_shuffle_ps::<0xAA>(a.0, b.0)),
                _ => F4(_mm_shuffle_ps::<0xFF>(a.0, b.0)),
            }
        }
    }
    /// Lanes (a0, b0, a1, b1).
    #[inline(always)]
    pub fn interleave_lo(a: F4, b: F4) -> F4 {
        unsafe { F4(std::arch::x86_64::_mm_unpacklo_ps(a.0, b.0)) }
    }
    /// Lanes (x1, x2, x3, 0): every lane moved down by one.
    #[inline(always)]
    pub fn shift_down(self) -> F4 {
        use std::arch::x86_64::*;
        unsafe {
            F4(_mm_castsi128_ps(_mm_srli_si128::<4>(_mm_castps_si128(
                self.0,
            ))))
        }
    }
    /// The lanes.
    #[inline(always)]
    pub fn to_array(self) -> [f32; 4] {
        let mut out = [0.0f32; 4];
        unsafe { std::arch::x86_64::_mm_storeu_ps(out.as_mut_ptr(), self.0) };
        out
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl F4 {
    /// Lanes (a, b, c, d).
    #[inline(always)]
    pub fn new(a: f32, b: f32, c: f32, d: f32) -> F4 {
        F4([a, b, c, d])
    }
    /// See the x86-64 version.
    #[inline(always)]
    pub fn transpose_pairs(a: &[f32; 2], b: &[f32; 2], c: &[f32; 2]) -> (F4, F4) {
        (F4([a[0], b[0], c[0], c[0]]), F4([a[1], b[1], c[1], c[1]]))
    }
    /// See the x86-64 version.
    #[inline(always)]
    pub fn from_f16_normal(v: &[u16]) -> Option<F4> {
        if v.len() < 4 {
            return None;
        }
        Some(F4(std::array::from_fn(|k| f16_bits_to_f32(v[k]))))
    }
    /// Every lane x.
    #[inline(always)]
    pub fn splat(x: f32) -> F4 {
        F4([x; 4])
    }
    /// The first four values of `v`, or `None` when it holds fewer.
    #[inline(always)]
    pub fn load(v: &[f32]) -> Option<F4> {
        if v.len() < 4 {
            return None;
        }
        Some(F4([v[0], v[1], v[2], v[3]]))
    }
    #[inline(always)]
    fn map2(self, o: F4, f: impl Fn(f32, f32) -> f32) -> F4 {
        F4(std::array::from_fn(|k| f(self.0[k], o.0[k])))
    }
    /// Lane-wise sum.
    #[inline(always)]
    fn add_lanes(self, o: F4) -> F4 {
        self.map2(o, |a, b| a + b)
    }
    /// Lane-wise difference.
    #[inline(always)]
    fn sub_lanes(self, o: F4) -> F4 {
        self.map2(o, |a, b| a - b)
    }
    /// Lane-wise product.
    #[inline(always)]
    fn mul_lanes(self, o: F4) -> F4 {
        self.map2(o, |a, b| a * b)
    }
    /// Lane-wise quotient.
    #[inline(always)]
    fn div_lanes(self, o: F4) -> F4 {
        self.map2(o, |a, b| a / b)
    }
    /// Lane-wise square root.
    #[inline(always)]
    pub fn sqrt(self) -> F4 {
        F4(self.0.map(f32::sqrt))
    }
    /// Lane-wise minimum (`o` where either is NaN, as `minps`).
    #[inline(always)]
    pub fn min(self, o: F4) -> F4 {
        self.map2(o, |a, b| if a < b { a } else { b })
    }
    /// Lane-wise maximum (`o` where either is NaN, as `maxps`).
    #[inline(always)]
    pub fn max(self, o: F4) -> F4 {
        self.map2(o, |a, b| if a > b { a } else { b })
    }
    /// Truncation toward 0 of lanes in i32 range, and the truncated values as f32.
    #[inline(always)]
    pub fn trunc(self) -> ([i32; 4], F4) {
        let i = self.0.map(|x| x as i32);
        (i, F4(i.map(|x| x as f32)))
    }
    /// See the x86-64 version.
    #[inline(always)]
    pub fn any_ge(self, o: F4) -> bool {
        (0..4).any(|k| self.0[k] >= o.0[k])
    }
    /// Every lane set to lane `L` (0..4).
    #[inline(always)]
    pub fn lane<const L: i32>(self) -> F4 {
        F4([self.0[L as usize]; 4])
    }
    /// Lanes (a[L], a[L], b[L], b[L]).
    #[inline(always)]
    pub fn pair_lanes<const L: i32>(a: F4, b: F4) -> F4 {
        let l = L as usize;
        F4([a.0[l], a.0[l], b.0[l], b.0[l]])
    }
    /// Lanes (a0, b0, a1, b1).
    #[inline(always)]
    pub fn interleave_lo(a: F4, b: F4) -> F4 {
        F4([a.0[0], b.0[0], a.0[1], b.0[1]])
    }
    /// Lanes (x1, x2, x3, 0): every lane moved down by one.
    #[inline(always)]
    pub fn shift_down(self) -> F4 {
        F4([self.0[1], self.0[2], self.0[3], 0.0])
    }
    /// The lanes.
    #[inline(always)]
    pub fn to_array(self) -> [f32; 4] {
        self.0
    }
}

macro_rules! lane_op {
    ($tr:ident, $f:ident, $imp:ident) => {
        impl std::ops::$tr for F4 {
            type Output = F4;
            #[inline(always)]
            fn $f(self, o: F4) -> F4 {
                self.$imp(o)
            }
        }
    };
}
lane_op!(Add, add, add_lanes);
lane_op!(Sub, sub, sub_lanes);
lane_op!(Mul, mul, mul_lanes);
lane_op!(Div, div, div_lanes);

#[cfg(test)]
mod tests;
