//! Adaptive grids: warped `halfdiff` axes fitted to a source's own variation.
//!
//! A measured material is sampled once on a fine tensor in the warp variables (θh, θd, φd; see
//! [`super::warp`]). For each axis the second differences along it, squared, weighted by the
//! accuracy metric's measure (cos θi cos θo squared, the halfdiff Jacobian 4 cos θd sin θh sin θd
//! and dθ/dv, both directions within [`AdaptiveOptions::cap_deg`]) and summed over the other two
//! axes give the error density e(v) that linear interpolation on that axis leaves; the L2-optimal
//! node density of a piecewise-linear interpolant is ∝ e^{1/5} (a cell of width h contributes
//! ∝ h⁵ e). That density, blended with a uniform floor, becomes the axis's [`Warp`].
//!
//! The result is an isotropic, bilaterally symmetric `halfdiff` grid whose three axes are warped:
//! θh with [`Nodes::Edges`] (θh = 0, the peak, is a node), θd with [`Nodes::Centers`] (as the
//! presets: no node on θd = 90°, where both directions graze and a measurement's
//! f_r = (f_r cos θo)/cos θo is noise over almost nothing — with a node there a Mitsuba render
//! of `vch_golden_yellow` came out 14% bright), φd with [`Nodes::Edges`] (folded).

use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::table::grid::{Axis, Grid, Mapping, Nodes, Param, Quantity};
use crate::table::symmetry::Symmetry;
use crate::table::warp::{Warp, WarpVar};

/// How [`adaptive_grid`] samples the source and shapes its warps.
#[derive(Debug, Clone, PartialEq)]
pub struct AdaptiveOptions {
    /// Nodes of the θh, θd and stored φd axes (φd over [0, π], or [0, π/2] with reciprocity).
    pub nodes: [usize; 3],
    /// Fine samples per axis (θh, θd, φd) of the variation estimate.
    pub fine: [usize; 3],
    /// Knots of each warp.
    pub knots: usize,
    /// Weight of the uniform density blended into each warp (0, 1].
    pub floor: f64,
    /// Directions beyond this angle from the normal do not count (degrees).
    pub cap_deg: f64,
    /// What the grid's values are: the warps follow the variation of that quantity.
    pub quantity: Quantity,
    /// θh's warp variable: [`WarpVar::SqrtSine`] (the default), or [`WarpVar::QuarterPower`],
    /// whose finite slope at 90° lets the warp place nodes up to the horizon (what a bake uses
    /// for every table judged over the whole hemisphere: all but a measurement's own f_r).
    pub h_var: WarpVar,
}

impl Default for AdaptiveOptions {
    fn default() -> Self {
        AdaptiveOptions {
            nodes: DEFAULT_NODES,
            fine: [256, 96, 64],
            knots: 128,
            floor: 0.15,
            cap_deg: 85.0,
            quantity: Quantity::Fr,
            h_var: WarpVar::SqrtSine,
        }
    }
}

/// The node counts (θh, θd, stored φd) of an adaptive grid asked for without counts or an
/// error target (RGL files' default bakes search the counts: [`crate::table::target`]): 1.8 MB
/// of f32 RGB, a third to a half of an RGL file on disk, within 1 % of every shipped RGL file
/// on average (BENCHMARKS.md, "Measured materials").
pub const DEFAULT_NODES: [usize; 3] = [128, 48, 25];

/// The warp variables of the three axes, θh's as `opts` chooses.
fn vars(opts: &AdaptiveOptions) -> [WarpVar; 3] {
    [opts.h_var, WarpVar::HalfPower, WarpVar::PseudoAngle]
}

/// An adaptive grid for `src` (isotropic; `symmetry` must be isotropic and bilateral, and may
/// be reciprocal): θh, θd and φd warped by the source's own variation (see the module docs).
pub fn adaptive_grid(src: &dyn Brdf, symmetry: Symmetry, opts: &AdaptiveOptions) -> Result<Grid> {
    adaptive_grid_with(src, symmetry, opts, &crate::progress::Silent)
}

