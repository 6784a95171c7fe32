//! The fast lookup of isotropic `halfdiff` tables — adaptive (warped) ones and the presets' and
//! MERL-style fixed mappings: what a renderer calls per shading point on a measured material or
//! a baked analytic model.
//!
//! The general lookup ([`super::lookup`]) computes the four Rusinkiewicz angles with acos and
//! atan2 and maps each through its axis. On a table whose θh, θd and φd axes are all
//! [`Warp`]s ([`super::adaptive`]), every axis only needs its warp *variable*, and
//! those come from the direction vectors without any transcendental function. With
//! h = ωi + ωo (not normalized) and unit ωi, ωo:
//!
//! - cos θd = ωi·ĥ = (1 + ωi·ωo)/|h| = |h|/2, so v_d = (1 − |h|/2)^½;
//! - sin²θh = (h_x² + h_y²)/|h|², so v_h = (sin θh)^½ needs no |h| first;
//! - the Rusinkiewicz difference vector d = R_y(−θh) R_z(−φh) ωi has, up to the common positive
//!   factor sin θh |h|², d_x ∝ h_z (h_x ωi_x + h_y ωi_y) − (h_x² + h_y²) ωi_z and
//!   d_y ∝ |h| (h_x ωi_y − h_y ωi_x), and the pseudo-angle of φd is a ratio of these.
//!
//! Then per axis one line on the variable's knot interval (one eight-byte load) gives the
//! fractional node index, and eight corners (λ innermost: two runs of 2 × channels adjacent
//! values per (θh, θd) pair) are blended in f32 from the table's f16 codes ([`Packed`]: half
//! the bytes, so a measured material's table stays in L2; expanded with F16C when the CPU has
//! it, chosen once per kernel).
//!
//! Grids on fixed mappings — the presets' (sqrt θh, cos θd, uniform φd) and MERL-style ones
//! (uniform θd: `--grid 90x1x90x180 --param halfdiff`) — take the same path: their mappings
//! are *resampled* as knot lines in the same variables ([`RESAMPLED_KNOTS`] per axis, within
//! [`RESAMPLE_TOLERANCE`] node units of the exact mapping), θh in (1 − cos θh)^¼
//! ([`WarpVar::QuarterPower`]), in which sqrt θh is smooth up to 90° (in √sin θh it has a
//! square-root singularity there), θd and φd in their usual variables. An axis whose knot lines
//! strayed from the mapping beyond some interval would get a *cut* there, pairs beyond it going
//! to the general lookup ([`Kernel::eval`] returns false); none of these mappings has one.
//! Such a table keeps exact f32 values ([`Packed::exact`]): it is what a user baked an
//! analytic model on (a Lambert table gives kd to f32 rounding), and the stored f32 values
//! stay what [`super::TabulatedBrdf::to_table`] and nearest lookups read. (The MERL-size grid
//! used to read f16 codes beyond 1 MiB of values: a median 1.17× faster, L3-bound, at a
//! rounding of up to 2^-11 of a value — given up when the presets, analytic tables, came to
//! this path; BENCHMARKS.md.)
//!
//! [`Kernel::eval`] is tested against the reference path (angles through
//! [`super::symmetry::canonical_coords`] and [`super::StoredAxis::linear`]) in this module's
//! tests.

use glam::DVec3;

use crate::geometry;
use crate::simd::F4;
use std::f64::consts::{FRAC_PI_2, PI};

use crate::table::calibration::Calibration;
use crate::table::grid::{Grid, Mapping, Nodes, Param, Quantity, StoredAxis};
use crate::table::warp::{Warp, WarpVar};

mod x8;
pub use x8::LANES;

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
/// set aside by [`super::TabulatedBrdf`] before they reach here.
///
/// Small tables whose kernel resamples a fixed mapping ([`Kernel::exact_values`]) keep f32
/// values instead ([`Packed::exact`]): such a table is what a user baked on a grid of their own
/// choosing, and while it fits in L2 its lookups give the stored values at the nodes exactly
/// at no cost in speed.
#[derive(Debug, Clone)]
pub struct Packed {
    /// The codes, then [`PACK_PAD`] zeros (a row's second four-value load reads past its end);
    /// empty for exact values.
    bits: Box<[u16]>,
    /// Exact values (f32), then [`PACK_PAD`] zeros; empty for codes.
    full: Box<[f32]>,
    /// 2^−e: multiplies the blended scaled values (exact; 1 for exact values).
    unscale: f32,
}

/// Zero codes after a [`Packed`] table's values.
const PACK_PAD: usize = 4;

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
        let full = values
            .iter()
            .map(|&v| if v.is_finite() { v } else { 0.0 })
            .chain(std::iter::repeat_n(0.0, PACK_PAD))
            .collect();
        Packed {
            bits: Box::new([]),
            full,
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
    fn scaled(&self, i: usize) -> f32 {
        if !self.full.is_empty() {
            return self.full.get(i).copied().unwrap_or(0.0);
        }
        self.bits
            .get(i)
            .map_or(0.0, |&b| half::f16::from_bits(b).to_f32())
    }
}

/// The most stored values a grid with resampled axes may have for the kernel to take it: the
/// kernel holds a table in one array, loaded whole at the first lookup; larger tables keep
/// their lazily loaded chunks (and the general lookup). 36 Mi values (144 MiB of f32) takes
/// every preset (the large non-reciprocal one stores 35.2 M values).
pub const RESAMPLED_MAX_VALUES: usize = 36 << 20;

/// Knots of a resampled axis (a fixed mapping read in the kernel's variable).
pub const RESAMPLED_KNOTS: usize = 1024;

/// How far (node units) a resampled axis's knot lines may stray from the exact mapping; from
/// the first interval that strays further, lookups take the general path.
pub const RESAMPLE_TOLERANCE: f64 = 1e-4;

/// One warped axis as the kernel reads it: the fractional node index s as a line in t = v·K
/// on each knot interval.
#[derive(Debug, Clone)]
struct Axis {
    /// Interval j (t ∈ [j, j + 1]): s = c + t·d, as `[c, d]`, where s = u·(n − 1) (edges)
    /// or u·n − ½ (centres) at the knots. One eight-byte load per lookup and no t − j.
    lines: Box<[[f32; 2]]>,
    /// K as f32.
    k: f32,
    /// Number of nodes (≥ 2).
    n: usize,
    /// The last knot interval (K − 1).
    kmax: u32,
    /// The last lower node (n − 2).
    imax: i32,
}

