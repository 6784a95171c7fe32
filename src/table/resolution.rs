//! The resolution of a [`TableSampler`](super::TableSampler): how many half-vector nodes and
//! conditioning views it holds, the defaults for isotropic, anisotropic and binned sources,
//! and the bytes they cost.
//!
//! Why a module of its own: the resolution is plain data that hosts read and pass back
//! (Python `Brdf.sampling_resolution`, the Mitsuba plugin's nodes) and `info` reports; the
//! decisions that probe a source for it ([`SamplingResolution::for_source`]) live with the
//! sampler in `table::sampling`, which builds at the resolution chosen here.

/// Resolution of a [`TableSampler`](super::TableSampler) (see the module docs of
/// `table::sampling`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SamplingResolution {
    /// Nodes over s, θh = (π/2)(a s + (1 − a) s²) with a = [`super::HALF_MAP_LINEAR`], at
    /// least 2.
    pub theta_h: usize,
    /// Nodes over φh (the first and the last are the same azimuth), at least 2.
    pub phi_h: usize,
    /// Conditioning nodes over t = sqrt(1 − cos θo).
    pub theta_o: usize,
    /// Conditioning nodes over φo (anisotropic sources only).
    pub phi_o: usize,
    /// Density added to every node whose mirror image of `wo` is above the horizon, as a
    /// fraction of those nodes' mean (0 < floor); a tenth of it is added to every node.
    pub floor: f64,
}

impl Default for SamplingResolution {
    fn default() -> Self {
        SamplingResolution {
            theta_h: 64,
            phi_h: 64,
            theta_o: 32,
            phi_o: 16,
            floor: 0.005,
        }
    }
}

impl SamplingResolution {
    /// The default for a source: [`SamplingResolution::default`] when `isotropic`, else
    /// [`SamplingResolution::anisotropic`].
    pub fn for_isotropy(isotropic: bool) -> Self {
        if isotropic {
            Self::default()
        } else {
            Self::anisotropic()
        }
    }

    /// The default for a source looked up as `isotropic` and `nearest` say:
    /// [`SamplingResolution::binned`] for isotropic nearest lookups, else
    /// [`SamplingResolution::for_isotropy`].
    pub fn for_lookup(isotropic: bool, nearest: bool) -> Self {
        if isotropic && nearest {
            Self::binned()
        } else {
            Self::for_isotropy(isotropic)
        }
    }

    /// This resolution with half again the φh nodes and the conditioning views over θo
    /// (2.25× the bytes): what [`TableSampler::for_source`](super::TableSampler::for_source) tries for a source whose lobe
    /// changes shape between the default views faster than they follow (the Phong family at
    /// grazing views: reciprocal Phong n = 1000 at 85°, CV 0.25 → 0.11).
    pub fn finer_views(&self) -> Self {
        SamplingResolution {
            phi_h: self.phi_h.max(2) * 3 / 2,
            theta_o: self.theta_o.max(2) * 3 / 2,
            ..*self
        }
    }

    /// Bytes a [`TableSampler`](super::TableSampler) of this resolution holds (`isotropic`: one node per θo).
    pub fn memory_bytes(&self, isotropic: bool) -> usize {
        let (nx, ny) = (self.theta_h.max(2), self.phi_h.max(2));
        let views = self.theta_o.max(1) * if isotropic { 1 } else { self.phi_o.max(1) };
        // f32 node densities, u32 alias entries over 2(ny − 1) half-strips and each row's
        // nx − 1 cells (`table::alias2d`).
        4 * views * (nx * ny + 2 * (ny - 1) + ny * (nx - 1))
    }

    /// The default for isotropic sources looked up by cell — a MERL file, a table read with
    /// nearest lookups — whose values step from cell to cell as the view moves: 48 θo nodes
    /// instead of 32 (1.6 MB). On a MERL file of `cc_ibiza_sunset` the weights' coefficient of
    /// variation at a 75° view goes from 0.105 to 0.098, at 85° from 0.167 to 0.124; more θh
    /// or φh nodes change it by less than 0.01.
    pub fn binned() -> Self {
        SamplingResolution {
            theta_o: 48,
            ..Default::default()
        }
    }

    /// A coarse resolution: 3 θh × 2 φh nodes at 2 θo × 1 φo views (a few dozen evaluations
    /// to build, under a kilobyte), for code that exercises the sampler rather than relies on
    /// its variance — the fuzz targets, and what
    /// [`TableSampler::for_source`](super::TableSampler::for_source) starts from in a
    /// `cfg(fuzzing)` build in place of [`SamplingResolution::for_lookup`] (the defaults'
    /// 131 k–737 k evaluations took 6–14 s per input in the instrumented build, over libFuzzer's
    /// timeout).
    pub const fn coarse() -> Self {
        SamplingResolution {
            theta_h: 3,
            phi_h: 2,
            theta_o: 2,
            phi_o: 1,
            floor: 0.005,
        }
    }

    /// The default for anisotropic sources (fewer nodes per view, 20 × 16 views: with 12 θo
    /// nodes the view at 85° blends the 80° and 90° slices, and anisotropic Ward's weights
    /// reached a CV of 0.23 there; 20 bring it to 0.18, for 6.0 MB).
    pub fn anisotropic() -> Self {
        SamplingResolution {
            theta_h: 48,
            phi_h: 48,
            theta_o: 20,
            phi_o: 16,
            ..Default::default()
        }
    }
}
