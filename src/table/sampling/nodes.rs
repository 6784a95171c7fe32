//! The densities a [`TableSampler`](super::TableSampler) is built from ([`SamplingNodes`]), one
//! plane per conditioning view, and [`Adjoint`], the source with its directions exchanged.

use glam::DVec3;
use std::f64::consts::TAU;

use super::half_map::{half_jacobian, half_of};
use crate::brdf::Brdf;
use crate::spectrum::MAX_CHANNELS;
use crate::table::alias2d::AliasWarp;
use crate::table::resolution::SamplingResolution;
use crate::table::warp2d::Planes;

/// The densities a [`TableSampler`](super::TableSampler) is built from: g(s, y) at `nx` × `ny` nodes of the unit
/// square (s → θh = (π/2)(0.02 s + 0.98 s²), y → φh = 2π y − π relative to φo for isotropic
/// sources) for each conditioning node, `nt` over t = sqrt(1 − cos θo) ∈ [0, 1] (uniform; one
/// node: t = ½) times `np` over φo ∈ [0, 2π) (periodic; 1 for isotropic sources), the floor
/// included (see the module docs), not normalized.
///
/// Hosts that sample on a device run the same draw on these ([`SamplingNodes::alias`]: the
/// Mitsuba plugin's `brdftab/_alias2d.py`), after the square, the half-vector map and the fold
/// at the horizon of [`TableSampler::sample`](super::TableSampler::sample).
#[derive(Debug, Clone)]
pub struct SamplingNodes {
    /// Nodes over s (the inner axis of `data`).
    pub nx: usize,
    /// Nodes over y.
    pub ny: usize,
    /// Conditioning nodes over t.
    pub nt: usize,
    /// Conditioning nodes over φo.
    pub np: usize,
    /// Conditioned on θo only (the view rotated to φo = 0).
    pub isotropic: bool,
    /// `nt` × `np` planes of `ny` × `nx` densities (t outermost, s innermost).
    pub data: Vec<f32>,
}

/// The constant-time draw of [`TableSampler`](super::TableSampler) as data ([`SamplingNodes::alias`]), for hosts
/// that run it themselves.
///
/// Per slice (conditioning node, `nt` × `np`, t outermost as in [`SamplingNodes::data`]) of
/// `ny` rows × `nx` nodes:
/// - `pdf`: the node densities normalized so that the slice's bilinear interpolant integrates
///   to 1 over its (nx − 1)(ny − 1) cells of unit area (per unit area of the square: times
///   (nx − 1)(ny − 1));
/// - `strips`: 2(ny − 1) alias entries over the half-strips — slot h is strip h / 2, row
///   h / 2 + h % 2, t across the strip from the density 2(1 − t) (even h) or 2t (odd h);
/// - `cells`: per row, nx − 1 alias entries over its cells; within the drawn cell a coin
///   weighted by the two end densities picks 2(1 − f) or 2f.
///
/// An entry e keeps its own slot with probability (e mod 2^(32 − b)) / 2^(32 − b) and otherwise
/// gives slot e >> (32 − b), b = `other_bits`. Slot i of n is drawn by x = u·n, i = ⌊x⌋,
/// f = x − i; the remainder f/keep (kept) or (f − keep)/(1 − keep) is the next step's uniform
/// number. The first number of a draw gives the cell, the coin and f; the second the slice (by
/// the conditioning weights, in corner order), the half-strip and t.
#[derive(Debug, Clone)]
pub struct AliasTables {
    /// Bits of an entry's `other` slot (the top bits).
    pub other_bits: u32,
    /// Normalized node densities, the layout of [`SamplingNodes::data`].
    pub pdf: Vec<f32>,
    /// Per slice, 2(ny − 1) half-strip entries.
    pub strips: Vec<u32>,
    /// Per slice and row, nx − 1 cell entries.
    pub cells: Vec<u32>,
}

impl SamplingNodes {
    /// The node densities of `brdf` (f_r·cos θi, channel mean) at resolution `res`, on the
    /// calling thread (what [`TableSampler::build`](super::TableSampler::build) runs, lazily, inside a `OnceLock`).
    /// `isotropic`: one conditioning node over φo.
    pub fn build(brdf: &dyn Brdf, isotropic: bool, res: &SamplingResolution) -> SamplingNodes {
        Self::build_with(brdf, isotropic, res, false)
    }

    /// [`SamplingNodes::build`] with the conditioning nodes spread over the library's pool
    /// ([`crate::par`]): for hosts that export the nodes (the Mitsuba plugin at scene load).
    pub fn build_par(brdf: &dyn Brdf, isotropic: bool, res: &SamplingResolution) -> SamplingNodes {
        Self::build_with(brdf, isotropic, res, true)
    }

