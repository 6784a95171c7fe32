//! Grid presets: `small`, `medium` (default), `large`.
//!
//! (RGL measurements bake by default on an adaptive grid instead, whose node positions follow
//! the material: see [`crate::table::adaptive`] and `GridChoice::Adaptive` in [`crate::bake`].)
//!
//! Full axis sizes (θ1 × φ1 × θ2 × φ2); θ axes use cell-centre nodes. `halfdiff` θh uses the
//! square-root mapping; isotropic `halfdiff` θd is uniform in cos θd (dense towards grazing, where
//! microfacet models grow), anisotropic θd uniform. What is stored follows from the symmetry (an
//! isotropic φ1 is stored with size 1; bilateral symmetry and reciprocity fold φ2).
//!
//! | preset | halfdiff isotropic     | halfdiff anisotropic | inout isotropic     | inout anisotropic   |
//! |--------|------------------------|----------------------|---------------------|---------------------|
//! | small  | 32 × – × 32 × 64       | 32 × 32 × 24 × 32    | 32 × – × 32 × 64    | 24 × 48 × 24 × 48   |
//! | medium | 90 × – × 180 × 360     | 64 × 48 × 32 × 48    | 90 × – × 90 × 180   | 45 × 90 × 45 × 90   |
//! | large  | 180 × – × 360 × 360    | 128 × 96 × 64 × 96   | 180 × – × 180 × 360 | 90 × 180 × 90 × 180 |
//!
//! Stored RGB values for an isotropic, reciprocal, bilateral source: small 52 k, medium 4.4 M
//! (17.7 MB as f32, the size of a MERL file), large 17.7 M. Isotropic `halfdiff` presets are
//! looked up by [`crate::table::kernel`] (their mappings resampled as knot lines, values exact):
//! one lookup of the medium table takes 36–44 ns (BENCHMARKS.md, "Preset tables on the kernel").
//!
//! Measured accuracy (`cargo run --release --example table_accuracy -- --seeds 5 small medium
//! large`; linear lookup, cosine-weighted relative RMSE over 10^5 random pairs, median over 5
//! seeds — the metric is heavy-tailed for models that grow without bound at grazing angles, so
//! the spread is given where it matters):
//!
//! | model                                   | small  | medium               | large                |
//! |-----------------------------------------|--------|----------------------|----------------------|
//! | Lambert                                 | 0      | 0                    | 0                    |
//! | Cook-Torrance m 0.3, n 0.2 k 3          | 13.6%  | 0.55% (0.34–1.07%)   | 0.31% (0.14–0.93%)   |
//! | reciprocal Phong n 50                   | 1.1%   | 0.13%                | 0.036%               |
//! | GGX α 0.1                               | 3.3%   | 0.16% (0.15–0.34%)   | 0.04%                |
//! | reciprocal Phong n 1000                 | 4.5%   | 0.59%                | 0.15%                |
//! | original Phong n 1000 (1/cos θi)        | >50%   | 9% (2.4–53%)         | 8.6% (2.4–68%)       |
//! | Ward αx 0.1 αy 0.3 (anisotropic)        | 70%    | 21% (16–31%)         | 12% (7–28%)          |
//!
//! Models that diverge at the horizon (original Phong's 1/cos θi, Ward's 1/sqrt(cos θi cos θo))
//! are poorly served: nodes outside the physical `halfdiff` domain are baked at directions lifted
//! to z = 1e-3 ([`crate::table::pair_of`]), where such models are huge, and interpolation next to
//! the horizon mixes those values in.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::spectrum::Channels;
use crate::table::grid::{Grid, Mapping, Param};
use crate::table::symmetry::Symmetry;

/// A grid size preset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// Quick previews, tests.
    Small,
    /// The default: MERL resolution for isotropic sources.
    #[default]
    Medium,
    /// Sharp lobes.
    Large,
}

impl Preset {
    /// `small`, `medium` or `large`: the name [`str::parse`] reads.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Small => "small",
            Preset::Medium => "medium",
            Preset::Large => "large",
        }
    }

    /// Full axis sizes for a parameterization and isotropy.
    pub fn sizes(self, param: Param, isotropic: bool) -> [usize; 4] {
        use Preset::*;
        match (param, isotropic, self) {
            (Param::HalfDiff, true, Small) => [32, 64, 32, 64],
            (Param::HalfDiff, true, Medium) => [90, 360, 180, 360],
            (Param::HalfDiff, true, Large) => [180, 360, 360, 360],
            (Param::HalfDiff, false, Small) => [32, 32, 24, 32],
            (Param::HalfDiff, false, Medium) => [64, 48, 32, 48],
            (Param::HalfDiff, false, Large) => [128, 96, 64, 96],
            (Param::InOut, true, Small) => [32, 64, 32, 64],
            (Param::InOut, true, Medium) => [90, 180, 90, 180],
            (Param::InOut, true, Large) => [180, 360, 180, 360],
            (Param::InOut, false, Small) => [24, 48, 24, 48],
            (Param::InOut, false, Medium) => [45, 90, 45, 90],
            (Param::InOut, false, Large) => [90, 180, 90, 180],
        }
    }

    /// The preset grid for `param` (default `halfdiff`), symmetry and channels.
    pub fn grid(
        self,
        param: Option<Param>,
        symmetry: Symmetry,
        channels: Channels,
    ) -> Result<Grid> {
        let param = param.unwrap_or(Param::HalfDiff);
        let mappings = match param {
            // Uniform in cos θd resolves the grazing growth of microfacet models (measured:
            // Cook-Torrance m = 0.3 medium 5.5% → 0.5% median rel. RMSE); the anisotropic
            // presets have too few θd nodes for it and keep θd uniform.
            Param::HalfDiff if symmetry.isotropic => [Mapping::Sqrt, Mapping::Cos],
            Param::HalfDiff => [Mapping::Sqrt, Mapping::Uniform],
            Param::InOut => [Mapping::Uniform, Mapping::Uniform],
        };
        Grid::with_sizes(
            param,
            self.sizes(param, symmetry.isotropic),
            mappings,
            channels,
            symmetry,
        )
    }
}

impl std::str::FromStr for Preset {
    type Err = crate::Error;

    /// Parses `small`, `medium` or `large`.
    fn from_str(s: &str) -> std::result::Result<Self, crate::Error> {
        match s.trim().to_ascii_lowercase().as_str() {
            "small" => Ok(Preset::Small),
            "medium" => Ok(Preset::Medium),
            "large" => Ok(Preset::Large),
            o => Err(Error::arg(
                "preset",
                format!("`{o}`: expected small, medium or large"),
            )),
        }
    }
}
