//! The sampler made for a source: its resolution decided by probing the source (a sharp peak at
//! normal incidence, the weights' CV predicted between the conditioning views) and its
//! distributions built. The draws and densities that read it are in `mod.rs`.

use glam::DVec3;

use super::half_map::{half_jacobian, theta_of_s};
use super::{SamplingNodes, SamplingResolution, TableSampler};
use crate::brdf::Brdf;
use crate::geometry;
use crate::table::alias2d::AliasWarp;
use crate::table::warp2d::Planes;

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
        crate::table::pole::pole_share(
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
        crate::table::views::predicted_cv(
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
        crate::table::views::worst_excess(
            brdf,
            &pdf,
            &Self::half_map(),
            self.res.theta_h,
            self.res.phi_h,
            self.nt,
        )
    }

    fn half_map() -> crate::table::views::HalfMap<'static> {
        crate::table::views::HalfMap {
            theta_of_s: &theta_of_s,
            jacobian: &half_jacobian,
        }
    }

    /// Bytes held by the distributions.
    pub fn memory_bytes(&self) -> usize {
        self.warp.memory_bytes()
    }
}
