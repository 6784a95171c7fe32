//! Random numbers of the tools (the renderer's pixel streams, `sample`'s draws, the benchmarks'
//! pairs): PCG32 from `rand_pcg`, with the few conversions they use. The core library keeps its
//! own generator private; the tools need not share its sequence, only its reproducibility (same
//! seed, same numbers).

use glam::DVec2;
use rand_core::{RngCore, SeedableRng};

/// A seeded PCG32 stream.
#[derive(Debug, Clone)]
pub struct Rng(rand_pcg::Pcg32);

impl Rng {
    /// The stream of `seed` on the default stream selector.
    pub fn new(seed: u64) -> Rng {
        Rng(rand_pcg::Pcg32::seed_from_u64(seed))
    }

    /// The stream of `seed` on stream selector `stream` (independent streams, e.g. per pixel).
    pub fn with_stream(seed: u64, stream: u64) -> Rng {
        Rng(rand_pcg::Pcg32::new(seed, stream))
    }

    /// The next 32 random bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        self.0.next_u32()
    }

    /// A uniform `f64` in [0, 1) with 53 random bits.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Two uniform numbers in [0, 1).
    #[inline]
    pub fn next_dvec2(&mut self) -> DVec2 {
        DVec2::new(self.next_f64(), self.next_f64())
    }

    /// An integer in [0, n) by multiply-shift (Lemire 2019 without the rejection step): the
    /// bias is below n / 2³², far under anything a preview's sample shuffling can show.
    pub fn below(&mut self, n: u32) -> u32 {
        ((self.next_u32() as u64 * n as u64) >> 32) as u32
    }
}