/// [`adaptive_grid`], asking `progress` to stop while the warps are fitted
/// ([`fit_warps_with`]).
pub fn adaptive_grid_with(
    src: &dyn Brdf,
    symmetry: Symmetry,
    opts: &AdaptiveOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<Grid> {
    if !(symmetry.isotropic && symmetry.bilateral) {
        return Err(Error::arg(
            "grid",
            format!("an adaptive grid needs an isotropic, bilateral source (it is {symmetry})"),
        ));
    }
    let [nh, nd, np] = opts.nodes;
    if nh < 2 || nd < 2 || np < 2 || opts.fine.iter().any(|&m| m < 4) {
        return Err(Error::arg(
            "grid",
            "an adaptive grid needs at least 2 nodes and 4 fine samples per axis",
        ));
    }
    within_memory(opts.nodes, src.channels().len())?;
    let warps = fit_warps_with(src, phi_hi(symmetry), opts, progress)?;
    grid_with_warps(src.channels().clone(), symmetry, opts.nodes, warps)?
        .with_quantity(opts.quantity)
}

/// Refuses node counts whose table could not be built in memory, as every adaptive table is
/// ([`MAX_IN_MEMORY_VALUES`](crate::table::fill::MAX_IN_MEMORY_VALUES)), before the warps are
/// fitted: `adaptive:10000000x8x8` (1.9 G values) aborted the process when its allocation
/// failed, and a count near `usize::MAX` grew until the system killed it.
fn within_memory(nodes: [usize; 3], channels: usize) -> Result<()> {
    let values = nodes.iter().try_fold(channels, |n, &k| n.checked_mul(k));
    match values {
        Some(v) if v <= crate::table::fill::MAX_IN_MEMORY_VALUES => Ok(()),
        Some(v) => Err(crate::table::fill::too_large(v)),
        None => Err(crate::table::fill::too_large(usize::MAX)),
    }
}

/// The end of the stored φd axis: π, or π/2 with reciprocity.
pub fn phi_hi(symmetry: Symmetry) -> f64 {
    if symmetry.reciprocal { FRAC_PI_2 } else { PI }
}

/// The adaptive grid of `nodes` (θh, θd, stored φd) on already fitted `warps` (from
/// [`fit_warps`] with [`phi_hi`] of `symmetry`): the warps do not depend on the node counts, so
/// grids of several sizes share one fit.
pub fn grid_with_warps(
    channels: crate::spectrum::Channels,
    symmetry: Symmetry,
    nodes: [usize; 3],
    warps: [Warp; 3],
) -> Result<Grid> {
    if !(symmetry.isotropic && symmetry.bilateral) {
        return Err(Error::arg(
            "grid",
            format!("an adaptive grid needs an isotropic, bilateral source (it is {symmetry})"),
        ));
    }
    let [nh, nd, np] = nodes;
    if nh < 2 || nd < 2 || np < 2 {
        return Err(Error::arg(
            "grid",
            "an adaptive grid needs at least 2 nodes per axis",
        ));
    }
    within_memory(nodes, channels.len())?;
    let [wh, wd, wp] = warps;
    // Full φd size: the stored np nodes over [0, hi] mirrored over [0, 2π).
    let full_phi = if symmetry.reciprocal {
        (np - 1) * 4
    } else {
        (np - 1) * 2
    };
    Grid::new(
        Param::HalfDiff,
        [
            Axis::theta(nh, Mapping::Warp(wh), Nodes::Edges),
            Axis::phi(full_phi),
            Axis::theta(nd, Mapping::Warp(wd), Nodes::Centers),
            Axis {
                size: full_phi,
                mapping: Mapping::Warp(wp),
                nodes: Nodes::Edges,
            },
        ],
        channels,
        symmetry,
    )
}

/// The three warps (θh, θd, φd over [0, `phi_hi`]) of `src`.
pub fn fit_warps(src: &dyn Brdf, phi_hi: f64, opts: &AdaptiveOptions) -> Result<[Warp; 3]> {
    fit_warps_with(src, phi_hi, opts, &crate::progress::Silent)
}

/// [`fit_warps`], asking `progress` to stop before each θh row of the fine tensor
/// ([`crate::progress::Progress::cancelled`]: [`crate::Error::Cancelled`]).
pub fn fit_warps_with(
    src: &dyn Brdf,
    phi_hi: f64,
    opts: &AdaptiveOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<[Warp; 3]> {
    let [mh, md, mp] = opts.fine;
    let c = src.channels().len();
    let his = [FRAC_PI_2, FRAC_PI_2, phi_hi];
    // Sample v at cell centres of the fine grids: f[((ih·md + id)·mp + ip)·c + k].
    let v = |a: usize, i: usize| (i as f64 + 0.5) / opts.fine[a] as f64;
    let vars = vars(opts);
    let ang = |a: usize, i: usize| vars[a].angle_of(v(a, i), his[a]);
    let cap = opts.cap_deg.to_radians().cos();
    let quantity = opts.quantity;
    let project = quantity != Quantity::Fr;
    let row = md * mp * c;
    let mut f = vec![0f32; mh * row];
    let mut w = vec![0f64; mh * md * mp];
    crate::par::install(|| {
        f.par_chunks_mut(row)
            .zip(w.par_chunks_mut(md * mp))
            .enumerate()
            .try_for_each(|(ih, (fr, wr))| {
                crate::progress::check(progress)?;
                let th = ang(0, ih);
                for id in 0..md {
                    let td = ang(1, id);
                    for ip in 0..mp {
                        let pd = ang(2, ip);
                        let (wi, wo) = crate::table::pair_of(Param::HalfDiff, [th, 0.0, td, pd]);
                        let o = id * mp + ip;
                        let out = &mut fr[o * c..(o + 1) * c];
                        src.eval(wi, wo, out);
                        if project {
                            for x in out.iter_mut() {
                                *x = (*x as f64 * quantity.factor(wi.z, wo.z)) as f32;
                            }
                        }
                        // Unlifted directions decide the cap (lifted ones sit at the horizon).
                        let (ri, ro) = crate::geometry::from_half_diff(crate::geometry::HalfDiff {
                            theta_h: th,
                            phi_h: 0.0,
                            theta_d: td,
                            phi_d: pd,
                        });
                        // The metric's weight (cos θi cos θo)², divided by what the quantity
                        // holds already.
                        let cc2 = (ri.z * ro.z).powi(2) / quantity.factor(ri.z, ro.z).powi(2);
                        wr[o] = if ri.z >= cap && ro.z >= cap && ri.z > 0.0 && ro.z > 0.0 {
                            cc2 * 4.0 * td.cos() * th.sin() * td.sin()
                        } else {
                            0.0
                        };
                    }
                }
                Ok(())
            })
    })?;
    for x in f.iter_mut() {
        if !x.is_finite() || *x < 0.0 {
            // Unmeasured (negative) or invalid: no variation from it.
            *x = 0.0;
        }
    }
    let stride = [md * mp, mp, 1];
    let mut warps = Vec::with_capacity(3);
    for a in 0..3 {
        let m = opts.fine[a];
        let mut e = vec![0f64; m];
        // dθ/dv of this axis at each fine centre (the measure in v).
        let dxdv: Vec<f64> = (0..m)
            .map(|i| {
                let h = 0.25 / m as f64;
                let (v0, v1) = ((v(a, i) - h).max(0.0), (v(a, i) + h).min(1.0));
                (vars[a].angle_of(v1, his[a]) - vars[a].angle_of(v0, his[a])) / (v1 - v0)
            })
            .collect();
        for ih in 0..mh {
            for id in 0..md {
                for ip in 0..mp {
                    let idx = [ih, id, ip];
                    let i = idx[a];
                    if i == 0 || i + 1 == m {
                        continue;
                    }
                    let p = (ih * md + id) * mp + ip;
                    let (lo, hi) = (p - stride[a], p + stride[a]);
                    let mut d2 = 0.0;
                    for k in 0..c {
                        let dd =
                            f[lo * c + k] as f64 - 2.0 * f[p * c + k] as f64 + f[hi * c + k] as f64;
                        d2 += dd * dd;
                    }
                    e[i] += d2 * w[p] * dxdv[i];
                }
            }
        }
        // Ends: copy the neighbours (no second difference there).
        e[0] = e[1];
        e[m - 1] = e[m - 2];
        let density: Vec<f64> = e.iter().map(|&x| x.max(0.0).powf(0.2)).collect();
        warps.push(Warp::from_density(
            vars[a], &density, opts.knots, opts.floor,
        )?);
    }
    let [a, b, c] = <[Warp; 3]>::try_from(warps).expect("three warps");
    Ok([a, b, c])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::ModelSpec;
    use crate::spectrum::Channels;

    fn model(spec: &str) -> Box<dyn Brdf + Send + Sync> {
        ModelSpec::parse(spec)
            .unwrap()
            .build(&Channels::Rgb)
            .unwrap()
    }

    #[test]
    fn a_sharp_lobe_pulls_theta_h_nodes_to_the_peak() {
        let ggx = model(r#"{"model": "ggx", "alpha": 0.02}"#);
        let sym = Symmetry {
            isotropic: true,
            reciprocal: true,
            bilateral: true,
        };
        let opts = AdaptiveOptions {
            nodes: [64, 48, 25],
            ..Default::default()
        };
        let g = adaptive_grid(ggx.as_ref(), sym, &opts).unwrap();
        let th = &g.stored_axes()[0];
        // Half of the 64 θh nodes within a few lobe widths of the peak (α = 0.02 ≈ 1.1°), the
        // first on it.
        assert_eq!(th.node(0), 0.0);
        assert!(
            th.node(32) < 6f64.to_radians(),
            "{}",
            th.node(32).to_degrees()
        );
        // Nodes increase strictly; θd's stop short of its horizon (cell centres).
        assert!((1..64).all(|i| th.node(i) > th.node(i - 1)));
        let td = &g.stored_axes()[2];
        assert!(td.node(td.size - 1) < FRAC_PI_2 && td.node(0) > 0.0);
        // A Lambertian source has no variation: the warps are the identity in v.
        let lam = model(r#"{"model": "lambert", "kd": 0.5}"#);
        for h_var in [WarpVar::SqrtSine, WarpVar::QuarterPower] {
            let o = AdaptiveOptions {
                h_var,
                ..opts.clone()
            };
            let g = adaptive_grid(lam.as_ref(), sym, &o).unwrap();
            let th = &g.stored_axes()[0];
            let v = h_var.of_angle(th.node(16), FRAC_PI_2);
            assert!((v - 16.0 / 63.0).abs() < 1e-5, "{h_var:?} {v}");
        }
    }

    #[test]
    fn needs_bilateral_isotropy() {
        let lam = model(r#"{"model": "lambert", "kd": 0.5}"#);
        let sym = Symmetry {
            isotropic: true,
            reciprocal: false,
            bilateral: false,
        };
        assert!(adaptive_grid(lam.as_ref(), sym, &AdaptiveOptions::default()).is_err());
    }
}
