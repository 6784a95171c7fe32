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
use std::f64::consts::{FRAC_PI_2, PI, TAU};

use super::alias2d::AliasWarp;
pub use super::resolution::SamplingResolution;
use super::warp2d::{Corners, Planes};
use crate::brdf::{Brdf, BrdfSample};
use crate::fastmath;
use crate::geometry::{self, mirror_z};
use crate::spectrum::MAX_CHANNELS;

/// The resolutions a source needs, decided by probing it (see [`TableSampler::for_source`]).
impl SamplingResolution {
    /// The resolution for `brdf` looked up as `isotropic` and `nearest` say: the resolution of
    /// [`TableSampler::for_source`] (which builds a sampler to decide; build that one rather
    /// than call this and build again). What tables, the native readers and `info` use.
    pub fn for_source(brdf: &dyn Brdf, isotropic: bool, nearest: bool) -> Self {
        TableSampler::for_source(brdf, isotropic, nearest).resolution()
    }

    /// Whether more than [`SHARP_POLE_SHARE`] of the normal view's f_r cos θi (in the
    /// sampler's half-vector domain) lies within the first [`SHARP_POLE_CELLS`] θh cells of
    /// `res`: a lobe the bilinear density over those cells cannot follow. GGX α = 0.002 puts
    /// 0.85 of its mass there and samples with a CV of 0.18 on 64 θh nodes, 0.09 on 128;
    /// α = 0.005 0.49 (0.10 → 0.06); α = 0.01 (0.21, CV 0.07), the reciprocal Phong at
    /// n = 1000 (0.05) and every shipped RGL file (at most 0.04) keep 64
    /// (`examples/sampling_cv`).
    pub fn sharp_peak(brdf: &dyn Brdf, res: &SamplingResolution) -> bool {
        Self::pole_share(brdf, res) > SHARP_POLE_SHARE
    }

    /// The share of the normal view's f_r cos θi (in the sampler's half-vector domain) within
    /// the first [`SHARP_POLE_CELLS`] θh cells of `res` (0 for a source that is nowhere
    /// positive there).
    pub fn pole_share(brdf: &dyn Brdf, res: &SamplingResolution) -> f64 {
        super::pole::pole_share(
            brdf,
            res.theta_h.max(2),
            SHARP_POLE_CELLS,
            theta_of_s,
            half_jacobian,
        )
    }
}

/// θh cells of the sampler's map that [`SamplingResolution::sharp_peak`] looks at.
pub const SHARP_POLE_CELLS: usize = 3;

/// Share of the normal view's mass within [`SHARP_POLE_CELLS`] above which a source's peak is
/// sharp ([`SamplingResolution::sharp_peak`]).
pub const SHARP_POLE_SHARE: f64 = 0.3;

/// Conditional half-vector warps of f_r·cos θi (see the module docs).
#[derive(Debug, Clone)]
pub struct TableSampler {
    nt: usize,
    np: usize,
    isotropic: bool,
    res: SamplingResolution,
    warp: AliasWarp,
}

/// Share of the θh map that is linear in s: θh = (π/2)(a s + (1 − a) s²), a = `HALF_MAP_LINEAR`.
/// The quadratic part puts the nodes close together at the pole (the RGL format's u(θ) = √(2θ/π)
/// is the pure quadratic); the linear part keeps dθh/ds > 0 there, so that the Jacobian
/// vanishes like s at the pole, as the bilinear density does — with the pure quadratic it
/// vanishes like s³ and the density of `wi` would be infinite at the mirror direction.
/// 0.02 rather than the 0.1 of sessions 9–26: the first cell narrows from 0.16° to 0.05°, so a
/// sharp peak spreads over more of them — GGX α = 0.002's weights' CV went from 0.85 to 0.18 on
/// 64 θh nodes and cg_sunflower's from 0.045–0.073 to 0.039–0.062 over views 3–75°, GGX
/// α = 0.05 unchanged (0.024–0.036); the outer cells barely change (2.7° → 2.8°).
pub const HALF_MAP_LINEAR: f64 = 0.02;
const LINEAR: f64 = HALF_MAP_LINEAR;

