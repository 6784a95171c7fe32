//! Eight lookups at once: the kernel's warp variables, knot lines, nodes and corner weights with
//! one pair per AVX2 lane, then each pair's blend (RGB, or any channel count four at a time).
//!
//! Why: one lookup of a measured table is a chain of dependent steps — three square roots and a
//! division for the warp variables, a knot line per axis, then the corner rows — about 180
//! cycles long, and the one-pair path ([`Kernel::eval`]) is bound by that chain and by its
//! ~200 instructions, not by memory (the table sits in L2). A renderer that shades in
//! wavefronts, and every batch call of the hosts ([`crate::Brdf::eval_batch`]), has many
//! independent pairs at hand. Here the warp variables, the knot lines (gathered), the node
//! indices and the corner weights of eight pairs take one AVX2 register each — an eighth of
//! the instructions per pair — and the eight blends that follow are independent chains the
//! CPU overlaps.
//!
//! Every lane performs the IEEE operations of the one-pair path in the same order (no fused
//! multiply-add), and the blend and its end are the one-pair path's own code
//! ([`Kernel::blend_rows`], [`Kernel::finish_rgb`]; for other channel counts
//! [`Kernel::blend_runs`], the projection and the calibration), so the results are bit-equal to
//! [`Kernel::eval`]'s (tested); the one-pair path stays the reference. Groups holding a pair
//! the lanes do not take — a direction that is not unit length, a pair beyond a resampled
//! axis's cut, a table too short for a corner — are left to the caller's one-pair loop.

use glam::DVec3;

#[cfg(target_arch = "x86_64")]
use super::{Calibration, MIN_COS_PRODUCT, Quantity, project_f32_lanes};
use super::{Kernel, Packed};
#[cfg(target_arch = "x86_64")]
use crate::simd::F4;

/// Pairs per group of [`Kernel::eval_x8`].
pub const LANES: usize = 8;

/// Every lane of a group.
const ALL: u8 = u8::MAX;

/// Whether this CPU runs the eight-lane path (AVX2 and F16C; checked at kernel construction).
pub(super) fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("f16c")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

impl Kernel {
    /// Whether [`Kernel::eval_x8`] runs for this kernel on this CPU: a CPU with AVX2 and F16C
    /// (and corner offsets within i32).
    pub fn has_x8(&self) -> bool {
        self.x8
    }

    /// Evaluates the first [`LANES`] pairs of `wi`, `wo` into `out[..c · LANES]` (c channels per
    /// pair)
    /// from the table's `values` ([`Packed::for_kernel`]), bit-equal to [`Kernel::eval`] pair by
    /// pair. Returns the lanes left to the caller's one-pair path (bit k: pair k; its output
    /// is unspecified): a direction that is not unit length (within
    /// [`crate::geometry::is_near_unit_l2`]) and a pair beyond a resampled axis's cut; all of them when the
    /// table is too short for some corner, there are fewer than [`LANES`] pairs or no
    /// eight-lane path ([`Kernel::has_x8`]).
    pub fn eval_x8(&self, wi: &[DVec3], wo: &[DVec3], out: &mut [f32], values: &Packed) -> u8 {
        if !self.x8 {
            return ALL;
        }
        #[cfg(target_arch = "x86_64")]
        if let (Some(wi), Some(wo), Some(out)) = (
            wi.first_chunk::<LANES>(),
            wo.first_chunk::<LANES>(),
            out.get_mut(..self.channels * LANES),
        ) {
            // SAFETY: `x8` is set only when the CPU has AVX2 and F16C (`available`).
            return unsafe {
                if self.exact {
                    self.x8_avx2::<true>(wi, wo, out, values)
                } else {
                    self.x8_avx2::<false>(wi, wo, out, values)
                }
            };
        }
        let _ = (wi, wo, out, values);
        ALL
    }

