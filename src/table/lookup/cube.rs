//! The two-phase linear lookup of batches: the eight corners of a trilinear lookup found first
//! ([`super::Lookup::prepare`]), prefetched, then gathered, so that several lookups' loads are in
//! flight at once.

/// The eight corners of a trilinear lookup over stored axes 0, 2 and 3: the two θ1-node
/// chunks, the offsets along axes 2 and 3 and the weights. All eight corners are read
/// unconditionally (a corner of weight 0 adds 0 — stored values are finite), with fixed trip
/// counts, so the loops unroll and the eight loads are issued together.
#[derive(Debug, Clone, Copy)]
pub struct Cube<'a> {
    pub(super) data: [&'a [f32]; 2],
    pub(super) ob: [usize; 2],
    pub(super) oq: [usize; 2],
    pub(super) wa: [f32; 2],
    pub(super) wb: [f32; 2],
    pub(super) wq: [f32; 2],
}

impl Cube<'_> {
    /// Accumulates exactly `N` channels into `out[..N]` (a corner outside its chunk — a chunk
    /// that could not be loaded — counts as 0).
    #[inline(always)]
    pub(super) fn gather<const N: usize>(&self, out: &mut [f32]) {
        let mut acc = [0.0f32; N];
        for i in 0..2 {
            for j in 0..2 {
                let w = self.wa[i] * self.wb[j];
                for k in 0..2 {
                    let off = self.ob[j] + self.oq[k];
                    if let Some(v) = self.data[i].get(off..off + N) {
                        let wt = w * self.wq[k];
                        for ch in 0..N {
                            acc[ch] += wt * v[ch];
                        }
                    }
                }
            }
        }
        out[..N].copy_from_slice(&acc);
    }

    /// [`Cube::gather`] for `channels` = 3 or 1 (the only counts a cube is built for).
    #[inline(always)]
    fn gather_into(&self, channels: usize, out: &mut [f32]) {
        if channels == 3 {
            self.gather::<3>(out);
        } else {
            self.gather::<1>(out);
        }
    }

    /// Hints the processor to fetch the cache lines of the four (θ1, θ2) corner rows.
    #[inline(always)]
    fn prefetch(&self) {
        #[cfg(target_arch = "x86_64")]
        for d in &self.data {
            for &o in &self.ob {
                if let Some(v) = d.get(o + self.oq[0]) {
                    // SAFETY: prefetching is a hint with no effect on memory or on faults; the
                    // address is in bounds anyway.
                    #[allow(unused_unsafe)]
                    unsafe {
                        std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
                            v as *const f32 as *const i8,
                        );
                    }
                }
            }
        }
    }
}

/// A lookup after its first phase ([`Lookup::prepare`](super::Lookup::prepare)).
#[derive(Debug, Clone, Copy)]
pub enum Prepared<'a> {
    /// The pair is invalid or below the horizon: every channel is 0.
    Zero,
    /// An eight-corner lookup, ready to prefetch and gather.
    Cube(Cube<'a>),
    /// A lookup the two-phase path does not cover (packed `inout`, channel counts other than
    /// 1 and 3, anisotropic off-node): use [`Lookup::eval`](super::Lookup::eval).
    General,
}

impl Prepared<'_> {
    /// Prefetches the corners' cache lines (a no-op for the other variants).
    #[inline(always)]
    pub fn prefetch(&self) {
        if let Prepared::Cube(c) = self {
            c.prefetch();
        }
    }

    /// Writes the lookup's `channels` values into `out`; returns `false` for
    /// [`Prepared::General`] (nothing written: call [`Lookup::eval`](super::Lookup::eval)).
    #[inline(always)]
    pub fn gather(&self, channels: usize, out: &mut [f32]) -> bool {
        match self {
            Prepared::Zero => {
                out[..channels].fill(0.0);
                true
            }
            Prepared::Cube(c) => {
                c.gather_into(channels, out);
                true
            }
            Prepared::General => false,
        }
    }
}
