//! A small deterministic random number generator (PCG32, O'Neill 2014).
//!
//! brdftab needs reproducible random numbers for analysis (random direction pairs), tests,
//! benchmarks and the renderer's deterministic seeds; a 16-byte generator with streams is all that
//! takes, so there is no dependency on `rand`.

use glam::DVec2;

/// PCG-XSH-RR 64/32: 64-bit state, 32-bit output, selectable stream.
#[derive(Debug, Clone)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

const MULT: u64 = 6364136223846793005;

impl Pcg32 {
    /// A generator seeded with `seed` on the default stream.
    pub fn new(seed: u64) -> Self {
        Self::with_stream(seed, 0xda3e39cb94b95bdb)
    }

    /// A generator seeded with `seed` on stream `stream` (different streams are independent,
    /// e.g. one per tile or per thread).
    pub fn with_stream(seed: u64, stream: u64) -> Self {
        let mut r = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    /// The next 32 random bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform `f64` in [0, 1) with 53 random bits.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() as u64) << 21;
        let lo = (self.next_u32() as u64) >> 11;
        (hi | lo) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Two uniform numbers in [0, 1).
    #[inline]
    pub fn next_dvec2(&mut self) -> DVec2 {
        DVec2::new(self.next_f64(), self.next_f64())
    }

    /// A uniform integer in [0, n) (n > 0), without modulo bias.
    pub fn below(&mut self, n: u32) -> u32 {
        let threshold = n.wrapping_neg() % n;
        loop {
            let r = self.next_u32();
            if r >= threshold {
                return r % n;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_mean_and_range() {
        let mut r = Pcg32::new(42);
        let n = 100_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let x = r.next_f64();
            assert!((0.0..1.0).contains(&x));
            sum += x;
        }
        // Standard error of the mean is 1/sqrt(12 n) ≈ 9e-4; allow 5 sigma.
        assert!((sum / n as f64 - 0.5).abs() < 5.0 / (12.0 * n as f64).sqrt());
    }

    #[test]
    fn seeds_and_streams_differ() {
        assert_ne!(Pcg32::new(1).next_u32(), Pcg32::new(2).next_u32());
        assert_ne!(
            Pcg32::with_stream(1, 1).next_u32(),
            Pcg32::with_stream(1, 2).next_u32()
        );
    }
}
