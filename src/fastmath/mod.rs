//! Sine, cosine, logarithm and floor without libm on the hot paths of sampling and lookup.
//!
//! Every importance sampler turns a uniform number into an azimuth and needs its sine and cosine;
//! glibc's `sincos` costs 15–20 ns there because it must handle any argument. The arguments in
//! samplers are bounded (2π·u with u in [0, 1), or π/4·t with |t| ≤ 1 in the concentric map), so
//! one exact quadrant reduction and a short Taylor polynomial on [−π/4, π/4] give the same values
//! to within a few units in the last place at a fraction of the cost. The polynomial degree comes
//! from the remainder bound: x¹⁷/17! ≤ 4.6·10⁻¹⁷ for |x| ≤ π/4, below half an ulp of 1.
//! Microfacet samplers invert their CDF with a logarithm; [`ln`] is inline and table-driven,
//! so it neither calls nor waits on libm.

use std::f64::consts::FRAC_PI_2;

/// ⌊x⌋ without `f64::floor`, which is a libm call on baseline x86-64 (no SSE4.1 `roundsd`):
/// truncation corrected by one for negative non-integers. NaN gives 0 and |x| ≥ 2⁶³ saturates
/// (callers clamp the result to an index range anyway).
///
/// `floor(2.7) = 2`, `floor(-2.5) = -3`, `floor(-3.0) = -3` (tests below).
#[inline(always)]
pub fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x { t - 1.0 } else { t }
}

/// (sin x, cos x) for |x| ≤ π/4 (larger |x| loses accuracy quickly; NaN stays NaN).
///
/// Absolute error ≤ 2·10⁻¹⁶ on the valid range (Taylor remainders x¹⁷/17! and x¹⁸/18!, plus
/// rounding in Horner's scheme).
#[inline]
pub fn sin_cos_quarter(x: f64) -> (f64, f64) {
    let x2 = x * x;
    // sin x = x Σ (−1)^k x^{2k} / (2k+1)!, k = 0..7, and cos x = Σ (−1)^k x^{2k} / (2k)!,
    // k = 0..8, by Horner's scheme in two lanes (sine, cosine): the same operations as two
    // scalar polynomials, half the instructions. The sine lane starts at 0 for its one
    // coefficient fewer (0·x² + c is exactly c).
    const S: [f64; 9] = [
        0.0,
        -1.0 / 1_307_674_368_000.0,
        1.0 / 6_227_020_800.0,
        -1.0 / 39_916_800.0,
        1.0 / 362_880.0,
        -1.0 / 5040.0,
        1.0 / 120.0,
        -1.0 / 6.0,
        1.0,
    ];
    const C: [f64; 9] = [
        1.0 / 20_922_789_888_000.0,
        -1.0 / 87_178_291_200.0,
        1.0 / 479_001_600.0,
        -1.0 / 3_628_800.0,
        1.0 / 40_320.0,
        -1.0 / 720.0,
        1.0 / 24.0,
        -0.5,
        1.0,
    ];
    let [s, c] = estrin2(x2, &S, &C);
    (x * s, c)
}

/// Two degree-8 polynomials (coefficients highest first) at `y` by Estrin's scheme, as the two
/// lanes of one register: pairs, then pairs of pairs with y², then y⁴ and y⁸ — four
/// multiply-add levels deep instead of Horner's eight, which matters where a sine and cosine head
/// a sampler's dependency chain.
#[inline(always)]
fn estrin2(y: f64, a: &[f64; 9], b: &[f64; 9]) -> [f64; 2] {
    // p(y) = Σ c_k y^k with c_k = a[8 − k]:
    // (c0 + c1 y) + (c2 + c3 y) y² + ((c4 + c5 y) + (c6 + c7 y) y²) y⁴ + c8 y⁸.
    let c = |k: usize| F2::new(a[8 - k], b[8 - k]);
    let y1 = F2::splat(y);
    let y2 = F2::splat(y * y);
    let y4 = y2.mul(y2);
    let p01 = c(1).mul(y1).add(c(0));
    let p23 = c(3).mul(y1).add(c(2));
    let p45 = c(5).mul(y1).add(c(4));
    let p67 = c(7).mul(y1).add(c(6));
    let lo = p23.mul(y2).add(p01);
    let hi = p67.mul(y2).add(p45);
    let top = c(8).mul(y4).add(hi);
    top.mul(y4).add(lo).to_array()
}

/// Two f64 lanes: one SSE2 register on x86-64 (always available there), a pair elsewhere. Each
/// lane performs exactly the scalar operation.
#[derive(Clone, Copy)]
struct F2(
    #[cfg(target_arch = "x86_64")] std::arch::x86_64::__m128d,
    #[cfg(not(target_arch = "x86_64"))] [f64; 2],
);