impl Axis {
    /// `centers`: node i at u = (i + ½)/n, s = u·n − ½; otherwise at u = i/(n − 1).
    fn new(w: &Warp, n: usize, centers: bool) -> Axis {
        let (scale, shift) = if centers {
            (n as f64, -0.5)
        } else {
            ((n - 1) as f64, 0.0)
        };
        let s: Vec<f64> = w
            .knots()
            .iter()
            .map(|&u| u as f64 * scale + shift)
            .collect();
        Axis::from_knots(&s, n)
    }

    /// The axis of a fixed mapping (not a warp) in the kernel's variable `var`: s at
    /// [`RESAMPLED_KNOTS`] + 1 knots uniform in v, computed exactly ([`StoredAxis::continuous`],
    /// unclamped), and the variable `vcut` from which the knot lines stray from the exact s by
    /// more than [`RESAMPLE_TOLERANCE`] node units (checked at three points per interval; 2
    /// when they never do). `None` when that leaves less than half the axis.
    fn resampled(ax: &StoredAxis, var: WarpVar, hi: f64) -> Option<(Axis, f32)> {
        let k = RESAMPLED_KNOTS;
        let s_at = |v: f64| ax.continuous(var.angle_of(v, hi));
        let s: Vec<f64> = (0..=k).map(|j| s_at(j as f64 / k as f64)).collect();
        if s.iter().any(|x| !x.is_finite()) {
            return None;
        }
        let n = ax.size;
        let clamp = |x: f64| x.clamp(0.0, (n - 1) as f64);
        let bad = (0..k).find(|&j| {
            [0.25, 0.5, 0.75].iter().any(|&f| {
                let line = s[j] + f * (s[j + 1] - s[j]);
                let exact = s_at((j as f64 + f) / k as f64);
                (clamp(line) - clamp(exact)).abs() > RESAMPLE_TOLERANCE
            })
        });
        let vcut = match bad {
            None => 2.0,
            Some(j) if j >= k / 2 => (j as f64 / k as f64) as f32,
            Some(_) => return None,
        };
        Some((Axis::from_knots(&s, n), vcut))
    }

    /// The knot lines of s given at K + 1 knots uniform in v, for an axis of `n` nodes.
    fn from_knots(s: &[f64], n: usize) -> Axis {
        let lines = s
            .windows(2)
            .enumerate()
            .map(|(j, p)| {
                let d = p[1] - p[0];
                [(p[0] - j as f64 * d) as f32, d as f32]
            })
            .collect();
        Axis {
            lines,
            k: (s.len() - 1) as f32,
            n,
            kmax: (s.len() - 2) as u32,
            imax: (n - 2) as i32,
        }
    }

    /// The line of knot interval `j` (clamped to the last; a negative j — never made — to it
    /// too).
    #[inline(always)]
    fn line(&self, j: i32) -> &[f32; 2] {
        let j = (j as u32).min(self.kmax) as usize;
        debug_assert!(j < self.lines.len());
        // SAFETY: `lines` has kmax + 1 entries (`Axis::from_knots`, the only constructor, sets
        // kmax to their count − 1; neither changes afterwards), and j ≤ kmax.
        unsafe { self.lines.get_unchecked(j) }
    }

    /// The lower node and the weight of the upper one at variable `v` ∈ [0, 1] (the scalar
    /// reference of the lane code in [`Kernel::eval_rgb`], the same operations).
    ///
    /// Indices go through i32: a saturating f32 → usize conversion costs about three times as
    /// many instructions, and every value here is in [0, 2^16].
    #[inline(always)]
    fn node(&self, v: f32) -> (usize, f32) {
        let t = v * self.k;
        // max/min, not clamp: NaN becomes the bound instead of propagating.
        let [c, d] = *self.line(t.min(self.k - 0.5) as i32);
        let s = (c + t * d).max(0.0).min((self.n - 1) as f32);
        let i = (s.min(self.n as f32 - 1.5) as i32).clamp(0, self.imax);
        (i as usize, s - i as f32)
    }
}

/// Whether the kernel resamples fixed mapping `m` on stored axis `k` (0: θh, 2: θd, 3: φd):
/// sqrt θh, uniform or cos θd, uniform φd.
fn fixed_mapping_fits(k: usize, m: &Mapping) -> bool {
    match k {
        0 => *m == Mapping::Sqrt,
        2 => matches!(m, Mapping::Uniform | Mapping::Cos),
        _ => *m == Mapping::Uniform,
    }
}

/// One axis of a [`KernelLayout`](super::device::KernelLayout): what a device evaluates of
/// this kernel's axes. Defined here (the kernel writes it), re-exported by [`super::device`].
#[derive(Debug, Clone, serde::Serialize)]
pub struct KernelAxis {
    /// Per knot interval j (of K = `c.len()`): s = `c[j] + t·d[j]` at t = v·K ∈ \[j, j + 1\].
    pub c: Vec<f32>,
    /// The slopes (see `c`).
    pub d: Vec<f32>,
    /// Number of nodes (≥ 2).
    pub nodes: usize,
    /// Pairs whose variable is at or above the cut take the
    /// [`GridLayout`](super::device::GridLayout) (2: never).
    pub cut: f32,
}

/// The fast linear lookup of a table on an adaptive grid (see the module docs).
#[derive(Debug, Clone)]
pub struct Kernel {
    axes: [Axis; 3],
    /// φd folded onto [0, π/2] (reciprocity) instead of [0, π].
    quarter: bool,
    /// θh's variable is [`WarpVar::QuarterPower`] ((1 − cos θh)^¼) instead of
    /// [`WarpVar::SqrtSine`].
    h_quarter_power: bool,
    channels: usize,
    /// Values per θd row of a chunk (stored φd nodes × channels).
    row: usize,
    /// Values per chunk (θh node).
    chunk: usize,
    /// Lane constants of [`Kernel::eval_rgb`]: K per axis, K − ½ (the last knot interval's
    /// truncation bound), n − 1 and n − 1.5 per axis; lane 3 is unused (0).
    lanes: [F4; 4],
    /// The CPU has F16C (checked once, at construction): RGB lookups expand codes with it.
    f16c: bool,
    /// Per axis the variable from which lookups take the general path (resampled axes; 2 on
    /// warped ones, never; lane 3: 2).
    cut: F4,
    /// Some axis is resampled (a fixed mapping).
    resampled: bool,
    /// Some axis has a cut (< 2): RGB lookups check it.
    cuts: bool,
    /// What the values are: lookups of a quantity other than f_r divide by its factor.
    quantity: Quantity,
    /// The albedo calibration lookups multiply by, if any.
    calibration: Option<Calibration>,
    /// Values are read exact ([`Packed::exact`]): some axis is resampled.
    exact: bool,
    /// [`Kernel::eval_x8`] runs: three channels, offsets within i32, and the CPU has AVX2 and
    /// F16C (checked once, at construction).
    x8: bool,
}