/// θh of the square's first coordinate s.
#[inline]
fn theta_of_s(s: f64) -> f64 {
    FRAC_PI_2 * s * (LINEAR + (1.0 - LINEAR) * s)
}

/// s of θh (inverse of [`theta_of_s`]): the positive root of (1 − a) s² + a s − 2θh/π = 0.
#[inline]
fn s_of_theta(theta: f64) -> f64 {
    let q = theta / FRAC_PI_2;
    // 2q / (a + √(a² + 4(1 − a) q)): the root without cancellation.
    let s = 2.0 * q / (LINEAR + (LINEAR * LINEAR + 4.0 * (1.0 - LINEAR) * q).sqrt());
    s.clamp(0.0, 1.0)
}

/// Below this s the density of `wi` is the pole's (`TableSampler::pole_density`): at the
/// pole (h on the normal, wi the mirror direction of wo) the square's density and the Jacobian
/// both vanish like s, so their quotient is 0/0 there, while its limit along any y is finite
/// and reached to ~1e-9 at this s.
const POLE_S: f64 = 1e-9;

/// |dωi / d(s, y)| / (4 (wo·h)) = sin θh · dθh/ds · dφh/dy.
#[inline]
fn half_jacobian(s: f64, sin_th: f64) -> f64 {
    sin_th * FRAC_PI_2 * (LINEAR + 2.0 * (1.0 - LINEAR) * s) * TAU
}

/// The half vector of square point `u` = (s, y) in the frame of the nodes, with sin θh.
#[inline]
fn half_of(u: [f64; 2]) -> (DVec3, f64) {
    let (st, ct) = fastmath::sin_cos_2pi(theta_of_s(u[0]) * (1.0 / TAU));
    // φh = 2π y − π: (sin, cos) of 2π y, negated.
    let (sp, cp) = fastmath::sin_cos_2pi(u[1]);
    (DVec3::new(-st * cp, -st * sp, ct), st)
}

/// The square point (s, y) of a half vector `h` of any positive length with h.z > 0 (inverse of
/// [`half_of`]): θh and φh are ratios of its components ([`fastmath::atan2`], no
/// normalization).
#[inline]
fn square_of(h: DVec3) -> [f64; 2] {
    let rho = (h.x * h.x + h.y * h.y).sqrt();
    let s = s_of_theta(fastmath::atan2(rho, h.z));
    let y = (fastmath::atan2(h.y, h.x) + PI) * (1.0 / TAU);
    // atan2 ∈ [−π, π]: y ∈ [0, 1], and 1 is 0.
    [s, if y >= 1.0 { y - 1.0 } else { y }]
}

/// The densities a [`TableSampler`] is built from: g(s, y) at `nx` × `ny` nodes of the unit
/// square (s → θh = (π/2)(0.02 s + 0.98 s²), y → φh = 2π y − π relative to φo for isotropic
/// sources) for each conditioning node, `nt` over t = sqrt(1 − cos θo) ∈ [0, 1] (uniform; one
/// node: t = ½) times `np` over φo ∈ [0, 2π) (periodic; 1 for isotropic sources), the floor
/// included (see the module docs), not normalized.
///
/// Hosts that sample on a device run the same draw on these ([`SamplingNodes::alias`]: the
/// Mitsuba plugin's `brdftab/_alias2d.py`), after the square, the half-vector map and the fold
/// at the horizon of [`TableSampler::sample`].
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

