//! Grid presets: `small`, `medium` (default), `large`.
//!
//! Full axis sizes (θ1 × φ1 × θ2 × φ2); θ axes use cell-centre nodes, `halfdiff` θh the
//! square-root mapping. What is stored follows from the symmetry (an isotropic φ1 is stored with
//! size 1; bilateral symmetry and reciprocity fold φ2). Stored values for an isotropic,
//! reciprocal, bilateral RGB source in brackets; measured accuracy in `DESIGN-table.md`-style
//! notes of the crate README and the `table` module tests.
//!
//! | preset | halfdiff isotropic            | halfdiff anisotropic | inout isotropic      | inout anisotropic |
//! |--------|-------------------------------|----------------------|----------------------|-------------------|
//! | small  | 32 × – × 32 × 64   [52 k]     | 32 × 32 × 24 × 32    | 32 × – × 32 × 64     | 24 × 48 × 24 × 48 |
//! | medium | 90 × – × 90 × 360  [2.2 M]    | 64 × 48 × 32 × 48    | 90 × – × 90 × 180    | 45 × 90 × 45 × 90 |
//! | large  | 180 × – × 128 × 360 [6.3 M]   | 128 × 96 × 64 × 96   | 180 × – × 180 × 360  | 90 × 180 × 90 × 180 |
//!
//! The default for an isotropic source is `halfdiff` (the sqrt θh axis resolves specular peaks);
//! anisotropic sources keep φh (or φi).

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
    /// Parses `small`, `medium` or `large`.
    pub fn parse(s: &str) -> Result<Preset> {
        match s.trim().to_ascii_lowercase().as_str() {
            "small" => Ok(Preset::Small),
            "medium" => Ok(Preset::Medium),
            "large" => Ok(Preset::Large),
            o => Err(Error::arg(
                "--preset",
                format!("`{o}`: expected small, medium or large"),
            )),
        }
    }

    /// Full axis sizes for a parameterization and isotropy.
    pub fn sizes(self, param: Param, isotropic: bool) -> [usize; 4] {
        use Preset::*;
        match (param, isotropic, self) {
            (Param::HalfDiff, true, Small) => [32, 64, 32, 64],
            (Param::HalfDiff, true, Medium) => [90, 360, 90, 360],
            (Param::HalfDiff, true, Large) => [180, 360, 128, 360],
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