    /// [`Kernel::eval_x8`] in AVX2 lanes; `EXACT`: the table holds exact values.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,f16c")]
    fn x8_avx2<const EXACT: bool>(
        &self,
        wi: &[DVec3; LANES],
        wo: &[DVec3; LANES],
        out: &mut [f32],
        values: &Packed,
    ) -> u8 {
        use std::arch::x86_64::*;
        // The pairs in lanes, with the one-pair path's checks and corrections
        // (`geometry::is_near_unit_l2` of each squared length in f64 and
        // `geometry::unit_or_near`; cos θ > 0 in f64). A lane whose pair is below the
        // horizon or left to the caller computes on what it holds: every step below maps NaN
        // and infinities into the table (min/max return their bound), and its output is 0 or
        // the caller's.
        let ((unit_i, up_i, scale_i), (unit_o, up_o, scale_o)) = (checks(wi), checks(wo));
        let (wi, wo) = (split(wi, scale_i), split(wo, scale_o));
        let left = !(unit_i & unit_o);
        let upper = up_i & up_o;
        let [ix, iy, iz] = wi;
        let [ox, oy, oz] = wo;
        let splat = _mm256_set1_ps;
        let (zero, one) = (splat(0.0), splat(1.0));
        let (add, sub, mul, div) = (_mm256_add_ps, _mm256_sub_ps, _mm256_mul_ps, _mm256_div_ps);
        let sqrt = _mm256_sqrt_ps;
        let abs = |x| _mm256_andnot_ps(splat(-0.0), x);
        // SAFETY (stores below): each is of eight f32/i32 into an array of eight.
        let st = |a: &mut [f32; LANES], x| unsafe { _mm256_storeu_ps(a.as_mut_ptr(), x) };
        let sti = |a: &mut [u32; LANES], x| unsafe {
            _mm256_storeu_si256(a.as_mut_ptr() as *mut __m256i, x)
        };

        // The warp variables: `Kernel::vars_lanes`, lane by lane.
        let (hx, hy, hz) = (add(ix, ox), add(iy, oy), add(iz, oz));
        let r2 = add(mul(hx, hx), mul(hy, hy));
        let hh = add(r2, mul(hz, hz));
        let hl = sqrt(hh);
        let vh = if self.h_quarter_power {
            sqrt(sqrt(div(r2, add(hh, mul(hl, hz)))))
        } else {
            sqrt(sqrt(div(r2, hh)))
        };
        let (ex, ey, ez) = (sub(ix, ox), sub(iy, oy), sub(iz, oz));
        let e2 = add(add(mul(ex, ex), mul(ey, ey)), mul(ez, ez));
        let dx = sub(mul(hz, add(mul(hx, ix), mul(hy, iy))), mul(r2, iz));
        let dy = abs(mul(hl, sub(mul(hx, iy), mul(hy, ix))));
        let den = add(abs(dx), dy);
        let pos = _mm256_cmp_ps::<_CMP_GT_OQ>(den, zero);
        let pd = _mm256_blendv_ps(one, den, pos);
        let pn = if self.quarter {
            _mm256_blendv_ps(zero, dy, pos)
        } else {
            _mm256_blendv_ps(one, dx, pos)
        };
        let cc = match self.quantity {
            Quantity::FrCosOut => oz,
            _ => mul(iz, oz),
        };
        let inv_cc = div(one, _mm256_max_ps(cc, splat(MIN_COS_PRODUCT)));
        let vd = sqrt(div(e2, mul(splat(2.0), add(splat(2.0), hl))));
        let q = div(pn, pd);
        let vp = if self.quarter {
            q
        } else {
            sub(splat(0.5), mul(splat(0.5), q))
        };
        let v = [vh, vd, vp];
        let [k, kcap, nmax, ncap, cut] = [
            self.lanes[0],
            self.lanes[1],
            self.lanes[2],
            self.lanes[3],
            self.cut,
        ]
        .map(|l| l.to_array());
        let mut left = left;
        if self.resampled {
            for a in 0..3 {
                let beyond = _mm256_cmp_ps::<_CMP_GE_OQ>(v[a], splat(cut[a]));
                left |= _mm256_movemask_ps(beyond) as u8;
            }
        }

        // Per axis: the knot interval (its line gathered), the fractional node index, its lower
        // node and the upper one's weight: `Kernel::eval_rgb`, lane by lane.
        let mut node = [_mm256_setzero_si256(); 3];
        let (mut w, mut om) = ([zero; 3], [zero; 3]);
        for a in 0..3 {
            let axis = &self.axes[a];
            let t = mul(v[a], splat(k[a]));
            let j = _mm256_cvttps_epi32(_mm256_min_ps(t, splat(kcap[a])));
            let j = _mm256_min_epu32(j, _mm256_set1_epi32(axis.kmax as i32));
            let base = axis.lines.as_ptr() as *const f32;
            // SAFETY: j ≤ kmax < lines.len(): both gathers read within `lines` (c at 8j, d at
            // 8j + 4 bytes).
            let (c, d) = unsafe {
                (
                    _mm256_i32gather_ps::<8>(base, j),
                    _mm256_i32gather_ps::<8>(base.add(1), j),
                )
            };
            let s = _mm256_min_ps(_mm256_max_ps(add(c, mul(t, d)), zero), splat(nmax[a]));
            node[a] = _mm256_cvttps_epi32(_mm256_min_ps(s, splat(ncap[a])));
            w[a] = sub(s, _mm256_cvtepi32_ps(node[a]));
            om[a] = sub(one, w[a]);
        }
        let row_w = [
            mul(om[0], om[1]),
            mul(om[0], w[1]),
            mul(w[0], om[1]),
            mul(w[0], w[1]),
        ];
        let mut p = [[0f32; LANES]; 8];
        for r in 0..4 {
            st(&mut p[r], mul(row_w[r], om[2]));
            st(&mut p[4 + r], mul(row_w[r], w[2]));
        }
        let offset = _mm256_add_epi32(
            _mm256_add_epi32(
                _mm256_mullo_epi32(node[0], _mm256_set1_epi32(self.chunk as i32)),
                _mm256_mullo_epi32(node[1], _mm256_set1_epi32(self.row as i32)),
            ),
            _mm256_mullo_epi32(node[2], _mm256_set1_epi32(self.channels as i32)),
        );
        let (mut o, mut inv) = ([0u32; LANES], [0f32; LANES]);
        sti(&mut o, offset);
        st(&mut inv, inv_cc);
        // Every corner within the values (only an empty or short table fails this).
        let len = if EXACT {
            values.full.len()
        } else {
            values.bits.len()
        };
        // (RGB: a row's two corners as two loads of four, the last at r + 3.)
        let c = self.channels;
        let reach = self.chunk + self.row + c + 4 * c.div_ceil(4);
        if o.iter().any(|&o| o as usize + reach > len) {
            return ALL;
        }

        // The calibration's cells of both cosines: `Calibration::apply_rgb`, lane by lane.
        let (mut cell, mut frac) = ([[0u32; LANES]; 2], [[0f32; LANES]; 2]);
        if let Some((scale, last, last_cell)) = self.calibration.as_ref().and_then(|c| c.rgb_axis())
        {
            for (side, cos) in [iz, oz].into_iter().enumerate() {
                let t = sqrt(_mm256_max_ps(sub(one, cos), zero));
                let s = _mm256_min_ps(mul(t, splat(scale)), splat(last));
                let j = _mm256_cvttps_epi32(s);
                let j = _mm256_min_epu32(j, _mm256_set1_epi32(last_cell as i32));
                sti(&mut cell[side], j);
                st(&mut frac[side], sub(s, _mm256_cvtepi32_ps(j)));
            }
        }

        if c != 3 {
            // Any other channel count: `Kernel::eval`'s general path at the lanes' corners.
            let (mut cos_i, mut cos_o) = ([0f32; LANES], [0f32; LANES]);
            st(&mut cos_i, iz);
            st(&mut cos_o, oz);
            for (k, dst) in out.chunks_exact_mut(c).enumerate().take(LANES) {
                if left & (1 << k) != 0 {
                    continue;
                }
                if upper & (1 << k) == 0 {
                    dst.fill(0.0);
                    continue;
                }
                let cos = [cos_i[k], cos_o[k]];
                let cells = (self.calibration.as_ref()).map(|c| c.cells(cos[0], cos[1]));
                let o = o[k] as usize;
                let rows = [o, o + self.row, o + self.chunk, o + self.chunk + self.row];
                let weights = std::array::from_fn(|r| (p[r][k], p[4 + r][k]));
                self.blend_runs::<true, EXACT>(rows, weights, dst, values);
                if self.quantity != Quantity::Fr {
                    project_f32_lanes(self.quantity, None, cos, dst);
                }
                if let (Some(cal), Some(cells)) = (&self.calibration, cells) {
                    cal.apply_lanes_cells(cells, dst);
                }
            }
            return left;
        }

        // Eight independent blends: the one-pair path's own.
        for k in 0..LANES {
            if left & (1 << k) != 0 {
                continue;
            }
            let dst = &mut out[3 * k..3 * k + 3];
            if upper & (1 << k) == 0 {
                dst.fill(0.0);
                continue;
            }
            let weights = std::array::from_fn(|r| (F4::splat(p[r][k]), F4::splat(p[4 + r][k])));
            let x = self.blend_rows::<true, EXACT>(o[k] as usize, weights, values);
            let cal = |c: &Calibration, x| {
                c.apply_rgb_cells([cell[0][k], cell[1][k]], [frac[0][k], frac[1][k]], x)
            };
            let x = self.finish_rgb(x, inv[k], cal);
            dst.copy_from_slice(&x.to_array()[..3]);
        }
        left
    }
}