// SAFETY (every `unsafe` block below): SSE2 is part of the x86-64 baseline, so its intrinsics
// are always available; the only memory access is the unaligned 16-byte store into a [f64; 2].
#[cfg(target_arch = "x86_64")]
impl F2 {
    #[inline(always)]
    fn new(x: f64, y: f64) -> Self {
        unsafe { F2(std::arch::x86_64::_mm_set_pd(y, x)) }
    }
    #[inline(always)]
    fn splat(x: f64) -> Self {
        unsafe { F2(std::arch::x86_64::_mm_set1_pd(x)) }
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        unsafe { F2(std::arch::x86_64::_mm_mul_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        unsafe { F2(std::arch::x86_64::_mm_add_pd(self.0, o.0)) }
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 2] {
        let mut out = [0.0; 2];
        unsafe { std::arch::x86_64::_mm_storeu_pd(out.as_mut_ptr(), self.0) };
        out
    }
}

#[cfg(not(target_arch = "x86_64"))]
impl F2 {
    #[inline(always)]
    fn new(x: f64, y: f64) -> Self {
        F2([x, y])
    }
    #[inline(always)]
    fn splat(x: f64) -> Self {
        F2([x, x])
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        F2([self.0[0] * o.0[0], self.0[1] * o.0[1]])
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        F2([self.0[0] + o.0[0], self.0[1] + o.0[1]])
    }
    #[inline(always)]
    fn to_array(self) -> [f64; 2] {
        self.0
    }
}

/// (sin 2πu, cos 2πu) for finite `u` (typically a uniform number in [0, 1)).
///
/// The reduction is exact: t = 4u is split into the nearest integer q (the quadrant) and
/// r = t − q ∈ [−½, ½] without rounding (for |t| < 2⁵²), so the result is as accurate as
/// [`sin_cos_quarter`] at x = r·π/2 — the only rounding is in 4u for |u| ≥ 2⁵⁰ and in r·π/2.
///
/// `sin_cos_2pi(0.125)` is (√½, √½) to 1e-15 (tests below).
#[inline]
pub fn sin_cos_2pi(u: f64) -> (f64, f64) {
    let t = 4.0 * u;
    // Nearest integer without `f64::round`, which is a libm call on baseline x86-64: truncate
    // (saturating; NaN → 0, and then r is NaN), then step by one if the remainder exceeds ½.
    // Selects, not branches: on random arguments a branch per quadrant step and per quadrant
    // mispredicts about half the time, which cost more than the polynomial.
    let q0 = t as i64;
    let r0 = t - q0 as f64;
    let (up, down) = ((r0 > 0.5) as i64, (r0 < -0.5) as i64);
    let q = q0 + up - down;
    let r = r0 - (up - down) as f64;
    let (s, c) = sin_cos_quarter(r * FRAC_PI_2);
    // Rotate by q quarter turns (q & 3: 0 → (s, c), 1 → (c, −s), 2 → (−s, −c), 3 → (−c, s)):
    // swap on odd q, negate the first on q & 2, the second on q = 1, 2 (mod 4); `&` works for
    // negative q too.
    let (a, b) = if q & 1 != 0 { (c, s) } else { (s, c) };
    (
        negate_if(a, q & 2 != 0),
        negate_if(b, (q ^ (q >> 1)) & 1 != 0),
    )
}

/// −x when `neg`, else x (a sign-bit flip, exact, no branch).
#[inline(always)]
fn negate_if(x: f64, neg: bool) -> f64 {
    f64::from_bits(x.to_bits() ^ ((neg as u64) << 63))
}

/// atan(z)/z = P(z²) for |z| ≤ tan(π/8): coefficients of w⁰ … w¹⁰, fitted by interpolation at
/// the 11 Chebyshev nodes of w ∈ [0, tan²(π/8)] in 60-digit arithmetic; the largest relative
/// error of z·P(z²) against atan z, evaluated in f64, is 2.0·10⁻¹⁶ over the range.
const ATAN: [f64; 11] = [
    1.0,
    -0.333_333_333_333_284_4,
    0.199_999_999_988_551_1,
    -0.142_857_141_809_764_67,
    0.111_111_061_804_559_46,
    -0.090_907_730_748_084_14,
    0.076_899_534_963_068_57,
    -0.066_402_339_304_294_08,
    0.056_883_492_268_090_106,
    -0.043_480_522_157_164_62,
    0.021_135_373_157_693_246,
];

/// atan2(y, x) ∈ [−π, π] for finite arguments, inline and without branches (libm's costs 20–40
/// ns where a sampler's density needs two per call).
///
/// The ratio z = min(|x|, |y|) / max(|x|, |y|) ∈ [0, 1] is reduced to |z′| ≤ tan(π/8) with
/// atan z = π/4 + atan((z − 1)/(z + 1)) above tan(π/8), by one division either way; then
/// z′ P(z′²) ([`ATAN`]) and the octant. Error: relative 4·10⁻¹⁶ in the first octant's small
/// branch, and at most 1·10⁻¹⁵ absolute after the reductions (roundings of π/4, π/2 − a and
/// π − a). atan2(0, 0) = 0 (libm gives ±0 or ±π by the signs of zero; callers here pass
/// directions, never both zero). NaN in, NaN out.
///
/// `atan2(1.0, -1.0)` is 3π/4 to 1e-15 (tests below).
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_4, PI};
    const TAN_PI_8: f64 = 0.414_213_562_373_095_03;
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = (ax.min(ay), ax.max(ay));
    let big = lo > TAN_PI_8 * hi;
    let (num, den) = if big { (lo - hi, lo + hi) } else { (lo, hi) };
    let z = if den > 0.0 { num / den } else { num };
    let w = z * z;
    // Estrin's scheme on w: P = (c0 + c1 w) + (c2 + c3 w) w² + ((c4 + c5 w) + (c6 + c7 w) w²) w⁴
    // + ((c8 + c9 w) + c10 w²) w⁸.
    let c = &ATAN;
    let w2 = w * w;
    let w4 = w2 * w2;
    let p01 = c[0] + c[1] * w;
    let p23 = c[2] + c[3] * w;
    let p45 = c[4] + c[5] * w;
    let p67 = c[6] + c[7] * w;
    let p89 = c[8] + c[9] * w;
    let p = (p01 + p23 * w2) + (p45 + p67 * w2) * w4 + (p89 + c[10] * w2) * (w4 * w4);
    let mut a = z * p + if big { FRAC_PI_4 } else { 0.0 };
    if ay > ax {
        a = FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = PI - a;
    }
    if (x + y).is_nan() {
        return f64::NAN; // min and max above drop a NaN
    }
    negate_if(a, y.is_sign_negative())
}