    /// The structure [`TableSampler`](super::TableSampler) draws these densities with: each slice normalized, its
    /// alias tables over half-strips and over each row's cells (see `table::alias2d`). A slice
    /// that does not integrate to a positive finite value (never, for nodes built here: the
    /// floor keeps them positive) makes every slice uniform, as the sampler does.
    pub fn alias(&self) -> AliasTables {
        let planes = |data| Planes {
            nx: self.nx,
            ny: self.ny,
            data,
        };
        let n = self.nt * self.np * self.nx * self.ny;
        let w = AliasWarp::build(planes(self.data.clone()))
            .or_else(|_| AliasWarp::build(planes(vec![1.0; n])))
            .unwrap_or_else(|_| unreachable!("a uniform warp is a density"));
        let (other_bits, pdf, strips, cells) = w.parts();
        AliasTables {
            other_bits,
            pdf: pdf.to_vec(),
            strips: strips.to_vec(),
            cells: cells.to_vec(),
        }
    }

    fn build_with(
        brdf: &dyn Brdf,
        isotropic: bool,
        res: &SamplingResolution,
        par: bool,
    ) -> SamplingNodes {
        use rayon::prelude::*;
        let nx = res.theta_h.max(2);
        let ny = res.phi_h.max(2);
        let nt = res.theta_o.max(1);
        let np = if isotropic { 1 } else { res.phi_o.max(1) };
        let floor = if res.floor > 0.0 && res.floor.is_finite() {
            res.floor
        } else {
            SamplingResolution::default().floor
        };
        let plane = nx * ny;
        let mut data = vec![0.0f32; nt * np * plane];
        let fill = |(slice, d): (usize, &mut [f32])| {
            let (kt, kp) = (slice / np, slice % np);
            let t = if nt == 1 {
                0.5
            } else {
                kt as f64 / (nt - 1) as f64
            };
            // The last node (t = 1) is the horizon, where f_r is 0: take it just above.
            let zo = (1.0 - t * t).max(1e-2);
            let ro = (1.0 - zo * zo).max(0.0).sqrt();
            let (sp, cp) = (TAU * kp as f64 / np as f64).sin_cos();
            node_plane(brdf, DVec3::new(ro * cp, ro * sp, zo), nx, floor, d);
        };
        if par {
            crate::par::install(|| data.par_chunks_mut(plane).enumerate().for_each(fill));
        } else {
            data.chunks_mut(plane).enumerate().for_each(fill);
        }
        SamplingNodes {
            nx,
            ny,
            nt,
            np,
            isotropic,
            data,
        }
    }
}

/// One conditioning node's densities `d` (`nx` columns) for the view `wo`, floor included.
fn node_plane(brdf: &dyn Brdf, wo: DVec3, nx: usize, floor: f64, d: &mut [f32]) {
    let c = brdf.channels().len().clamp(1, MAX_CHANNELS);
    let mut f = [0.0f32; MAX_CHANNELS];
    let (plane, ny) = (d.len(), d.len() / nx);
    let (mut sum, mut valid) = (0.0f64, 0usize);
    for (k, v) in d.iter_mut().enumerate() {
        let u = [
            (k % nx) as f64 / (nx - 1) as f64,
            (k / nx) as f64 / (ny - 1) as f64,
        ];
        let (h, sin_th) = half_of(u);
        let dot = wo.dot(h);
        let wi = 2.0 * dot * h - wo;
        if dot <= 0.0 || wi.z <= 0.0 {
            *v = -1.0; // marks a node whose mirror image is below the horizon
            continue;
        }
        valid += 1;
        brdf.eval(wi, wo, &mut f[..c]);
        let fr = f[..c].iter().map(|&x| x as f64).sum::<f64>() / c as f64;
        let g = fr * wi.z * 4.0 * dot * half_jacobian(u[0], sin_th);
        if g.is_finite() && g > 0.0 {
            *v = g as f32;
            sum += g;
        }
    }
    // A node with nothing measured is uniform on the square. Otherwise the valid nodes share
    // `floor` × the node's mass, and every node `floor` / 10 of it (cells across the horizon).
    let (on_valid, everywhere) = if sum > 0.0 && sum.is_finite() {
        (
            (floor * sum / valid.max(1) as f64) as f32,
            (0.1 * floor * sum / plane as f64) as f32,
        )
    } else {
        (1.0, 1.0)
    };
    for (k, v) in d.iter_mut().enumerate() {
        *v = if k % nx == 0 {
            // The pole (s = 0), where the Jacobian vanishes: no floor, so the density of `wi`
            // stays finite there.
            0.0
        } else if *v < 0.0 {
            everywhere
        } else {
            *v + on_valid + everywhere
        };
    }
}

/// `f_r` with its directions exchanged: A(wi, wo) = f_r(wo, wi). Nodes or a sampler built from
/// it draw `wo` given `wi`, ∝ f_r(wi, wo) cos θo — what a host that conditions on the light
/// direction needs (Mitsuba samples its `wo` given `si.wi`, brdftab's `wi`).
pub struct Adjoint<'a>(pub &'a dyn Brdf);

impl Brdf for Adjoint<'_> {
    fn channels(&self) -> &crate::spectrum::Channels {
        self.0.channels()
    }
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        self.0.eval(wo, wi, out)
    }
    fn flags(&self) -> crate::brdf::Flags {
        self.0.flags()
    }
    fn describe(&self) -> String {
        format!("adjoint of {}", self.0.describe())
    }
}
