//! The kernel's axes: per axis the fractional node index as a line in the warp variable on
//! each knot interval ([`Axis`], read once per axis and lookup), built from a warp's knots or
//! by resampling a fixed mapping ([`RESAMPLED_KNOTS`], [`RESAMPLE_TOLERANCE`],
//! [`RESAMPLED_MAX_VALUES`]), and the same lines as a device reads them ([`KernelAxis`]).
//!
//! Why a file of its own: which mappings the kernel takes and how closely its knot lines follow
//! them is decided here, apart from the lookup that reads the lines.

use crate::table::grid::{Mapping, StoredAxis};
use crate::table::warp::{Warp, WarpVar};

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
pub(super) struct Axis {
    /// Interval j (t ∈ [j, j + 1]): s = c + t·d, as `[c, d]`, where s = u·(n − 1) (edges)
    /// or u·n − ½ (centres) at the knots. One eight-byte load per lookup and no t − j.
    pub(super) lines: Box<[[f32; 2]]>,
    /// K as f32.
    pub(super) k: f32,
    /// Number of nodes (≥ 2).
    pub(super) n: usize,
    /// The last knot interval (K − 1).
    pub(super) kmax: u32,
    /// The last lower node (n − 2).
    imax: i32,
}

impl Axis {
    /// `centers`: node i at u = (i + ½)/n, s = u·n − ½; otherwise at u = i/(n − 1).
    pub(super) fn new(w: &Warp, n: usize, centers: bool) -> Axis {
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
    pub(super) fn resampled(ax: &StoredAxis, var: WarpVar, hi: f64) -> Option<(Axis, f32)> {
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

    /// The knot lines of s given at K + 1 knots uniform in v (K ≥ 1: `line` relies on it), for
    /// an axis of `n` nodes.
    fn from_knots(s: &[f64], n: usize) -> Axis {
        assert!(s.len() >= 2, "an axis needs two knots");
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
    pub(super) fn line(&self, j: i32) -> &[f32; 2] {
        let j = (j as u32).min(self.kmax) as usize;
        debug_assert!(j < self.lines.len());
        // SAFETY: `lines` has kmax + 1 ≥ 1 entries (`Axis::from_knots`, the only constructor,
        // sets kmax to their count − 1; neither changes afterwards), and j ≤ kmax. From K + 1
        // ≥ 2 knots: a warp has 2 to 65536 (`Warp::new`, which a table file's warps are read
        // through too), a resampled axis RESAMPLED_KNOTS + 1.
        unsafe { self.lines.get_unchecked(j) }
    }

    /// The lower node and the weight of the upper one at variable `v` ∈ [0, 1] (the scalar
    /// reference of the lane code in [`Kernel::eval_rgb`], the same operations).
    ///
    /// Indices go through i32: a saturating f32 → usize conversion costs about three times as
    /// many instructions, and every value here is in [0, 2^16].
    ///
    /// [`Kernel::eval_rgb`]: super::Kernel::eval_rgb
    #[inline(always)]
    pub(super) fn node(&self, v: f32) -> (usize, f32) {
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
pub(super) fn fixed_mapping_fits(k: usize, m: &Mapping) -> bool {
    match k {
        0 => *m == Mapping::Sqrt,
        2 => matches!(m, Mapping::Uniform | Mapping::Cos),
        _ => *m == Mapping::Uniform,
    }
}

/// One axis of a [`KernelLayout`](crate::table::device::KernelLayout): what a device evaluates of
/// this kernel's axes. Defined here (the kernel writes it), re-exported by [`table::device`].
///
/// [`table::device`]: crate::table::device
#[derive(Debug, Clone, serde::Serialize)]
pub struct KernelAxis {
    /// Per knot interval j (of K = `c.len()`): s = `c[j] + t·d[j]` at t = v·K ∈ \[j, j + 1\].
    pub c: Vec<f32>,
    /// The slopes (see `c`).
    pub d: Vec<f32>,
    /// Number of nodes (≥ 2).
    pub nodes: usize,
    /// Pairs whose variable is at or above the cut take the
    /// [`GridLayout`](crate::table::device::GridLayout) (2: never).
    pub cut: f32,
}
