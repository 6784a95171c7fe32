//! Importance sampling for tables (and any BRDF that is cheap to evaluate): conditional 2D
//! warps of f_r·cos θi over the half vector, in the manner of the RGL format's own warps.
//!
//! A [`TableSampler`] draws `wi` given `wo`. [`TabulatedBrdf`](super::TabulatedBrdf) uses it for
//! `sample` and `pdf`, and so do the native RGL reader
//! ([`RglBrdf`](crate::measured::RglBrdf)), whose file's own warps are conditioned on the other
//! direction, and the MERL reader ([`MerlBrdf`](crate::measured::MerlBrdf)), whose format has
//! none.
//!
//! # Design
//!
//! - **Domain: the half vector.** `wi` is drawn as the mirror image of `wo` about a half vector
//!   h, wi = 2 (wo·h) h − wo (dωi = 4 (wo·h) dωh). Reflectance concentrates around h = n (the
//!   specular peak) for every view, so the distributions of neighbouring views look alike and
//!   interpolate well, and one fixed, pole-dense parameterization resolves sharp peaks: the unit
//!   square (s, y) maps to θh = (π/2)(0.02 s + 0.98 s²) (nearly the RGL format's u(θ) = √(2θ/π),
//!   but with a Jacobian that vanishes at the pole as the bilinear density does, so the density
//!   of `wi` stays finite at the mirror direction) and φh = 2π y − π (relative to φo for
//!   isotropic sources, absolute otherwise).
//! - **Per conditioning node** (a view `wo`): the target density on the square,
//!   g(s, y) = f_r·cos θi · 4 (wo·h) · sin θh · dθh/ds · 2π (f_r the channel mean), sampled at
//!   `theta_h` × `phi_h` nodes and interpolated bilinearly — the density of the RGL format's
//!   `Marginal2D` (`table::warp2d`), drawn exactly in constant time with alias tables
//!   (`table::alias2d`: no search, no quadratic).
//! - **Floor**: the nodes whose mirror image lies above the horizon also share `floor` × the
//!   node's mass, and every node a tenth of that, so the density is positive wherever f_r may
//!   be (a lobe narrower than the nodes, cells across the horizon) and the estimate unbiased.
//!   Its share of the samples lands where f_r cos θi may be near 0: it costs up to about
//!   √(1.1 floor) in the coefficient of variation of the weights (0.074 at the default 0.005,
//!   far less where the floor overlaps the lobe).
//! - **Fold at the horizon**: a draw whose mirror image falls below the horizon is reflected
//!   above it (z → −z) rather than refused, so the mass that bilinear interpolation puts across
//!   the horizon (cells with valid and invalid corners, where f_r cos θi is cut off) is not
//!   wasted; the density of `wi` is then the sum over both preimages, h(wi) and h(wi mirrored
//!   below the horizon) — one more density lookup per sample and per `pdf`. (Giving invalid
//!   nodes their neighbours' values instead was tried: it put mass where f_r cos θi vanishes at
//!   the horizon and doubled the CV of diffuse files.)
//! - **Conditioning nodes**: `theta_o` nodes uniform in t = sqrt(1 − cos θo) ∈ [0, 1] (within
//!   10 % of uniform in θo; needs no `acos`); anisotropic sources also `phi_o` periodic nodes
//!   over φo. Isotropic sources rotate a query into the nodes' frame (φo = 0) by vector algebra.
//!   Between nodes the density is interpolated linearly (bilinearly for anisotropic sources),
//!   as the RGL format does over (φi, θi): the result is again a normalized distribution — the
//!   mixture of the neighbouring nodes' — that is sampled exactly (one node chosen at random by
//!   its weight, then drawn from), so [`TableSampler::pdf`] is the density of
//!   [`TableSampler::sample`] for every `wo`, not only at the nodes.
//! - **Cost**: a sample is a choice of node, two alias-table draws and a square root, two
//!   `sin_cos` (polynomial, `fastmath`), a reflection, the density of the other preimage (two
//!   `fastmath::atan2` and a bilinear lookup) and one evaluation of the source for the weight;
//!   it never allocates. (Drawing by two binary searches over CDFs interpolated
//!   between nodes and two quadratics, as RGL's `Marginal2D` does, cost 283 ns per sample
//!   of a measured table where this costs 184; `pdf` 125 → 89 ns.)
//!
//! # Resolution and memory
//!
//! Defaults ([`SamplingResolution::default`]): isotropic 64 θh × 64 φh nodes, 32 θo nodes
//! (≈ 2 × 4 bytes per node and conditioning node: a density and an alias entry → 1.06 MB);
//! anisotropic
//! ([`SamplingResolution::anisotropic`]) 48 × 48 nodes, 20 θo × 16 φo (6.0 MB). Per source
//! ([`TableSampler::for_source`]): twice the θh nodes for a peak at normal incidence too sharp
//! for them (`table::pole`), half again the views and φh nodes (2.4 MB) where the weights' CV
//! predicted from the density between the grazing views misses a bar (`table::views`). Building
//! evaluates the source once per node (131 k evaluations isotropic, 737 k anisotropic); it runs
//! on the calling thread (no rayon: a lazy build inside `OnceLock` must not re-enter itself
//! through rayon's work stealing).