impl Kernel {
    /// The kernel of `grid` when it applies: `halfdiff`, isotropic and bilateral, θh (by
    /// [`WarpVar::SqrtSine`] or [`WarpVar::QuarterPower`]), θd and φd warped with their default
    /// variables on edge nodes, or on fixed mappings over the whole axes (sqrt θh, uniform or
    /// cos θd, uniform φd on edge nodes; at most [`RESAMPLED_MAX_VALUES`] values), resampled.
    /// `None` otherwise (use the general lookup).
    pub fn new(grid: &Grid) -> Option<Kernel> {
        let s = grid.symmetry();
        if grid.param() != Param::HalfDiff || !s.isotropic || !s.bilateral {
            return None;
        }
        let ax = grid.stored_axes();
        let phi_hi = if s.reciprocal { FRAC_PI_2 } else { PI };
        let want = [
            (0, WarpVar::SqrtSine, FRAC_PI_2),
            (2, WarpVar::HalfPower, FRAC_PI_2),
            (3, WarpVar::PseudoAngle, phi_hi),
        ];
        let mut axes = Vec::with_capacity(3);
        let mut cut = [2f32; 4];
        let mut resampled = false;
        let mut h_quarter_power = false;
        for (i, (k, var, hi)) in want.into_iter().enumerate() {
            let a = &ax[k];
            let nodes_ok = match a.nodes {
                Nodes::Edges => true,
                Nodes::Centers => k != 3,
                Nodes::CellStart => false,
            };
            if a.size < 2 || !nodes_ok || a.periodic {
                return None;
            }
            let centers = a.nodes == Nodes::Centers;
            match &a.mapping {
                Mapping::Warp(w) if w.var() == var => axes.push(Axis::new(w, a.size, centers)),
                Mapping::Warp(w) if k == 0 && w.var() == WarpVar::QuarterPower => {
                    h_quarter_power = true;
                    axes.push(Axis::new(w, a.size, centers));
                }
                // Fixed mappings — MERL's (sqrt θh, uniform θd and φd) and the presets' (cos
                // θd) — resampled. θh in the quarter-power variable: sqrt θh is smooth in it
                // up to 90°, where in v_h = √sin θh it has a square-root singularity.
                m @ (Mapping::Sqrt | Mapping::Uniform | Mapping::Cos)
                    if fixed_mapping_fits(k, m)
                        && grid.stored_values() <= RESAMPLED_MAX_VALUES
                        && a.lo == 0.0
                        && (a.hi - hi).abs() < 1e-12 =>
                {
                    let var = if k == 0 {
                        h_quarter_power = true;
                        WarpVar::QuarterPower
                    } else {
                        var
                    };
                    let (axis, vcut) = Axis::resampled(a, var, hi)?;
                    axes.push(axis);
                    cut[i] = vcut;
                    resampled = true;
                }
                _ => return None,
            }
        }
        let axes: [Axis; 3] = axes.try_into().ok()?;
        let channels = grid.channels().len();
        // The eight-lane path computes corner offsets in i32 lanes.
        let x8 = channels == 3 && grid.stored_values() < (i32::MAX as usize) / 2 && x8::available();
        let per = |f: &dyn Fn(&Axis) -> f32| F4::new(f(&axes[0]), f(&axes[1]), f(&axes[2]), 0.0);
        let lanes = [
            per(&|a| a.k),
            per(&|a| a.k - 0.5),
            per(&|a| (a.n - 1) as f32),
            per(&|a| a.n as f32 - 1.5),
        ];
        Some(Kernel {
            lanes,
            row: axes[2].n * channels,
            chunk: axes[1].n * axes[2].n * channels,
            axes,
            quarter: s.reciprocal,
            h_quarter_power,
            channels,
            f16c: has_f16c(),
            cut: F4::new(cut[0], cut[1], cut[2], cut[3]),
            resampled,
            cuts: cut.iter().any(|&c| c < 2.0),
            exact: resampled,
            quantity: grid.quantity(),
            calibration: grid.calibration().cloned(),
            x8,
        })
    }

    /// Whether this kernel reads exact (f32) values ([`Packed::exact`]): some axis resamples a
    /// fixed mapping. Warped (adaptive) tables read f16 codes ([`Packed::new`]).
    pub fn exact_values(&self) -> bool {
        self.exact
    }

    /// The kernel's three axes (θh, θd, φd) as [`super::device`] describes them: per knot
    /// interval the line s = c + t·d (t = v·K), the node count and the cut.
    pub(crate) fn device_axes(&self) -> [KernelAxis; 3] {
        let cut = self.cut.to_array();
        std::array::from_fn(|i| {
            let a = &self.axes[i];
            KernelAxis {
                c: a.lines.iter().map(|l| l[0]).collect(),
                d: a.lines.iter().map(|l| l[1]).collect(),
                nodes: a.n,
                cut: cut[i],
            }
        })
    }

    /// θh's variable: [`WarpVar::QuarterPower`] or [`WarpVar::SqrtSine`].
    pub(crate) fn h_var(&self) -> WarpVar {
        if self.h_quarter_power {
            WarpVar::QuarterPower
        } else {
            WarpVar::SqrtSine
        }
    }

    /// φd is folded onto [0, π/2] (reciprocity): v_φ = |d_y|/(|d_x| + |d_y|).
    pub(crate) fn quarter(&self) -> bool {
        self.quarter
    }

    /// Whether some axis resamples a fixed mapping (MERL-style grids and the presets); false
    /// on adaptive (warped) grids.
    pub fn resampled(&self) -> bool {
        self.resampled
    }

    /// Whether some resampled axis has a cut, beyond which pairs take the general lookup
    /// ([`Kernel::eval`] returns false there). The fixed mappings the kernel takes today are
    /// smooth in its variables over the whole axis, so none has.
    pub fn has_cut(&self) -> bool {
        self.cuts
    }

    /// The warp variables (v_h, v_d, v_φ) of a pair, or `None` below the horizon (the fast
    /// path; [`reference_vars`] is the same in the paper's terms).
    #[inline(always)]
    pub fn vars(&self, wi: DVec3, wo: DVec3) -> Option<[f32; 3]> {
        warp_vars(wi, wo, self.h_quarter_power, self.quarter).map(|(v, _)| v)
    }