/// Bits of the table index of [`ln`]: 2⁷ subintervals of the reduced argument.
const LN_BITS: u32 = 7;
/// The reduced argument z lies in [0.6875, 1.375): these are the bits of 0.6875.
const LN_OFF: u64 = 0x3fe6_0000_0000_0000;
/// ln 2 split so that k · LN2_HI is exact for |k| < 2¹¹ (its last 11 bits are zero).
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fefa_3800);
/// ln 2 − LN2_HI.
const LN2_LO: f64 = f64::from_bits(0x3d2e_f357_93c7_6730);

/// Per subinterval of z: (1/c, ln c) for a point c of the subinterval (its midpoint; exactly 1
/// for the two subintervals next to 1, so that r = z − 1 is exact there).
static LN_TABLE: std::sync::LazyLock<[[f64; 2]; 1 << LN_BITS]> = std::sync::LazyLock::new(|| {
    std::array::from_fn(|i| {
        let lo = f64::from_bits(LN_OFF + ((i as u64) << (52 - LN_BITS)));
        let hi = f64::from_bits(LN_OFF + ((i as u64 + 1) << (52 - LN_BITS)));
        if lo == 1.0 || hi == 1.0 {
            return [1.0, 0.0];
        }
        let invc = 1.0 / (0.5 * (lo + hi));
        [invc, -invc.ln()]
    })
});

/// Natural logarithm, inline and table-driven: x = 2^k z with z ∈ [0.6875, 1.375), z in one of
/// 128 subintervals with point c, ln x = k ln 2 + ln c + ln(1 + r) with r = z/c − 1,
/// |r| ≤ 0.0078, and ln(1 + r) by its Taylor polynomial of degree 8 (remainder r⁹/9 ≤ 10⁻²⁰).
/// Without a fused multiply-add, r = z · (1/c) − 1 carries one rounding of the product, so the
/// error bound is absolute near x = 1 — |error| ≤ 2·10⁻¹⁶ + 3.4·10⁻¹⁶ |ln x| — which is what
/// samplers need (tan² α = −m² ln(1 − u) enters D only through exp(−tan² α / m²), where an
/// absolute error δ is a relative error δ). Zero, negative, subnormal, infinite and NaN
/// arguments go to libm.
///
/// `ln(0.3)` is `0.3f64.ln()` to 1e-15 (tests below).
#[inline]
pub fn ln(x: f64) -> f64 {
    if !(f64::MIN_POSITIVE..f64::INFINITY).contains(&x) {
        return x.ln();
    }
    let ix = x.to_bits();
    let tmp = ix.wrapping_sub(LN_OFF);
    let i = ((tmp >> (52 - LN_BITS)) as usize) & ((1 << LN_BITS) - 1);
    let k = (tmp as i64) >> 52;
    let z = f64::from_bits(ix.wrapping_sub(tmp & (0xfff << 52)));
    let [invc, logc] = LN_TABLE[i];
    let r = z * invc - 1.0;
    let kd = k as f64;
    // ln(1 + r) = r + r² q(r), q = −1/2 + r/3 − r²/4 + r³/5 − r⁴/6 + r⁵/7 − r⁶/8 (Estrin).
    let r2 = r * r;
    let r4 = r2 * r2;
    let q01 = -0.5 + r * (1.0 / 3.0);
    let q23 = -0.25 + r * (1.0 / 5.0);
    let q45 = -1.0 / 6.0 + r * (1.0 / 7.0);
    let q = q01 + r2 * q23 + r4 * (q45 + r2 * (-1.0 / 8.0));
    let hi = kd * LN2_HI + logc;
    hi + (r + (kd * LN2_LO + r2 * q))
}

#[cfg(test)]
mod tests;