/// The constant-time draw of [`TableSampler`] as data ([`SamplingNodes::alias`]), for hosts
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
    /// calling thread (what [`TableSampler::build`] runs, lazily, inside a `OnceLock`).
    /// `isotropic`: one conditioning node over φo.
    pub fn build(brdf: &dyn Brdf, isotropic: bool, res: &SamplingResolution) -> SamplingNodes {
        Self::build_with(brdf, isotropic, res, false)
    }

    /// [`SamplingNodes::build`] with the conditioning nodes spread over the library's pool
    /// ([`crate::par`]): for hosts that export the nodes (the Mitsuba plugin at scene load).
    pub fn build_par(brdf: &dyn Brdf, isotropic: bool, res: &SamplingResolution) -> SamplingNodes {
        Self::build_with(brdf, isotropic, res, true)
    }

    /// The structure [`TableSampler`] draws these densities with: each slice normalized, its
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

impl TableSampler {
    /// Builds the distributions of `brdf` (f_r·cos θi, channel mean). `isotropic`: condition on
    /// θo only and rotate by φo.
    pub fn build(brdf: &dyn Brdf, isotropic: bool, res: &SamplingResolution) -> TableSampler {
        let SamplingNodes {
            nx,
            ny,
            nt,
            np,
            data,
            ..
        } = SamplingNodes::build(brdf, isotropic, res);
        let plane = nx * ny;
        let warp = match AliasWarp::build(Planes { nx, ny, data }) {
            Ok(w) => w,
            // Unreachable (every node is positive), but never panic: fall back to uniform.
            Err(_) => AliasWarp::build(Planes {
                nx,
                ny,
                data: vec![1.0; nt * np * plane],
            })
            .unwrap_or_else(|_| unreachable!("a uniform warp is a density")),
        };
        TableSampler {
            nt,
            np,
            isotropic,
            res: *res,
            warp,
        }
    }

    /// The sampler of `brdf` looked up as `isotropic` and `nearest` say, at the resolution
    /// that source needs: [`SamplingResolution::for_lookup`], with twice the θh nodes for an
    /// isotropic source whose specular peak at normal incidence is too sharp for them
    /// ([`SamplingResolution::sharp_peak`]), and then, for an isotropic source whose
    /// predicted weights miss a bar between the conditioning views
    /// ([`TableSampler::view_excess`] > 1), [`SamplingResolution::finer_views`] when those do
    /// better by a tenth. Costs a build and the prediction (about 150 k evaluations and
    /// densities), twice for a source that gets the finer views. A `cfg(fuzzing)` build (the
    /// fuzz targets) starts from [`SamplingResolution::coarse`] instead: the same decisions on
    /// a few dozen nodes.
    pub fn for_source(brdf: &dyn Brdf, isotropic: bool, nearest: bool) -> TableSampler {
        let mut res = if cfg!(fuzzing) {
            SamplingResolution::coarse()
        } else {
            SamplingResolution::for_lookup(isotropic, nearest)
        };
        if !isotropic {
            return TableSampler::build(brdf, false, &res);
        }
        if SamplingResolution::sharp_peak(brdf, &res) {
            res.theta_h *= 2;
        }
        let base = TableSampler::build(brdf, true, &res);
        let excess = base.view_excess(brdf);
        if excess <= 1.0 {
            return base;
        }
        let finer = TableSampler::build(brdf, true, &res.finer_views());
        if finer.view_excess(brdf) < 0.9 * excess {
            finer
        } else {
            base
        }
    }

    /// The resolution this sampler was built at.
    pub fn resolution(&self) -> SamplingResolution {
        self.res
    }

    /// The coefficient of variation the weights f_r cos θi / pdf of `brdf` (channel mean of
    /// f_r, the source this sampler was built from) have at the view `wo`, computed from the
    /// density (∫ g²/p dωi / (∫ g dωi)² − 1 with g = f_r cos θi) on cells of half the node
    /// spacing of the sampler's own half-vector square rather than drawn (`table::views`).
    pub fn predicted_cv(&self, brdf: &dyn Brdf, wo: DVec3) -> f64 {
        let Some(wo) = geometry::unit(wo).filter(|w| w.z > 0.0) else {
            return 0.0;
        };
        // The rule covers every azimuth of h, so any frame serves.
        let pdf = |wi: DVec3, wo: DVec3| self.pdf(wi, wo);
        let cells = |n: usize| 2 * (n.max(2) - 1);
        super::views::predicted_cv(
            brdf,
            &pdf,
            &Self::half_map(),
            wo,
            cells(self.res.theta_h),
            cells(self.res.phi_h),
        )
    }