use glam::{DVec2, DVec3};
use std::f64::consts::TAU;

use super::alias2d::AliasWarp;
pub use super::resolution::SamplingResolution;
use super::warp2d::Corners;
use crate::brdf::{Brdf, BrdfSample};
use crate::fastmath;
use crate::geometry::{self, mirror_z};

mod build;
mod half_map;
mod nodes;

pub use build::{SHARP_POLE_CELLS, SHARP_POLE_SHARE};
pub use half_map::HALF_MAP_LINEAR;
use half_map::{POLE_S, half_jacobian, half_of, square_of, theta_of_s};
pub use nodes::{Adjoint, AliasTables, SamplingNodes};

/// Conditional half-vector warps of f_r·cos θi (see the module docs).
#[derive(Debug, Clone)]
pub struct TableSampler {
    nt: usize,
    np: usize,
    isotropic: bool,
    res: SamplingResolution,
    warp: AliasWarp,
}

impl TableSampler {
    /// Rotation (cos φo, sin φo) into the nodes' frame (isotropic) or identity.
    #[inline]
    fn frame(&self, wo: DVec3) -> (f64, f64) {
        if !self.isotropic {
            return (1.0, 0.0);
        }
        let r2 = wo.x * wo.x + wo.y * wo.y;
        if r2 > 1e-300 {
            let inv = 1.0 / r2.sqrt();
            (wo.x * inv, wo.y * inv)
        } else {
            (1.0, 0.0)
        }
    }

    /// The conditioning nodes around a unit `wo` and their weights.
    #[inline]
    fn corners(&self, wo: DVec3) -> Corners {
        let (t0, t1, ft) = if self.nt == 1 {
            (0, 0, 0.0)
        } else {
            let t = (1.0 - wo.z).max(0.0).sqrt();
            let st = (t * (self.nt - 1) as f64).clamp(0.0, (self.nt - 1) as f64);
            let t0 = (st as usize).min(self.nt - 2);
            (t0, t0 + 1, st - t0 as f64)
        };
        if self.np == 1 {
            return Corners {
                slice: [t0, t1, t0, t1],
                w: [1.0 - ft, ft, 0.0, 0.0],
            };
        }
        let mut phi = fastmath::atan2(wo.y, wo.x);
        if phi < 0.0 {
            phi += TAU;
        }
        let sp = phi / TAU * self.np as f64;
        let p0 = (sp as usize).min(self.np - 1);
        let p1 = (p0 + 1) % self.np;
        let fp = (sp - p0 as f64).clamp(0.0, 1.0);
        let np = self.np;
        Corners {
            slice: [t0 * np + p0, t0 * np + p1, t1 * np + p0, t1 * np + p1],
            w: [
                (1.0 - ft) * (1.0 - fp),
                (1.0 - ft) * fp,
                ft * (1.0 - fp),
                ft * fp,
            ],
        }
    }

