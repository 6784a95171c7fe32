//! The kernel's blends: from the warp variables to the interpolated values — per axis the knot
//! line and the node, then the eight corners of the (θh, θd, φd) cell read from [`Packed`]
//! values and weighted. Three channels in four-lane registers ([`Kernel::eval_rgb`],
//! [`Kernel::blend_rows`], also the eight-lane path's blend), any count four at a time
//! ([`Kernel::blend_lanes`]), and the scalar reference both are tested against
//! (`Kernel::blend`).
//!
//! Why a file of its own: this is the arithmetic of every lookup, all `#[inline(always)]`
//! into the entry points in the parent module (`Kernel::eval`, `rgb_f16c`,
//! `blend_lanes_f16c`) and [`super::x8`]; it reads the table and the axes and nothing else.

use super::Kernel;
use super::packed::Packed;
use crate::simd::F4;

impl Kernel {
    /// `Kernel::blend` for three channels on four-lane registers ([`F4`]): the three axes'
    /// knot and node arithmetic in one register, then each of the four (θh, θd) corner rows
    /// as two four-lane loads (RGB of the two φd corners; the fourth lane is ignored). Computes
    /// the same operations as `blend::<3>`, which stays as its reference (tested equal).
    #[inline(always)]
    pub(super) fn eval_rgb<const F16C: bool, const EXACT: bool>(
        &self,
        v: F4,
        values: &Packed,
    ) -> F4 {
        let [k, kcap, nmax, ncap] = self.lanes;
        let zero = F4::splat(0.0);
        // Knot interval j and its fraction per axis (lane 3: 0).
        // v ∈ [0, 1] by construction (each is a ratio bounded by 1), so t ∈ [0, K] up to
        // rounding; the truncation bound K − ½ keeps j ≤ K − 1 (and maps NaN there too).
        let t = v * k;
        let (j, _) = t.min(kcap).trunc();
        let (c, d) = F4::transpose_pairs(
            self.axes[0].line(j[0]),
            self.axes[1].line(j[1]),
            self.axes[2].line(j[2]),
        );
        // Fractional node index s, clamped to [0, n − 1] (beyond the first and last cell
        // centres the end values hold), its lower node (≤ n − 2) and the upper one's weight.
        let s = (c + t * d).max(zero).min(nmax);
        let (i, if_) = s.min(ncap).trunc();
        let w = s - if_;
        let om = F4::splat(1.0) - w;
        // Row weights (1−th)(1−td), (1−th)td, th(1−td), th·td, times each φd corner's weight.
        let rw = F4::pair_lanes::<0>(om, w) * F4::interleave_lo(om.lane::<1>(), w.lane::<1>());
        let (p0, p1) = (rw * om.lane::<2>(), rw * w.lane::<2>());
        let o = i[0] as usize * self.chunk + i[1] as usize * self.row + i[2] as usize * 3;
        let weights = [
            (p0.lane::<0>(), p1.lane::<0>()),
            (p0.lane::<1>(), p1.lane::<1>()),
            (p0.lane::<2>(), p1.lane::<2>()),
            (p0.lane::<3>(), p1.lane::<3>()),
        ];
        self.blend_rows::<F16C, EXACT>(o, weights, values)
    }

    /// The RGB blend of [`Kernel::eval_rgb`] from the corner offset `o` (the lower corner's
    /// first value) and the four (θh, θd) rows' weights of their two φd corners (each weight in
    /// every lane); the scaled result times the table's unscale. Shared by the one-pair path
    /// and the eight-lane one ([`x8`]), so both compute the same operations.
    ///
    /// [`x8`]: super::x8
    #[inline(always)]
    pub(super) fn blend_rows<const F16C: bool, const EXACT: bool>(
        &self,
        o: usize,
        weights: [(F4, F4); 4],
        values: &Packed,
    ) -> F4 {
        let mut acc = F4::splat(0.0);
        let load = |x: &[u16]| {
            if F16C {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `F16C` is true only in functions compiled with F16C enabled, which
                // run when the CPU has it (`rgb_f16c`, `x8`).
                return unsafe { F4::from_f16_f16c(x) };
            }
            F4::from_f16_normal(x)
        };
        // The four rows' values, all within o .. o + chunk + row + 7 (one bounds check; only
        // an empty table fails it). Each row's six values r..r+6: four at r (φd corner 0 in
        // lanes 0..3) and four at r + 3 (corner 1; the fourth lane reads the next row or the
        // padding, ignored).
        let span = o..o + self.chunk + self.row + 7;
        let offsets = [0, self.row, self.chunk, self.chunk + self.row];
        // The windows of row offset r: x[r..r + 4] and x[r + 3..r + 7].
        fn windows<T>(x: &[T], r: usize) -> (&[T], &[T]) {
            debug_assert!(r + 7 <= x.len());
            // SAFETY: callers pass x = values[o..o + chunk + row + 7] and r ≤ chunk + row,
            // so r + 7 ≤ x.len(): both windows lie within x.
            unsafe { (x.get_unchecked(r..r + 4), x.get_unchecked(r + 3..r + 7)) }
        }
        if EXACT {
            if let Some(x) = values.full.get(span) {
                for (r, (w0, w1)) in offsets.into_iter().zip(weights) {
                    let (a, b) = windows(x, r);
                    if let (Some(a), Some(b)) = (F4::load(a), F4::load(b)) {
                        acc = acc + (w0 * a + w1 * b);
                    }
                }
            }
        } else if let Some(x) = values.bits.get(span) {
            for (r, (w0, w1)) in offsets.into_iter().zip(weights) {
                let (a, b) = windows(x, r);
                if let (Some(a), Some(b)) = (load(a), load(b)) {
                    acc = acc + (w0 * a + w1 * b);
                }
            }
        }
        acc * F4::splat(values.unscale)
    }