/// The x, y and z of eight directions in f32 lanes, each scaled in f64 by its lane of `scale`
/// (from [`checks`]) and rounded as `as f32`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn split(
    d: &[DVec3; LANES],
    scale: [std::arch::x86_64::__m256d; 2],
) -> [std::arch::x86_64::__m256; 3] {
    use std::arch::x86_64::*;
    let [a, b] =
        [0, 1].map(|h| components(d, h).map(|x| _mm256_cvtpd_ps(_mm256_mul_pd(x, scale[h]))));
    [0, 1, 2].map(|c| _mm256_set_m128(b[c], a[c]))
}

/// The unit-length check of eight directions (bit k: direction k's squared length, computed as
/// `DVec3::length_squared` does, passes `geometry::is_near_unit_l2`), the upper-hemisphere
/// check (z > 0) and each direction's scale, in f64 lanes: 1 for a direction unit to within
/// 2⁻⁴⁰ (`geometry::is_unit_l2`: used as is), `geometry::near_unit`'s factor (3 − l²)/2 for
/// any other — the one-pair path's operations, so the same values.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn checks(d: &[DVec3; LANES]) -> (u8, u8, [std::arch::x86_64::__m256d; 2]) {
    use std::arch::x86_64::*;
    let (mut unit, mut upper) = (0u8, 0u8);
    let mut scale = [_mm256_set1_pd(1.0); 2];
    for (h, sc) in scale.iter_mut().enumerate() {
        let [x, y, z] = components(d, h);
        let l2 = _mm256_add_pd(
            _mm256_add_pd(_mm256_mul_pd(x, x), _mm256_mul_pd(y, y)),
            _mm256_mul_pd(z, z),
        );
        let dev = _mm256_andnot_pd(_mm256_set1_pd(-0.0), _mm256_sub_pd(l2, _mm256_set1_pd(1.0)));
        let exact = _mm256_cmp_pd::<_CMP_LE_OQ>(dev, _mm256_set1_pd(1.0 / (1u64 << 40) as f64));
        let near = _mm256_cmp_pd::<_CMP_LE_OQ>(dev, _mm256_set1_pd(crate::geometry::NEAR_UNIT_L2));
        let newton = _mm256_sub_pd(_mm256_set1_pd(1.5), _mm256_mul_pd(_mm256_set1_pd(0.5), l2));
        *sc = _mm256_blendv_pd(newton, _mm256_set1_pd(1.0), exact);
        let ok = _mm256_movemask_pd(near) as u8;
        let up = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(z, _mm256_setzero_pd())) as u8;
        unit |= ok << (4 * h);
        upper |= up << (4 * h);
    }
    (unit, upper, scale)
}

