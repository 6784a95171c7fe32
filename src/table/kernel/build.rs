//! The kernel made from a grid: which grids it takes (`halfdiff`, isotropic, axes warped or on
//! fixed mappings it resamples), the lane constants it computes once, and what it tells of
//! itself. The lookups that read it are in `mod.rs` and `blend`.

use std::f64::consts::{FRAC_PI_2, PI};

use super::axis::{Axis, fixed_mapping_fits};
use super::{Kernel, KernelAxis, RESAMPLED_MAX_VALUES, x8};
use crate::simd::F4;
use crate::table::grid::{Grid, Mapping, Nodes, Param};
use crate::table::warp::WarpVar;

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
        let x8 = channels <= crate::spectrum::MAX_CHANNELS
            && grid.stored_values() < (i32::MAX as usize) / 2
            && x8::available();
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
            #[cfg(target_arch = "x86_64")]
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
    ///
    /// [`Packed::exact`]: super::Packed::exact
    /// [`Packed::new`]: super::Packed::new
    pub fn exact_values(&self) -> bool {
        self.exact
    }

    /// The kernel's three axes (θh, θd, φd) as [`crate::table::device`] describes them: per knot
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
}

/// Whether the CPU has F16C.
#[cfg(target_arch = "x86_64")]
pub(super) fn has_f16c() -> bool {
    std::is_x86_feature_detected!("f16c")
}