    /// Density on the unit square at `u` for the view whose corners are `k`.
    #[inline]
    fn square_pdf(&self, u: [f64; 2], k: &Corners) -> f64 {
        self.warp.eval(u, k)
    }

    /// The density (solid angle) with which [`TableSampler::sample`] draws `wi` given `wo`;
    /// 0 when either is invalid or at/below the horizon.
    pub fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let (Some(wi), Some(wo)) = (geometry::unit(wi), geometry::unit(wo)) else {
            return 0.0;
        };
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let (c, s) = self.frame(wo);
        let rot = |v: DVec3| DVec3::new(c * v.x + s * v.y, -s * v.x + c * v.y, v.z);
        let (wil, wol) = (rot(wi), rot(wo));
        let k = self.corners(wo);
        let pdf = self.density_at(wil, wol, &k) + self.density_at(mirror_z(wil), wol, &k);
        if pdf.is_finite() && pdf > 0.0 {
            pdf
        } else {
            0.0
        }
    }

    /// The density of drawing the half vector of (`wil`, `wol`) (nodes' frame; `wil` may be
    /// below the horizon), per solid angle of `wil`; 0 when the half vector is below the
    /// horizon or undefined.
    #[inline]
    fn density_at(&self, wil: DVec3, wol: DVec3, k: &Corners) -> f64 {
        // h unnormalized: θh and φh are ratios of its components, sin θh and wo·ĥ need 1/|h|.
        let h = wil + wol;
        let rho2 = h.x * h.x + h.y * h.y;
        let l2 = rho2 + h.z * h.z;
        if !(h.z > 0.0 && l2 > 0.0 && l2.is_finite()) {
            return 0.0;
        }
        let l = l2.sqrt();
        let inv_l = 1.0 / l;
        // wo·ĥ = |wi + wo| / 2 for unit wi, wo: as `wol.dot(h)` it cancelled where ĥ is nearly
        // perpendicular to wo's azimuth at a grazing view (wo·ĥ ~ 1e-8 from terms ~ 0.1), and
        // the density of a direction moved by rounding jumped by orders of magnitude.
        let dot = 0.5 * l;
        if !(dot > 0.0) {
            return 0.0;
        }
        let [s, y] = square_of(h);
        let d = if s >= POLE_S {
            self.square_pdf([s, y], k) / (4.0 * dot * half_jacobian(s, rho2.sqrt() * inv_l))
        } else {
            self.pole_density(dot, k)
        };
        if d.is_finite() { d } else { 0.0 }
    }

    /// The density of a `wi` whose half vector lies within s < [`POLE_S`] of the pole: the
    /// limit at the pole along y = ½ (φh = φo), read at s = `POLE_S`. The limit depends on the
    /// direction of approach (by ~0.1 %); one fixed y makes a draw there and `pdf` of the
    /// drawn direction agree, whatever azimuth rounding gives the recomputed half vector.
    #[cold]
    fn pole_density(&self, dot: f64, k: &Corners) -> f64 {
        let sin_th = theta_of_s(POLE_S).sin();
        self.square_pdf([POLE_S, 0.5], k) / (4.0 * dot * half_jacobian(POLE_S, sin_th))
    }

    /// Draws `wi` for `wo` from `u` ∈ [0,1)²; evaluates `brdf` for the weight f_r cos θi / pdf.
    pub fn sample(
        &self,
        brdf: &dyn Brdf,
        wo: DVec3,
        u: DVec2,
        weight: &mut [f32],
    ) -> Option<BrdfSample> {
        let ch = brdf.channels().len();
        let d = self.draw_and(wo, u, |wi, wo| brdf.eval(wi, wo, &mut weight[..ch]))?;
        d.weigh(&mut weight[..ch]);
        Some(BrdfSample {
            wi: d.wi,
            pdf: d.pdf,
            delta: false,
        })
    }

    /// The direction and density of [`TableSampler::sample`] without the weight's evaluation
    /// (for callers that evaluate many draws at once: [`Draw::weigh`] finishes each).
    pub fn draw(&self, wo: DVec3, u: DVec2) -> Option<Draw> {
        self.draw_and(wo, u, |_, _| {})
    }

    /// [`TableSampler::draw`], calling `eval(wi, wo)` as soon as the direction is known (before
    /// the folded preimage's density, whose chain then runs beside the evaluation's instead of
    /// ahead of it in program order). `eval` may be called for a draw that then returns `None`
    /// (a density that is not positive and finite).
    #[inline]
    pub fn draw_and(&self, wo: DVec3, u: DVec2, eval: impl FnOnce(DVec3, DVec3)) -> Option<Draw> {
        let wo = geometry::unit(wo)?;
        if wo.z <= 0.0 || !geometry::in_unit_square(u) {
            return None;
        }
        let (c, s) = self.frame(wo);
        let wol = DVec3::new(c * wo.x + s * wo.y, -s * wo.x + c * wo.y, wo.z);
        let k = self.corners(wo);
        let (p, pdf_square) = self.warp.sample([u.x, u.y], &k);
        let (h, sin_th) = half_of(p);
        let dot = wol.dot(h);
        if dot <= 0.0 {
            return None;
        }
        let drawn = 2.0 * dot * h - wol;
        let here = if p[0] >= POLE_S {
            pdf_square / (4.0 * dot * half_jacobian(p[0], sin_th))
        } else {
            self.pole_density(dot, &k)
        };
        // Folded at the horizon: the other preimage of `wil` is its mirror image below it.
        // The mirror image of `drawn` below the horizon has its half vector (∝ wo + mirror)
        // above the horizon only when drawn.z < wo.z; otherwise its density is 0.
        // `other`: where the other preimage's density is to be read, if anywhere.
        let (wil, other) = if drawn.z > 0.0 {
            (drawn, (drawn.z < wol.z).then(|| mirror_z(drawn)))
        } else {
            // The other preimage is `wil` itself, whose half vector is always above.
            let wil = mirror_z(drawn);
            (wil, Some(wil))
        };
        if !(wil.z > 0.0) {
            return None;
        }
        // Back from the nodes' frame. Unit to rounding (h and wo are unit, the rotation is
        // orthogonal): within what lookups take as unit, so no normalization.
        let wi = DVec3::new(c * wil.x - s * wil.y, s * wil.x + c * wil.y, wil.z);
        eval(wi, wo);
        let pdf = here + other.map_or(0.0, |p| self.density_at(p, wol, &k));
        if !(pdf > 0.0) || !pdf.is_finite() {
            return None;
        }
        Some(Draw { wi, wo, pdf })
    }
}

/// A direction drawn by [`TableSampler::draw`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Draw {
    /// The drawn incident direction (unit).
    pub wi: DVec3,
    /// The view it was drawn for, unit: what the weight's evaluation takes.
    pub wo: DVec3,
    /// The density of `wi` (solid angle).
    pub pdf: f64,
}

impl Draw {
    /// Turns f_r(`wi`, `wo`) in `f` into the weight f_r cos θi / pdf (in f64, rounded once).
    #[inline]
    pub fn weigh(&self, f: &mut [f32]) {
        let k = self.wi.z / self.pdf;
        for w in f {
            *w = (*w as f64 * k) as f32;
        }
    }
}

#[cfg(test)]
mod table_tests;
#[cfg(test)]
mod tests;