/// x, y and z of directions 4h .. 4h + 4 in f64 lanes: three loads of the twelve values (x0 y0
/// z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3), two blends and one permutation per component.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn components(d: &[DVec3; LANES], h: usize) -> [std::arch::x86_64::__m256d; 3] {
    use std::arch::x86_64::*;
    let f: &[f64; 3 * LANES] = bytemuck_dvec3(d);
    let at = &f[12 * h..12 * h + 12];
    // SAFETY: `at` holds twelve f64; each load reads four of them.
    let [m0, m1, m2] = [0, 4, 8].map(|i| unsafe { _mm256_loadu_pd(at[i..i + 4].as_ptr()) });
    // x: m0[0], m0[3], m1[2], m2[1] → lanes (x0, x3, x2, x1), then reordered.
    let x = _mm256_blend_pd::<0b0010>(_mm256_blend_pd::<0b0100>(m0, m1), m2);
    // y: m1[0], m0[1], m2[2], m1[3] → (y1, y0, y3, y2).
    let y = _mm256_blend_pd::<0b0100>(_mm256_blend_pd::<0b1001>(m0, m1), m2);
    // z: m2[0], m1[1], m0[2], m2[3] → (z2, z1, z0, z3).
    let z = _mm256_blend_pd::<0b1001>(_mm256_blend_pd::<0b0010>(m0, m1), m2);
    [
        _mm256_permute4x64_pd::<0b01_10_11_00>(x),
        _mm256_permute4x64_pd::<0b10_11_00_01>(y),
        _mm256_permute4x64_pd::<0b11_00_01_10>(z),
    ]
}

/// Eight directions as their 24 components (`DVec3` is three f64, `repr(C)`).
#[cfg(target_arch = "x86_64")]
fn bytemuck_dvec3(d: &[DVec3; LANES]) -> &[f64; 3 * LANES] {
    const _: () = assert!(std::mem::size_of::<DVec3>() == 24);
    const _: () = assert!(std::mem::align_of::<DVec3>() == 8);
    // SAFETY: DVec3 is `repr(C)` { x, y, z: f64 } with no padding (size 24, align 8, checked
    // above), so eight of them are 24 consecutive f64.
    unsafe { &*(d.as_ptr() as *const [f64; 3 * LANES]) }
}

#[cfg(test)]
mod tests;