    /// The worst over the views between the grazing conditioning nodes (θo 60–85°) of the
    /// predicted CV ([`TableSampler::predicted_cv`]) over 0.95 × its bar (0.10 up to 75°, 0.2
    /// to 85°): above 1, a view between the nodes is expected to miss its bar. 0 for an
    /// anisotropic sampler (not probed).
    pub fn view_excess(&self, brdf: &dyn Brdf) -> f64 {
        if !self.isotropic {
            return 0.0;
        }
        let pdf = |wi: DVec3, wo: DVec3| self.pdf(wi, wo);
        super::views::worst_excess(
            brdf,
            &pdf,
            &Self::half_map(),
            self.res.theta_h,
            self.res.phi_h,
            self.nt,
        )
    }

    fn half_map() -> super::views::HalfMap<'static> {
        super::views::HalfMap {
            theta_of_s: &theta_of_s,
            jacobian: &half_jacobian,
        }
    }

    /// Bytes held by the distributions.
    pub fn memory_bytes(&self) -> usize {
        self.warp.memory_bytes()
    }

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
#[path = "sampling_tests.rs"]
mod table_tests;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    #[test]
    fn half_vector_map_round_trips() {
        let mut rng = Pcg32::new(3);
        for _ in 0..10_000 {
            let p = rng.next_dvec2();
            let (h, sin_th) = half_of([p.x, p.y]);
            assert!((h.length() - 1.0).abs() < 1e-12 && h.z >= 0.0);
            assert!((sin_th - (h.x * h.x + h.y * h.y).sqrt()).abs() < 1e-12);
            let q = square_of(h);
            assert!(
                (p.x - q[0]).abs() < 1e-9 && (p.y - q[1]).abs() < 1e-9,
                "{p} -> {h} -> {q:?}"
            );
        }
    }

    #[test]
    fn jacobian_is_the_solid_angle_of_a_patch() {
        // |∂ωi/∂s × ∂ωi/∂y| by finite differences = 4 (wo·h) · half_jacobian.
        let mut rng = Pcg32::new(4);
        let e = 1e-6;
        let wo = geometry::spherical(0.7, 0.2);
        let wi_of = |u: [f64; 2]| {
            let (h, _) = half_of(u);
            2.0 * wo.dot(h) * h - wo
        };
        for _ in 0..1000 {
            let p = rng.next_dvec2() * 0.98 + DVec2::splat(0.01);
            let u = [p.x, p.y];
            let a = wi_of(u);
            let bx = wi_of([u[0] + e, u[1]]) - wi_of([u[0] - e, u[1]]);
            let by = wi_of([u[0], u[1] + e]) - wi_of([u[0], u[1] - e]);
            let area = bx.cross(by).length() / (4.0 * e * e);
            let _ = a;
            let (h, st) = half_of(u);
            let j = 4.0 * wo.dot(h).abs() * half_jacobian(u[0], st);
            assert!((area - j).abs() <= 1e-6 * j + 1e-9, "{u:?}: {area} vs {j}");
        }
    }

    /// A plain reference of [`TableSampler::pdf`]: libm trigonometry, θo and φo by `acos` and
    /// `atan2`, the bilinear density read from the nodes by hand, both preimages summed.
    fn pdf_reference(t: &TableSampler, wi: DVec3, wo: DVec3) -> f64 {
        let (wi, wo) = (wi.normalize(), wo.normalize());
        let (theta_o, mut phi_o) = (wo.z.acos(), wo.y.atan2(wo.x));
        // Isotropic: the nodes' frame has φo = 0.
        let rot = if t.isotropic { -phi_o } else { 0.0 };
        let turn = |v: DVec3| {
            let (s, c) = rot.sin_cos();
            DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
        };
        let (wil, wol) = (turn(wi), turn(wo));
        // Conditioning weights: t = √(1 − cos θo) on nt nodes, φo on np periodic nodes.
        let mut slices = Vec::new();
        let tt = (1.0 - theta_o.cos()).sqrt() * (t.nt - 1) as f64;
        let t0 = (tt.floor() as usize).min(t.nt - 2);
        for (kt, wt) in [(t0, 1.0 - (tt - t0 as f64)), (t0 + 1, tt - t0 as f64)] {
            if t.np == 1 {
                slices.push((kt, wt));
                continue;
            }
            if phi_o < 0.0 {
                phi_o += TAU;
            }
            let pp = phi_o / TAU * t.np as f64;
            let p0 = pp.floor() as usize % t.np;
            let fp = pp - pp.floor();
            slices.push((kt * t.np + p0, wt * (1.0 - fp)));
            slices.push((kt * t.np + (p0 + 1) % t.np, wt * fp));
        }
        let (nx, ny) = (t.warp.pdf.nx, t.warp.pdf.ny);
        let node =
            |sl: usize, x: usize, y: usize| t.warp.pdf.data[sl * nx * ny + y * nx + x] as f64;
        let mut total = 0.0;
        for w in [wil, DVec3::new(wil.x, wil.y, -wil.z)] {
            let h = (w + wol).normalize();
            if h.z <= 0.0 {
                continue;
            }
            // atan2, not acos(h.z): acos loses θh's relative precision near the pole, where
            // the density divides by sin θh.
            let th = (h.x * h.x + h.y * h.y).sqrt().atan2(h.z);
            let s = s_of_theta(th);
            let y = ((h.y.atan2(h.x) + PI) / TAU).rem_euclid(1.0);
            let (fx, fy) = (s * (nx - 1) as f64, y * (ny - 1) as f64);
            let (ix, iy) = ((fx as usize).min(nx - 2), (fy as usize).min(ny - 2));
            let (ax, ay) = (fx - ix as f64, fy - iy as f64);
            let mut p = 0.0;
            for &(sl, wt) in &slices {
                p += wt
                    * ((1.0 - ay) * ((1.0 - ax) * node(sl, ix, iy) + ax * node(sl, ix + 1, iy))
                        + ay * ((1.0 - ax) * node(sl, ix, iy + 1) + ax * node(sl, ix + 1, iy + 1)));
            }
            p *= ((nx - 1) * (ny - 1)) as f64;
            let dtheta_ds = FRAC_PI_2 * (LINEAR + 2.0 * (1.0 - LINEAR) * s);
            total += p / (4.0 * wol.dot(h) * th.sin() * dtheta_ds * TAU);
        }
        total
    }

    #[test]
    fn pdf_and_sample_match_a_plain_reference() {
        let iso = crate::spec::ModelSpec::parse(
            r#"{"model": "cook_torrance", "m": 0.2, "fresnel": {"conductor": "Au"}}"#,
        )
        .unwrap()
        .build(&crate::spectrum::Channels::Rgb)
        .unwrap();
        let aniso = crate::spec::ModelSpec::parse(
            r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
        )
        .unwrap()
        .build(&crate::spectrum::Channels::Rgb)
        .unwrap();
        let small = SamplingResolution {
            theta_h: 24,
            phi_h: 20,
            theta_o: 9,
            phi_o: 6,
            floor: 0.005,
        };
        let mut rng = Pcg32::new(8);
        for (b, isotropic) in [(iso.as_ref(), true), (aniso.as_ref(), false)] {
            let t = TableSampler::build(b, isotropic, &small);
            let mut w = [0.0f32; 3];
            for _ in 0..20_000 {
                let wo = geometry::uniform_hemisphere(rng.next_dvec2());
                let wi = geometry::uniform_hemisphere(rng.next_dvec2());
                let (fast, slow) = (t.pdf(wi, wo), pdf_reference(&t, wi, wo));
                assert!(
                    (fast - slow).abs() <= 1e-9 * slow,
                    "{wi} {wo}: {fast} vs {slow}"
                );
                if let Some(smp) = t.sample(b, wo, rng.next_dvec2(), &mut w) {
                    let slow = pdf_reference(&t, smp.wi, wo);
                    // Where a preimage's half vector is nearly undefined (w + wo → 0: wi near
                    // the mirror image of −wo below the horizon), roundings of 1e-16 in the
                    // directions move ĥ by 1e-16/|w + wo| and wo·ĥ with it: relative errors of
                    // up to 1e-15/(|w + wo| wo·ĥ) in that term.
                    let cond = [smp.wi, mirror_z(smp.wi)]
                        .map(|w| {
                            let h = w + wo;
                            let dot = wo.dot(h) / h.length();
                            if h.z > 0.0 && dot > 0.0 {
                                1e-15 / (h.length() * dot)
                            } else {
                                0.0
                            }
                        })
                        .into_iter()
                        .fold(0.0, f64::max);
                    assert!(
                        (smp.pdf - slow).abs() <= (1e-7 + cond) * slow,
                        "{}: {} vs {slow}",
                        smp.wi,
                        smp.pdf
                    );
                }
            }
        }
    }

    /// The exported nodes are the sampler's own, and the adjoint exchanges the directions:
    /// for a reciprocal model it gives the same nodes, for a non-reciprocal one others.
    #[test]
    fn nodes_and_their_adjoint() {
        use crate::spec::ModelSpec;
        let res = SamplingResolution {
            theta_h: 12,
            phi_h: 10,
            theta_o: 5,
            ..SamplingResolution::default()
        };
        let open = |json: &str| {
            ModelSpec::parse(json)
                .unwrap()
                .build(&crate::spectrum::Channels::Rgb)
                .unwrap()
        };
        let ggx = open(r#"{"model": "ggx", "alpha": 0.3}"#);
        let n = SamplingNodes::build(ggx.as_ref(), true, &res);
        assert_eq!((n.nx, n.ny, n.nt, n.np), (12, 10, 5, 1));
        assert_eq!(
            n.data,
            SamplingNodes::build_par(ggx.as_ref(), true, &res).data
        );
        assert_eq!(n.data.len(), 12 * 10 * 5);
        let a = SamplingNodes::build(&Adjoint(ggx.as_ref()), true, &res);
        for (x, y) in n.data.iter().zip(&a.data) {
            assert!((x - y).abs() <= 1e-5 * x.abs().max(1e-6), "{x} vs {y}");
        }
        // Original Phong divides by cos θi: not reciprocal, so its adjoint differs.
        let phong = open(r#"{"model": "phong", "ks": 0.5, "n": 20}"#);
        let p = SamplingNodes::build(phong.as_ref(), true, &res);
        let q = SamplingNodes::build(&Adjoint(phong.as_ref()), true, &res);
        let diff = p
            .data
            .iter()
            .zip(&q.data)
            .filter(|(x, y)| (*x - *y).abs() > 1e-3 * x.abs());
        assert!(diff.count() > 10);
        let mut f = [0.0f32; 3];
        let mut g = [0.0f32; 3];
        let (wi, wo) = (DVec3::new(0.3, 0.1, 0.9), DVec3::new(-0.5, 0.2, 0.6));
        phong.eval(wo, wi, &mut f);
        Adjoint(phong.as_ref()).eval(wi, wo, &mut g);
        assert_eq!(f, g);
    }
}