    /// [`Kernel::vars`] on four lanes: the three quotients in one division, the square roots
    /// in one (two for v_h); the same IEEE operations, so the same values (tested).
    /// Lane 0 of the one division also gives 1 / (cos θi cos θo) (returned beside the variables;
    /// the cosine product is kept at or above [`MIN_COS_PRODUCT`] so that it stays finite), and
    /// (cos θi, cos θo) come last.
    #[inline(always)]
    fn vars_lanes(&self, wi: DVec3, wo: DVec3) -> Option<(F4, f32, [f32; 2])> {
        // One branch for the usual unit pair; anything else goes through `geometry::unit`.
        let unit =
            geometry::is_unit_l2(wi.length_squared()) & geometry::is_unit_l2(wo.length_squared());
        let (wi, wo) = if unit { (wi, wo) } else { unit_pair(wi, wo)? };
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return None;
        }
        let (ix, iy, iz) = (wi.x as f32, wi.y as f32, wi.z as f32);
        let (ox, oy, oz) = (wo.x as f32, wo.y as f32, wo.z as f32);
        let (hx, hy, hz) = (ix + ox, iy + oy, iz + oz);
        let r2 = hx * hx + hy * hy;
        let hh = r2 + hz * hz;
        let hl = hh.sqrt();
        // v_h's chain (a quotient, two roots); for SqrtSine it starts without waiting for |h|.
        let vh = if self.h_quarter_power {
            (r2 / (hh + hl * hz)).sqrt().sqrt()
        } else {
            (r2 / hh).sqrt().sqrt()
        };
        let (ex, ey, ez) = (ix - ox, iy - oy, iz - oz);
        let e2 = ex * ex + ey * ey + ez * ez;
        let dx = hz * (hx * ix + hy * iy) - r2 * iz;
        let dy = (hl * (hx * iy - hy * ix)).abs();
        let den = dx.abs() + dy;
        // Lane 1: 1 − cos θd; lane 2: q = dy/den (quarter) or dx/den, the degenerate den = 0
        // giving v_φ = 0.
        let (pn, pd) = match (den > 0.0, self.quarter) {
            (true, true) => (dy, den),
            (true, false) => (dx, den),
            (false, true) => (0.0, 1.0),
            (false, false) => (1.0, 1.0),
        };
        let cc = match self.quantity {
            Quantity::FrCosOut => oz,
            _ => iz * oz,
        }
        .max(MIN_COS_PRODUCT);
        let q = F4::new(1.0, e2, pn, 0.0) / F4::new(cc, 2.0 * (2.0 + hl), pd, 1.0);
        let [q0, q1, q2, _] = q.to_array();
        let p = if self.quarter { q2 } else { 0.5 - 0.5 * q2 };
        let v = F4::new(vh, q1.sqrt(), p, 0.0);
        Some((v, q0, [iz, oz]))
    }

    /// Evaluates into `out[..channels]` from the table's `values` (all chunks, in order, as
    /// [`Packed::for_kernel`] makes them; corners beyond its end — none for [`Packed::empty`], a
    /// table that could not be loaded — count as 0). Returns false, with `out` untouched, for a
    /// pair beyond a resampled axis's cut: the caller looks it up on the general path.
    #[inline]
    pub fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32], values: &Packed) -> bool {
        if self.channels == 3 {
            if self.exact {
                return self.rgb::<false, true, true>(wi, wo, out, values);
            }
            #[cfg(target_arch = "x86_64")]
            if self.f16c {
                // SAFETY: `f16c` is set only when the CPU has F16C (`has_f16c`).
                return unsafe {
                    if self.cuts {
                        self.rgb_f16c::<true>(wi, wo, out, values)
                    } else {
                        self.rgb_f16c::<false>(wi, wo, out, values)
                    }
                };
            }
            return if self.cuts {
                self.rgb::<false, false, true>(wi, wo, out, values)
            } else {
                self.rgb::<false, false, false>(wi, wo, out, values)
            };
        }
        let Some((v, cos)) = warp_vars(wi, wo, self.h_quarter_power, self.quarter) else {
            out[..self.channels].fill(0.0);
            return true;
        };
        if F4::new(v[0], v[1], v[2], 0.0).any_ge(self.cut) {
            return false;
        }
        // The calibration's cells first: they need only the cosines (see `rgb`).
        let cells = (self.calibration.as_ref()).map(|c| c.cells(cos[0], cos[1]));
        #[cfg(target_arch = "x86_64")]
        if self.exact {
            self.blend_lanes::<false, true>(v, out, values);
        } else if self.f16c {
            // SAFETY: `f16c` is set only when the CPU has F16C (`has_f16c`).
            unsafe { self.blend_lanes_f16c(v, out, values) };
        } else {
            self.blend::<0>(v, out, values);
        }
        #[cfg(not(target_arch = "x86_64"))]
        self.blend::<0>(v, out, values);
        let out = &mut out[..self.channels];
        if self.quantity != Quantity::Fr {
            // In f32, as the RGB lookup does (one rule for every channel count).
            project_f32_lanes(self.quantity, None, cos, out);
        }
        if let (Some(c), Some(cells)) = (&self.calibration, cells) {
            c.apply_lanes_cells(cells, out);
        }
        true
    }

    /// The RGB lookup of f16 codes compiled with F16C (and the VEX encoding it brings).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "f16c")]
    fn rgb_f16c<const CUT: bool>(
        &self,
        wi: DVec3,
        wo: DVec3,
        out: &mut [f32],
        values: &Packed,
    ) -> bool {
        self.rgb::<true, false, CUT>(wi, wo, out, values)
    }

    /// The RGB lookup; `F16C`: expand codes with F16C (only inside [`Kernel::rgb_f16c`]);
    /// `EXACT`: read exact values; `CUT`: check the resampled axes' cut (warped axes have none:
    /// the check is left out).
    #[inline(always)]
    fn rgb<const F16C: bool, const EXACT: bool, const CUT: bool>(
        &self,
        wi: DVec3,
        wo: DVec3,
        out: &mut [f32],
        values: &Packed,
    ) -> bool {
        match self.vars_lanes(wi, wo) {
            // Only resampled axes have a cut (< 2).
            Some((v, _, _)) if CUT && v.any_ge(self.cut) => false,
            Some((v, inv_cc, [cos_i, cos_o])) => {
                // The calibration's factors first: they need only the cosines, and here they
                // run beside the blend's chain (after it, they lengthened the lookup by 5 ns).
                let k = (self.calibration.as_ref()).and_then(|c| c.factors_rgb(cos_i, cos_o));
                let x = self.eval_rgb::<F16C, EXACT>(v, values);
                let cal = |_: &Calibration, x| Calibration::times(x, k);
                let [r, g, b, _] = self.finish_rgb(x, inv_cc, cal).to_array();
                out[..3].copy_from_slice(&[r, g, b]);
                true
            }
            None => {
                out[..3].fill(0.0);
                true
            }
        }
    }

    /// f_r from the blended RGB `x` of a pair with 1/(its quantity's factor) `inv_cc`: a
    /// quantity other than f_r divided by its factor and clamped at 0, then the calibration
    /// applied by `cal` (at the pair's cosines; the one-pair and eight-lane paths' common end).
    #[inline(always)]
    fn finish_rgb(&self, mut x: F4, inv_cc: f32, cal: impl FnOnce(&Calibration, F4) -> F4) -> F4 {
        if self.quantity != Quantity::Fr {
            // Extrapolated nodes beyond the horizon may pull the blend below 0.
            x = (x * F4::splat(inv_cc)).max(F4::splat(0.0));
        }
        if let Some(c) = &self.calibration {
            x = cal(c, x);
        }
        x
    }

    /// [`Kernel::blend`] for three channels on four-lane registers ([`F4`]): the three axes'
    /// knot and node arithmetic in one register, then each of the four (θh, θd) corner rows
    /// as two four-lane loads (RGB of the two φd corners; the fourth lane is ignored). Computes
    /// the same operations as `blend::<3>`, which stays as its reference (tested equal).
    #[inline(always)]
    fn eval_rgb<const F16C: bool, const EXACT: bool>(&self, v: F4, values: &Packed) -> F4 {
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
    #[inline(always)]
    fn blend_rows<const F16C: bool, const EXACT: bool>(
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

    /// [`Kernel::blend_lanes`] expanding f16 codes with F16C.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "f16c")]
    fn blend_lanes_f16c(&self, v: [f32; 3], out: &mut [f32], values: &Packed) {
        self.blend_lanes::<true, false>(v, out, values)
    }

    /// [`Kernel::blend`] for any number of channels, four at a time: each corner row's two φd
    /// corners (`channels` values each, adjacent) are read as runs of four-lane loads — f16
    /// codes expanded four at once (`F16C`) or exact values (`EXACT`) — instead of one value
    /// and one conversion at a time (one lookup of a seven-wavelength measured table: 140 → 79 ns).
    /// The same operations lane by lane as `blend::<0>`, its reference (tested bit-equal). The
    /// last run of a row reads up to three values beyond it: the next row's, or the
    /// [`PACK_PAD`] zeros after the table; those lanes are not written out.
    #[inline(always)]
    fn blend_lanes<const F16C: bool, const EXACT: bool>(
        &self,
        v: [f32; 3],
        out: &mut [f32],
        values: &Packed,
    ) {
        const RUNS: usize = crate::spectrum::MAX_CHANNELS.div_ceil(4);
        let c = self.channels.min(4 * RUNS);
        let runs = c.div_ceil(4);
        let (rows, w, (wp0, wp1)) = self.corners(v, c);
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
        for (r, w) in rows.iter().zip(w) {
            // The reference's condition: both corners within the values.
            if *r + 2 * c <= n {
                let (w0, w1) = (F4::splat(w * wp0), F4::splat(w * wp1));
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
    /// reference of [`Kernel::eval_rgb`] (which computes the same operations in lanes).
    #[inline(always)]
    fn blend<const N: usize>(&self, v: [f32; 3], out: &mut [f32], values: &Packed) {
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

/// The smallest factor (cos θi cos θo, cos θo) a lookup of a [`Quantity`] divides by (a normal
/// f32; pairs closer to the horizon keep a finite value).
pub const MIN_COS_PRODUCT: f32 = 1e-30;

/// f_r from an interpolated `quantity`: `out` divided by the quantity's factor for the pair
/// (unit vectors made here) and clamped at 0 (extrapolated nodes beyond the horizon may pull
/// the blend below 0; f_r itself is left as it is), then multiplied by the `calibration`'s
/// k_in(θi) k_out(θo) if there is one; 0 for pairs below the horizon.
pub fn project_out(
    quantity: Quantity,
    calibration: Option<&Calibration>,
    wi: DVec3,
    wo: DVec3,
    out: &mut [f32],
) {
    match geometry::upper_pair(wi, wo) {
        Some((wi, wo)) => {
            if quantity != Quantity::Fr {
                let s = 1.0 / quantity.factor(wi.z, wo.z).max(MIN_COS_PRODUCT as f64);
                for x in out.iter_mut() {
                    *x = ((*x as f64 * s) as f32).max(0.0);
                }
            }
            if let Some(c) = calibration {
                c.apply(wi.z as f32, wo.z as f32, out);
            }
        }
        None => out.fill(0.0),
    }
}

/// The warp variables (v_h, v_d, v_φ) of a pair in f32 and (cos θi, cos θo), or `None` below
/// the horizon: [`Kernel::vars`] (and `super::device`'s `KernelLayout::vars`). With h = ωi + ωo
/// (not normalized), e = ωi − ωo and r² = h_x² + h_y²: v_h = (r²/|h|²)^¼, or
/// (r²/(|h|² + |h| h_z))^¼ for `h_quarter_power`; v_d = (|e|²/(2(2 + |h|)))^½; the
/// difference vector's d_x = h_z(h_x ωi_x + h_y ωi_y) − r² ωi_z, d_y = ||h|(h_x ωi_y − h_y ωi_x)|
/// give v_φ = d_y/(|d_x| + d_y) (`quarter`) or ½ − ½ d_x/(|d_x| + d_y), 0 when both vanish.
#[inline(always)]
pub(crate) fn warp_vars(
    wi: DVec3,
    wo: DVec3,
    h_quarter_power: bool,
    quarter: bool,
) -> Option<([f32; 3], [f32; 2])> {
    let (wi, wo) = (geometry::unit(wi)?, geometry::unit(wo)?);
    if !(wi.z > 0.0 && wo.z > 0.0) {
        return None;
    }
    let (ix, iy, iz) = (wi.x as f32, wi.y as f32, wi.z as f32);
    let (ox, oy, oz) = (wo.x as f32, wo.y as f32, wo.z as f32);
    let (hx, hy, hz) = (ix + ox, iy + oy, iz + oz);
    let r2 = hx * hx + hy * hy;
    let hl = (r2 + hz * hz).sqrt();
    // sin²θh = r²/|h|², and 1 − cos θd = 1 − |h|/2 = |ωi − ωo|²/(2(2 + |h|)): no
    // cancellation near θh = 0 or θd = 0.
    let (ex, ey, ez) = (ix - ox, iy - oy, iz - oz);
    let vd = ((ex * ex + ey * ey + ez * ez) / (2.0 * (2.0 + hl))).sqrt();
    // sin θh = r/|h|, or 1 − cos θh = r²/(|h|(|h| + hz)): no cancellation near θh = 0.
    let vh = if h_quarter_power {
        (r2 / (r2 + hz * hz + hl * hz)).sqrt().sqrt()
    } else {
        (r2 / (r2 + hz * hz)).sqrt().sqrt()
    };
    let dx = hz * (hx * ix + hy * iy) - r2 * iz;
    let dy = (hl * (hx * iy - hy * ix)).abs();
    let den = dx.abs() + dy;
    let vp = if !(den > 0.0) {
        0.0
    } else if quarter {
        dy / den
    } else {
        0.5 - 0.5 * (dx / den)
    };
    Some(([vh, vd, vp], [iz, oz]))
}

/// The kernel's projection of an interpolated `quantity` at unit directions with z = `cos_i`,
/// `cos_o`, in f32: other than f_r, times 1/max(factor, [`MIN_COS_PRODUCT`]) and clamped at 0;
/// then times the `calibration`'s k_in(θi) k_out(θo) — what [`Kernel::eval`] does for every
/// channel count (the RGB path in lanes), and what `super::device` states for devices.
pub(crate) fn project_f32(
    quantity: Quantity,
    calibration: Option<&Calibration>,
    [cos_i, cos_o]: [f32; 2],
    out: &mut [f32],
) {
    if quantity != Quantity::Fr {
        let inv = inverse_factor(quantity, [cos_i, cos_o]);
        for x in out.iter_mut() {
            *x = (*x * inv).max(0.0);
        }
    }
    if let Some(c) = calibration {
        c.apply(cos_i, cos_o, out);
    }
}

/// 1/max(factor, [`MIN_COS_PRODUCT`]) of a stored `quantity` at cosines (cos θi, cos θo).
#[inline(always)]
fn inverse_factor(quantity: Quantity, [cos_i, cos_o]: [f32; 2]) -> f32 {
    let f = match quantity {
        Quantity::FrCosOut => cos_o,
        _ => cos_i * cos_o,
    };
    1.0 / f.max(MIN_COS_PRODUCT)
}

/// [`project_f32`] four channels at a time (the same operations lane by lane, tested equal).
#[inline(always)]
pub(crate) fn project_f32_lanes(
    quantity: Quantity,
    calibration: Option<&Calibration>,
    [cos_i, cos_o]: [f32; 2],
    out: &mut [f32],
) {
    if quantity != Quantity::Fr {
        let inv = inverse_factor(quantity, [cos_i, cos_o]);
        let (iv, zero) = (F4::splat(inv), F4::splat(0.0));
        let mut chunks = out.chunks_exact_mut(4);
        for x4 in &mut chunks {
            if let Some(x) = F4::load(x4) {
                x4.copy_from_slice(&(x * iv).max(zero).to_array());
            }
        }
        for x in chunks.into_remainder() {
            *x = (*x * inv).max(0.0);
        }
    }
    if let Some(c) = calibration {
        c.apply_lanes(cos_i, cos_o, out);
    }
}

/// Whether the CPU has F16C (x86-64 only).
fn has_f16c() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("f16c")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Both directions made unit (out of the hot path).
#[cold]
#[inline(never)]
fn unit_pair(wi: DVec3, wo: DVec3) -> Option<(DVec3, DVec3)> {
    Some((geometry::unit(wi)?, geometry::unit(wo)?))
}

/// The warp variables of a pair from its Rusinkiewicz angles (the reference for
/// [`Kernel::vars`]): `None` below the horizon.
pub fn reference_vars(wi: DVec3, wo: DVec3, quarter: bool, h_var: WarpVar) -> Option<[f64; 3]> {
    let (wi, wo) = geometry::upper_pair(wi, wo)?;
    let hd = geometry::to_half_diff(wi, wo)?;
    // Bilateral symmetry folds φd onto [0, π]; reciprocity (φd → φd + π) onto [0, π/2].
    let mut p = hd.phi_d.abs();
    let hi = if quarter {
        if p > std::f64::consts::FRAC_PI_2 {
            p = std::f64::consts::PI - p;
        }
        std::f64::consts::FRAC_PI_2
    } else {
        std::f64::consts::PI
    };
    Some([
        h_var.of_angle(hd.theta_h, std::f64::consts::FRAC_PI_2),
        WarpVar::HalfPower.of_angle(hd.theta_d, std::f64::consts::FRAC_PI_2),
        WarpVar::PseudoAngle.of_angle(p, hi),
    ])
}

/// The adaptive-grid cases the kernel's tests bake (reciprocity, stored quantity, θh's
/// variable): both θh variables, f_r and both projected quantities.
#[cfg(test)]
pub(crate) const TEST_CASES: [(bool, Quantity, WarpVar); 4] = [
    (false, Quantity::Fr, WarpVar::SqrtSine),
    (true, Quantity::Fr, WarpVar::QuarterPower),
    (false, Quantity::FrCosOut, WarpVar::QuarterPower),
    (true, Quantity::FrCosCos, WarpVar::SqrtSine),
];

/// The small adaptive grid the kernel's and the device layout's tests bake (24 × 16 × 9 nodes).
#[cfg(test)]
pub(crate) fn test_adaptive_options(
    quantity: Quantity,
    h_var: WarpVar,
) -> crate::table::adaptive::AdaptiveOptions {
    crate::table::adaptive::AdaptiveOptions {
        nodes: [24, 16, 9],
        fine: [64, 32, 16],
        quantity,
        h_var,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Brdf;
    use crate::rng::Pcg32;
    use crate::spec::ModelSpec;
    use crate::spectrum::Channels;
    use crate::table::adaptive::adaptive_grid;
    use crate::table::symmetry::Symmetry;
    use crate::table::{BakeOptions, TabulatedBrdf, bake, lookup::Interp, lookup::Lookup};

    fn random_pair(r: &mut Pcg32) -> (DVec3, DVec3) {
        let d = |r: &mut Pcg32| {
            let (u, v) = (r.next_f64(), r.next_f64());
            let z = u.max(1e-9);
            let s = (1.0 - z * z).sqrt();
            let p = std::f64::consts::TAU * v;
            DVec3::new(s * p.cos(), s * p.sin(), z)
        };
        (d(r), d(r))
    }

    fn test_kernel(quarter: bool, h_quarter_power: bool) -> Kernel {
        let axes =
            std::array::from_fn(|_| Axis::new(&Warp::identity(WarpVar::HalfPower), 2, false));
        let per = |x: f32| F4::new(x, x, x, 0.0);
        Kernel {
            axes,
            quarter,
            h_quarter_power,
            channels: 1,
            row: 2,
            chunk: 4,
            lanes: [per(1.0), per(0.5), per(1.0), per(0.5)],
            f16c: false,
            cut: F4::splat(2.0),
            resampled: false,
            cuts: false,
            exact: false,
            quantity: Quantity::Fr,
            calibration: None,
            x8: false,
        }
    }

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

    #[test]
    fn fast_variables_match_the_angles() {
        for (quarter, hq) in [(false, false), (true, false), (false, true), (true, true)] {
            let mut r = Pcg32::new(71);
            let k = test_kernel(quarter, hq);
            let h_var = if hq {
                WarpVar::QuarterPower
            } else {
                WarpVar::SqrtSine
            };
            for _ in 0..100_000 {
                let (wi, wo) = random_pair(&mut r);
                let f = k.vars(wi, wo).unwrap();
                let g = reference_vars(wi, wo, quarter, h_var).unwrap();
                // The lane version does the same IEEE operations.
                let l = k.vars_lanes(wi, wo).unwrap().0.to_array();
                assert_eq!(&l[..3], &f[..], "{wi} {wo}");
                // f32 arithmetic without cancellation: a few ulps of v ≤ 1. φd itself is
                // only as good as h = ωi + ωo in f32 relative to sin θh (it is undefined at
                // θh = 0, where an isotropic BRDF does not depend on it). v_h² ≤ sin θh for
                // both variables (√2 sin(θh/2) ≤ sin θh up to 90°).
                let sin_h = (g[0] * g[0]).max(1e-12);
                assert!((f[0] as f64 - g[0]).abs() < 1e-5, "{wi} {wo}: {f:?} {g:?}");
                assert!((f[1] as f64 - g[1]).abs() < 1e-5, "{wi} {wo}: {f:?} {g:?}");
                assert!(
                    (f[2] as f64 - g[2]).abs() < 1e-5 + 1e-6 / sin_h,
                    "{wi} {wo}: {f:?} {g:?}"
                );
            }
        }
    }

    /// `src` baked on the adaptive grid of one of [`TEST_CASES`] (isotropic, bilateral), and
    /// its kernel.
    fn test_table(
        src: &dyn Brdf,
        (reciprocal, quantity, h_var): (bool, Quantity, WarpVar),
    ) -> (crate::table::Table, Kernel) {
        let sym = Symmetry {
            isotropic: true,
            reciprocal,
            bilateral: true,
        };
        let opts = test_adaptive_options(quantity, h_var);
        let grid = adaptive_grid(src, sym, &opts).unwrap();
        let (t, _) = bake(src, &grid, &BakeOptions::default()).unwrap();
        let k = Kernel::new(t.grid()).expect("an adaptive grid has a kernel");
        (t, k)
    }

    #[test]
    fn kernel_agrees_with_the_general_lookup() {
        let src = ModelSpec::parse(r#"{"model": "ggx", "alpha": 0.05}"#)
            .unwrap()
            .build(&Channels::Rgb)
            .unwrap();
        // f_r tables (θh by SqrtSine and QuarterPower) and tables of the other quantities, whose
        // lookups divide by the cosines (and whose nodes beyond the horizon are extrapolated).
        for (reciprocal, quantity, h_var) in TEST_CASES {
            let (t, k) = test_table(src.as_ref(), (reciprocal, quantity, h_var));
            let general = Lookup::new(t.grid());
            let tb = TabulatedBrdf::from_table(t.clone());
            let packed = Packed::new(t.values());
            let mut r = Pcg32::new(32);
            let (mut a, mut b, mut c, mut d) = ([0f32; 3], [0f32; 3], [0f32; 3], [0f32; 3]);
            let mut soft = [0f32; 3];
            let peak = t.values().iter().fold(0f32, |m, &x| m.max(x.abs()));
            let mut worst = 0f32;
            for _ in 0..50_000 {
                let (wi, wo) = random_pair(&mut r);
                // What the lookup divides the interpolated quantity by.
                let s = match geometry::upper_pair(wi, wo) {
                    Some((i, o)) => 1.0 / quantity.factor(i.z, o.z) as f32,
                    None => 0.0,
                };
                k.eval(wi, wo, &mut a, &packed);
                // Without F16C (the integer expansion) exactly the same.
                k.rgb::<false, false, false>(wi, wo, &mut soft, &packed);
                assert_eq!(a, soft, "{wi} {wo}");
                general.eval(Interp::Linear, wi, wo, &mut b, |i| t.chunk(i));
                project_out(quantity, None, wi, wo, &mut b);
                tb.eval(wi, wo, &mut c);
                // The four-lane RGB path against its scalar reference, `blend::<3>`.
                if let Some(v) = k.vars(wi, wo) {
                    k.blend::<3>(v, &mut d, &packed);
                    project_out(quantity, None, wi, wo, &mut d);
                    for ch in 0..3 {
                        assert!((a[ch] - d[ch]).abs() <= 1e-6 * d[ch].abs(), "{a:?} {d:?}");
                    }
                }
                for ch in 0..3 {
                    // Both interpolate the same nodes; they differ by the values' f16
                    // rounding (≤ 2^-11 of each, so of the blend) and the f32 variables (a few
                    // 1e-7) times the slope in node units: below 1e-3 of the value plus 1e-4 of
                    // the table's peak (both divided by the quantity's factor).
                    let e = (a[ch] - b[ch]).abs() / (b[ch].abs() * 1e-3 + peak * 1e-4 * s);
                    worst = worst.max(e);
                    assert_eq!(a[ch], c[ch], "TabulatedBrdf uses the kernel");
                }
            }
            assert!(worst <= 1.0, "worst scaled difference {worst}");
        }
    }

    /// Tables of other than three channels blend four channels at a time
    /// (`Kernel::blend_lanes`): bit-equal to the one-value-at-a-time reference `blend::<0>`, for
    /// f16 codes (F16C and integer expansion) and exact values, at channel counts that leave
    /// every remainder of four, on tables of each quantity.
    #[test]
    fn blends_of_any_channel_count_equal_their_reference() {
        for nch in [1usize, 2, 5, 7, 12] {
            let nm: Vec<f64> = (0..nch)
                .map(|i| 400.0 + 300.0 * i as f64 / nch as f64)
                .collect();
            let channels = Channels::Wavelengths(nm);
            let src = ModelSpec::parse(
                r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2},
                    {"model": "ggx", "alpha": 0.1, "fresnel": {"conductor": "Au"}}]}"#,
            )
            .unwrap()
            .build(&channels)
            .unwrap();
            for (reciprocal, quantity, h_var) in TEST_CASES {
                let (t, k) = test_table(src.as_ref(), (reciprocal, quantity, h_var));
                let (packed, exact) = (Packed::new(t.values()), Packed::exact(t.values()));
                // The same table calibrated (symmetric factors where it folds by reciprocity):
                // its `eval` (the lanes, the projection, the calibration found before the
                // blend) against the plain steps.
                let calibrated = {
                    let k_in: Vec<f32> = (0..17 * nch).map(|i| 0.9 + 0.001 * i as f32).collect();
                    let k_out: Vec<f32> = if reciprocal {
                        k_in.clone()
                    } else {
                        (0..17 * nch).map(|i| 1.2 - 0.002 * i as f32).collect()
                    };
                    let cal = Calibration::new(k_in, Some(k_out), nch, 0.99).unwrap();
                    let g = t.grid().clone().with_calibration(cal.clone()).unwrap();
                    Some((Kernel::new(&g).expect("a kernel"), cal))
                };
                let mut r = Pcg32::new(7 + nch as u64);
                let (mut a, mut b) = (vec![0f32; nch], vec![0f32; nch]);
                for _ in 0..20_000 {
                    let (wi, wo) = random_pair(&mut r);
                    let Some(v) = k.vars(wi, wo) else { continue };
                    if let Some((kc, cal)) = &calibrated {
                        kc.eval(wi, wo, &mut a, &packed);
                        kc.blend::<0>(v, &mut b, &packed);
                        let cos = [wi.z as f32, wo.z as f32];
                        project_f32(quantity, Some(cal), cos, &mut b);
                        assert_eq!(a, b, "{nch} channels, calibrated eval: {wi} {wo}");
                    }
                    for (values, exact) in [(&packed, false), (&exact, true)] {
                        k.blend::<0>(v, &mut b, values);
                        // The projection (quantity and clamp) four at a time, too.
                        let cos = [wi.z as f32, wo.z as f32];
                        let (mut p, mut q) = (b.clone(), b.clone());
                        project_f32(quantity, None, cos, &mut p);
                        project_f32_lanes(quantity, None, cos, &mut q);
                        assert_eq!(p, q, "{nch} channels, projection: {wi} {wo}");
                        #[cfg(target_arch = "x86_64")]
                        {
                            if exact {
                                k.blend_lanes::<false, true>(v, &mut a, values);
                                assert_eq!(a, b, "{nch} channels, exact: {wi} {wo}");
                                continue;
                            }
                            k.blend_lanes::<false, false>(v, &mut a, values);
                            assert_eq!(a, b, "{nch} channels, integer expansion: {wi} {wo}");
                            if has_f16c() {
                                // SAFETY: the CPU has F16C.
                                unsafe { k.blend_lanes_f16c(v, &mut a, values) };
                                assert_eq!(a, b, "{nch} channels, F16C: {wi} {wo}");
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn fixed_mappings_are_resampled_without_a_cut_and_agree_with_the_general_lookup() {
        use crate::table::grid::Grid;
        use crate::table::presets::Preset;
        let src = ModelSpec::parse(r#"{"model": "cook_torrance", "m": 0.3}"#)
            .unwrap()
            .build(&Channels::Rgb)
            .unwrap();
        for reciprocal in [false, true] {
            let sym = Symmetry {
                isotropic: true,
                reciprocal,
                bilateral: true,
            };
            // The MERL-size grid of `--grid 90x1x90x180 --param halfdiff` (sqrt θh, uniform θd)
            // and the small preset's (sqrt θh, cos θd).
            let merl = Grid::with_sizes(
                crate::table::Param::HalfDiff,
                [90, 1, 90, 180],
                [Mapping::Sqrt, Mapping::Uniform],
                Channels::Rgb,
                sym,
            )
            .unwrap();
            let preset = Preset::Small.grid(None, sym, Channels::Rgb).unwrap();
            assert_eq!(preset.axes()[2].mapping, Mapping::Cos);
            let k = Kernel::new(&merl).expect("sqrt/uniform axes are resampled");
            // Exact values, also beyond L2 (1.1 M values here).
            assert!(k.resampled() && k.exact_values());
            let kp = Kernel::new(&preset).expect("sqrt/cos axes are resampled");
            assert!(kp.resampled() && kp.exact_values());
            for (grid, k) in [(&merl, &k), (&preset, &kp)] {
                // θh read as (1 − cos θh)^¼, in which sqrt θh is smooth up to 90°: no cut.
                assert_eq!(k.h_var(), WarpVar::QuarterPower);
                assert!(!k.has_cut(), "{:?}", k.cut.to_array());
                let (t, _) = bake(src.as_ref(), grid, &BakeOptions::default()).unwrap();
                let general = Lookup::new(t.grid());
                let packed = Packed::for_kernel(k, t.values());
                let tb = TabulatedBrdf::from_table(t.clone());
                let peak = t.values().iter().fold(0f32, |m, &x| m.max(x));
                let (mut a, mut b, mut c) = ([0f32; 3], [0f32; 3], [0f32; 3]);
                let mut worst = 0f32;
                let mut r = Pcg32::new(8);
                for i in 0..60_000 {
                    let (mut wi, mut wo) = random_pair(&mut r);
                    if i % 10 == 0 {
                        // Near-grazing opposite pairs: θh near 90°, where v_h = √sin θh
                        // needed a cut.
                        wi = DVec3::new(0.999, 0.0, 0.0447).normalize();
                        wo = DVec3::new(-0.9, -0.4, 0.02 + 0.01 * r.next_f64()).normalize();
                    }
                    general.eval(Interp::Linear, wi, wo, &mut b, |i| t.chunk(i));
                    tb.eval(wi, wo, &mut c);
                    assert!(k.eval(wi, wo, &mut a, &packed), "no pair leaves the kernel");
                    assert_eq!(a, c, "TabulatedBrdf uses the kernel");
                    if !k.exact_values() {
                        // Without F16C (the integer expansion) exactly the same.
                        let mut soft = [0f32; 3];
                        assert!(k.rgb::<false, false, true>(wi, wo, &mut soft, &packed));
                        assert_eq!(a, soft, "{wi} {wo}");
                    }
                    for ch in 0..3 {
                        // The same nodes; the kernel's f16 codes (≤ 2^-11 of each value, so of
                        // the blend), f32 variables and knot lines (≤ 1e-4 node units from the
                        // mapping) against the general lookup's f32 values and f64
                        // coordinates.
                        let e = (a[ch] - b[ch]).abs() / (b[ch].abs() * 1e-3 + peak * 1e-5);
                        worst = worst.max(e);
                    }
                }
                assert!(worst <= 1.0, "worst scaled difference {worst}");
            }
        }
    }
}
