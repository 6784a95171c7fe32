//! The lanes' unit tests: the operations against the scalar ones, the pairs' transposition at any
//! alignment, and the f16 lanes exact on every finite code, also when the thread flushes
//! subnormals.

use super::*;

#[test]
fn lanes_do_the_scalar_operations() {
    let a = F4::new(1.5, -2.0, 9.0, 0.25);
    let b = F4::new(0.5, 4.0, 3.0, -8.0);
    assert_eq!((a + b).to_array(), [2.0, 2.0, 12.0, -7.75]);
    assert_eq!((a - b).to_array(), [1.0, -6.0, 6.0, 8.25]);
    assert_eq!((a * b).to_array(), [0.75, -8.0, 27.0, -2.0]);
    assert_eq!((a / b).to_array(), [3.0, -0.5, 3.0, -0.03125]);
    assert_eq!(
        F4::new(4.0, 9.0, 0.0, 2.25).sqrt().to_array(),
        [2.0, 3.0, 0.0, 1.5]
    );
    assert_eq!(a.min(b).to_array(), [0.5, -2.0, 3.0, -8.0]);
    assert_eq!(a.max(b).to_array(), [1.5, 4.0, 9.0, 0.25]);
    assert_eq!(a.lane::<2>().to_array(), [9.0; 4]);
    assert!(a.any_ge(b) && !F4::splat(-9.0).any_ge(b) && !F4::splat(f32::NAN).any_ge(b));
    assert_eq!(F4::pair_lanes::<1>(a, b).to_array(), [-2.0, -2.0, 4.0, 4.0]);
    assert_eq!(F4::interleave_lo(a, b).to_array(), [1.5, 0.5, -2.0, 4.0]);
    assert_eq!(a.shift_down().to_array(), [-2.0, 9.0, 0.25, 0.0]);
    let (i, f) = F4::new(2.7, 0.2, 7.999, 3.0).trunc();
    assert_eq!(i, [2, 0, 7, 3]);
    assert_eq!(f.to_array(), [2.0, 0.0, 7.0, 3.0]);
    // NaN in the first operand: max/min give the second (NaN never escapes a clamp).
    let n = F4::splat(f32::NAN);
    assert_eq!(n.max(F4::splat(0.0)).to_array(), [0.0; 4]);
    assert_eq!(n.min(F4::splat(1.0)).to_array(), [1.0; 4]);
    assert!(F4::load(&[1.0, 2.0, 3.0]).is_none());
    assert!(F4::from_f16_normal(&[1, 2, 3]).is_none());
    assert_eq!(
        F4::load(&[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap().to_array(),
        [1.0, 2.0, 3.0, 4.0]
    );
}

/// Pairs at any four-byte alignment, as the kernel's knot lines (`[f32; 2]` in a boxed
/// slice) are: of two pairs one and two values into one buffer, one is not eight-byte
/// aligned, so a load that requires eight (a typed `*const f64` read) is undefined
/// behaviour that Miri reports here (`tools/memcheck.sh miri`).
#[test]
fn pairs_are_transposed_at_any_alignment() {
    let v = [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];
    let at = |i: usize| -> &[f32; 2] { v[i..i + 2].try_into().unwrap() };
    for o in 0..2 {
        let (x, y) = F4::transpose_pairs(at(o), at(o + 2), at(o + 4));
        let f = o as f32;
        assert_eq!(
            (x.to_array(), y.to_array()),
            (
                [1.0 + f, 3.0 + f, 5.0 + f, 5.0 + f],
                [2.0 + f, 4.0 + f, 6.0 + f, 6.0 + f]
            )
        );
    }
}

/// Every finite f16 code read four at a time and one at a time between `flush_on()` and
/// `flush_off()` (a mode that reads subnormal inputs as 0), against the half crate's values
/// read before: bit-equal.
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
fn f16_reads_are_exact_while(flush_on: impl FnOnce(), flush_off: impl FnOnce()) {
    let bits: Vec<u16> = (0..0x7c00).chain(0x8000..0xfc00).collect();
    let want: Vec<f32> = bits
        .iter()
        .map(|&b| half::f16::from_bits(b).to_f32())
        .collect();
    flush_on();
    // The mode is on: a subnormal input reads 0.
    let flushed = std::hint::black_box(f32::from_bits(1)) * 2.0 == 0.0;
    let mut got = Vec::with_capacity(bits.len());
    let mut one = Vec::with_capacity(bits.len());
    for q in bits.chunks(4).filter(|q| q.len() == 4) {
        got.extend(
            F4::from_f16_normal(std::hint::black_box(q))
                .unwrap()
                .to_array(),
        );
    }
    for &b in &bits {
        one.push(f16_bits_to_f32(std::hint::black_box(b)));
    }
    flush_off();
    assert!(flushed, "the flush-to-zero mode did not take effect");
    for k in 0..got.len() {
        assert_eq!(
            got[k].to_bits(),
            want[k].to_bits(),
            "lanes, code {:#06x}",
            bits[k]
        );
    }
    for k in 0..bits.len() {
        assert_eq!(
            one[k].to_bits(),
            want[k].to_bits(),
            "scalar, code {:#06x}",
            bits[k]
        );
    }
}

/// Renderers set x86's DAZ and FTZ for speed (Embree asks for it, Cycles does): every f16
/// subnormal code must still read its value, on the SSE2 path as on F16C.
#[cfg(target_arch = "x86_64")]
#[test]
#[cfg_attr(miri, ignore = "inline assembly (stmxcsr/ldmxcsr): Miri cannot run it")]
fn f16_lanes_are_exact_when_the_thread_flushes_subnormals() {
    let read_csr = || {
        let mut v = 0u32;
        // SAFETY: stmxcsr stores the 4-byte MXCSR at the address of `v`.
        unsafe { std::arch::asm!("stmxcsr [{}]", in(reg) &mut v) };
        v
    };
    let write_csr = |v: u32| {
        // SAFETY: ldmxcsr loads MXCSR from `v`; only the DAZ/FTZ bits differ from the
        // thread's own value, and the test restores it.
        unsafe { std::arch::asm!("ldmxcsr [{}]", in(reg) &v) };
    };
    let old = read_csr();
    f16_reads_are_exact_while(|| write_csr(old | 0x8040), || write_csr(old)); // FTZ | DAZ
}

/// Arm's FZ (FPCR bit 24) flushes subnormal f32 inputs and outputs to zero, as renderers
/// set it for speed: the integer expansion that serves every target but x86-64 reads every
/// f16 code exactly under it.
#[cfg(target_arch = "aarch64")]
#[test]
#[cfg_attr(miri, ignore = "inline assembly (mrs/msr fpcr): Miri cannot run it")]
fn f16_lanes_are_exact_when_the_thread_flushes_subnormals() {
    let read = || {
        let v: u64;
        // SAFETY: reads this thread's FPCR, no memory access.
        unsafe { std::arch::asm!("mrs {}, fpcr", out(reg) v) };
        v
    };
    let write = |v: u64| {
        // SAFETY: writes this thread's FPCR; only FZ differs from the thread's own value,
        // and the test restores it.
        unsafe { std::arch::asm!("msr fpcr, {}", in(reg) v) };
    };
    let old = read();
    f16_reads_are_exact_while(|| write(old | 1 << 24), || write(old));
}

#[test]
fn f16_lanes_are_exact_on_every_finite_f16() {
    // Powers of two by repeated exact halving/doubling: `powi`'s precision is unspecified
    // (Miri rounds it off by an ulp or so, as a platform's libm may).
    let pow2 = |e: i32| (0..e.abs()).fold(1f32, |x, _| if e < 0 { x / 2.0 } else { x * 2.0 });
    assert_eq!(SUBNORMAL_MAGIC, pow2(-14));
    assert_eq!(f32::from_bits(REBIAS + (127 << 23)), pow2(112));
    // Every finite f16 — zero, subnormals, normals, both signs — four at a time against the
    // half crate.
    let bits: Vec<u16> = (0..0x7c00).chain(0x8000..0xfc00).collect();
    for q in bits.chunks(4).filter(|q| q.len() == 4) {
        let want: Vec<f32> = q
            .iter()
            .map(|&b| half::f16::from_bits(b).to_f32())
            .collect();
        let got = F4::from_f16_normal(q).unwrap().to_array();
        assert_eq!(&got[..], &want[..], "{q:?}");
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("f16c") {
            // SAFETY: F16C is present (just detected).
            let h = unsafe { F4::from_f16_f16c(q) }.unwrap().to_array();
            assert_eq!(h, got, "{q:?}");
        }
    }
}