    /// `Kernel::blend` for any number of channels, four at a time: each corner row's two φd
    /// corners (`channels` values each, adjacent) are read as runs of four-lane loads — f16
    /// codes expanded four at once (`F16C`) or exact values (`EXACT`) — instead of one value
    /// and one conversion at a time (one lookup of a seven-wavelength measured table: 140 → 79 ns).
    /// The same operations lane by lane as `blend::<0>`, its reference (tested bit-equal). The
    /// last run of a row reads up to three values beyond it: the next row's, or the
    /// [`PACK_PAD`] zeros after the table; those lanes are not written out.
    ///
    /// [`PACK_PAD`]: super::packed::PACK_PAD
    #[inline(always)]
    pub(super) fn blend_lanes<const F16C: bool, const EXACT: bool>(
        &self,
        v: [f32; 3],
        out: &mut [f32],
        values: &Packed,
    ) {
        let c = self.channels.min(crate::spectrum::MAX_CHANNELS);
        let (rows, w, (wp0, wp1)) = self.corners(v, c);
        let weights = w.map(|w| (w * wp0, w * wp1));
        self.blend_runs::<F16C, EXACT>(rows, weights, out, values)
    }

    /// The blend of [`Kernel::blend_lanes`] from the four (θh, θd) corner rows' offsets and
    /// the weights of each row's two φd corners: shared by the one-pair path and the
    /// eight-lane one ([`x8`]), so both compute the same operations.
    ///
    /// [`x8`]: super::x8
    #[inline(always)]
    pub(super) fn blend_runs<const F16C: bool, const EXACT: bool>(
        &self,
        rows: [usize; 4],
        weights: [(f32, f32); 4],
        out: &mut [f32],
        values: &Packed,
    ) {
        const RUNS: usize = crate::spectrum::MAX_CHANNELS.div_ceil(4);
        let c = self.channels.min(4 * RUNS);
        let runs = c.div_ceil(4);
        let mut acc = [F4::splat(0.0); RUNS];
        let n = values.len();
        let load = |r: usize| -> Option<F4> {
            if EXACT {
                return values.full.get(r..r + 4).and_then(F4::load);
            }
            let x = values.bits.get(r..r + 4)?;
            if F16C {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: `F16C` is true only inside `blend_lanes_f16c`, compiled with F16C
                // and called when the CPU has it.
                return unsafe { F4::from_f16_f16c(x) };
            }
            F4::from_f16_normal(x)
        };
        for (r, (w0, w1)) in rows.iter().zip(weights) {
            // The reference's condition: both corners within the values.
            if *r + 2 * c <= n {
                let (w0, w1) = (F4::splat(w0), F4::splat(w1));
                for (q, acc) in acc.iter_mut().enumerate().take(runs) {
                    if let (Some(a), Some(b)) = (load(r + 4 * q), load(r + c + 4 * q)) {
                        *acc = *acc + (w0 * a + w1 * b);
                    }
                }
            }
        }
        let unscale = F4::splat(values.unscale);
        for (q, chunk) in out[..c].chunks_mut(4).enumerate() {
            let x = (acc[q] * unscale).to_array();
            chunk.copy_from_slice(&x[..chunk.len()]);
        }
    }

    /// The corners of a trilinear blend at warp variables `v` with `c` channels per node: the
    /// offsets of the four (θh, θd) corner rows, each holding its two φd corners side by side
    /// (`c` values apart), the rows' weights, and the two φd weights.
    #[inline(always)]
    fn corners(&self, v: [f32; 3], c: usize) -> ([usize; 4], [f32; 4], (f32, f32)) {
        let (ih, th) = self.axes[0].node(v[0]);
        let (id, td) = self.axes[1].node(v[1]);
        let (ip, tp) = self.axes[2].node(v[2]);
        let o = ih * self.chunk + id * self.row + ip * c;
        let rows = [o, o + self.row, o + self.chunk, o + self.chunk + self.row];
        let w = [
            (1.0 - th) * (1.0 - td),
            (1.0 - th) * td,
            th * (1.0 - td),
            th * td,
        ];
        (rows, w, (1.0 - tp, tp))
    }

    /// Trilinear blend of the eight corners; `N` > 0: exactly N channels in registers. The
    /// reference of [`Kernel::eval_rgb`] (which computes the same operations in lanes) and of
    /// [`Kernel::blend_lanes`]; the lookups call those, so it is built for the tests only.
    #[cfg(test)]
    #[inline(always)]
    pub(super) fn blend<const N: usize>(&self, v: [f32; 3], out: &mut [f32], values: &Packed) {
        let c = if N > 0 { N } else { self.channels };
        let (rows, w, (wp0, wp1)) = self.corners(v, c);
        let out = &mut out[..c];
        out.fill(0.0);
        let n = values.len();
        for (r, w) in rows.iter().zip(w) {
            if *r + 2 * c <= n {
                let (w0, w1) = (w * wp0, w * wp1);
                for (k, o) in out.iter_mut().enumerate() {
                    *o += w0 * values.scaled(r + k) + w1 * values.scaled(r + c + k);
                }
            }
        }
        for x in out.iter_mut() {
            *x *= values.unscale;
        }
    }
}
