//! Writing RGL-EPFL `.bsdf` files (Dupuy & Jakob 2018) from any [`Brdf`]: the one measured
//! format pbrt-v4's `measured` material and Mitsuba 3's `measured` plugin load natively.
//!
//! A `.bsdf` file does not store reflectance on a fixed grid: it stores the material's own
//! *adaptive parameterization* and the reflectance sampled through it. Writing one therefore
//! rebuilds that parameterization from the source, in the order the paper acquires it:
//!
//! 1. [`ndf`]: the microfacet distribution D recovered from the source's retro-reflection
//!    f(ω, ω) by power iteration (Dupuy et al. 2015: D is the eigenvector of
//!    D(ω) ∝ f(ω, ω) cos θ σ(ω)), and its projected area σ(ω) = ∫ D(m) max(0, m·ω) dm;
//! 2. [`warps`]: per incident direction (φi, θi), the visible-normal density
//!    D(m) max(0, m·ωi) on the (θ, φ) unit square (with the square's Jacobian 2π² u sin θ), built
//!    into the reader's own marginal-conditional warp;
//! 3. [`values`]: the reflectance sampled on an N × N grid of the warp's *input* square: each grid
//!    point is warped to a half vector m, ωo = reflect(ωi, m), and the file stores
//!    f_r·cos θo · 4σ(ωi) / D(m) (the `jacobian` = 1 convention: readers multiply by
//!    D(m) / (4σ(ωi)), interpolated from the same tables, so at the grid points they return
//!    exactly f_r·cos θo), clipped at 0 as the readers clip;
//! 4. the `luminance` table (Rec. 709 Y of the stored values; for spectra their photometric Y
//!    under D65, [`ndf::luminance_weights`]) that the readers sample by, and [`container`] lays
//!    the fields out as the published files do.
//!
//! [`report()`] measures a written file against its source with brdftab's own reader.
//!
//! The positions in step 3 are found with the reader's warp code itself
//! ([`rgl`](super::rgl)), so writer and reader agree on where every stored value lives.
//!
//! Defaults (measured, see the tests and BENCHMARKS.md "Written files placed where they are
//! wrong"): an isotropic source's incident elevations are placed by [`elevations`] — from 16
//! even in cos θi, split where the file's own reader is farthest from the source over the whole
//! domain, up to 32 within [`PLACED_BYTES`] — at N = 64, or at N = 128 when a figure stays past
//! its bar, 128 does better and 16 elevations of it fit the budget; an anisotropic source's
//! azimuths and elevations are placed together by [`azimuths`] — from 9 φi evenly over [−π, π]
//! (no symmetry reduction assumed) and 16 θi even in cos θi, split where the file is farthest
//! from the source, at N = 64 on 64 × 64 warps ([`GRID_VNDF`]) within [`PLACED_BYTES`] (its
//! error lies mostly in the interpolation over azimuths, which no count that fits brings
//! within the grazing band's bar: BENCHMARKS.md "Anisotropic files placed over azimuths and
//! elevations"); an isotropic source gets φi = 0. Warps are otherwise 128 × 128, NDF and σ on
//! 128 elevations (2 identical azimuth rows when isotropic, 64 rows over [−π, π] otherwise). One fixed spacing served no source over the whole domain:
//! 16 elevations even in cos θi left a Lambertian's grazing band 6.3 % off and Cook-Torrance
//! gold's albedo 4.5 % off at 89°; even in θi, a Cook-Torrance's grazing band 10 %. A given
//! count of elevations (`theta_i`) is even in cos θi as before. The published files' layout
//! (N = 32, the database's 8 non-uniform elevations, asked for with 8) serves measurements,
//! whose parameterization follows the material, but it interpolates analytic lobes poorly over
//! θi: Cook-Torrance m = 0.3 gold measured 3.6% with it, 1.3% with 16 elevations at N = 32,
//! 0.35% at N = 64 (the metric of [`report()`]). `.bsdf` sources are instead resampled into
//! their own parameterization ([`Options::reuse_source_file`]): same elevations, NDF, warps and N, and
//! the stored values at below-horizon grid points kept; where the source evaluates to the
//! file's own values at every grid point (it is the file), they are copied as stored, so a
//! re-encoded file is the original's table exactly (it used to evaluate them clipped at 0,
//! which brightened dark channels by up to 13 % in albedo).
//!
//! Renderers: Mitsuba 3's `measured` plugin loads RGB files in its RGB variants and spectral files
//! in its spectral variants (checked by `bindings/python/tests/test_rgl_writer_mitsuba.py`).
//! pbrt-v4's `measured` material reads only `spectra` + `wavelengths` (write spectral sources,
//! e.g. specs evaluated at wavelengths), supports no φ reduction (these files have none) and
//! conditions the tensor on its own `wo` (the camera side): for non-reciprocal sources the two
//! renderers therefore see the file with the directions swapped.
//!
//! Choices where the source has no measurement to offer:
//! - the θi = 90° slice evaluates the source at θi = 89.5° (f_r·cos θo at exact grazing incidence
//!   is 0 by the [`Brdf`] conventions; readers interpolate towards this slice above 78.5°);
//! - grid points whose ωo falls below the horizon continue their valid neighbours linearly (they
//!   are corners of cells readers interpolate in, never evaluated themselves); the `valid` field
//!   marks them 0 (a bit per sample, packed most significant bit first over φi × θi × N × N —
//!   the published files' `valid` has exactly that many bytes, φi·θi·N²/8, though what their bits
//!   mean is not documented; no reader uses the field);
//! - D is floored at 10⁻⁵ of its maximum so that every warp covers the whole hemisphere, and
//!   for isotropic sources raised to a tenth of what any incidence up to 80° needs
//!   ([`ndf::COVERAGE`]): a lobe that the retro-reflection misses (Phong's, about the mirror
//!   direction) otherwise gets a few cells for the whole lobe;
//! - a luminance slice that is zero everywhere (a source black for that incidence) is stored
//!   uniform, which keeps the file loadable.
//!
//! Errors: a source that is zero everywhere (no retro-reflection to recover D from), or returns
//! NaN or infinite values, is an [`Error::InvalidArgument`]; invalid cells of MERL files evaluate
//! as 0 in the source and are written as 0.
//!
//! [`Error::InvalidArgument`]: crate::Error::InvalidArgument

pub mod azimuths;
mod build;
pub mod container;
pub mod elevations;
pub mod ndf;
mod options;
mod parameterization;
pub mod report;
pub mod values;
pub mod warps;

use std::path::Path;

use crate::brdf::Brdf;
use crate::error::Result;

pub use build::encode;
use build::fields_of;
pub use container::Fields;
pub use options::{Layout, Options};
pub use parameterization::Parameterization;
pub use report::{Report, report, report_with};

/// The incident elevations (radians) of the published isotropic files (0°, 27.7°, 39.9°, 49.9°,
/// 59.3°, 68.6°, 78.5°, 90°), used when 8 are asked for.
pub const DATABASE_THETA_I: [f32; 8] = [
    0.0,
    0.482_896_83,
    0.695_710_7,
    0.871_582_87,
    1.034_542_9,
    1.196_715_5,
    1.369_449,
    std::f32::consts::FRAC_PI_2,
];

/// Default reflectance table resolution N for sources without a parameterization of their own.
pub const DEFAULT_RESOLUTION: usize = 64;

/// The resolution N a source gets by default when at [`DEFAULT_RESOLUTION`] a figure stays past
/// its bar ([`elevations::Placement::past_bar`]).
pub const FINE_RESOLUTION: usize = 128;

/// The most bytes placement lets a file grow to (the values, luminance and VNDF of every
/// elevation): more elevations or the finer table only while they fit. 16 elevations always
/// fit (the count written before placement); a spectral file of 48 wavelengths stays at
/// N = 64 (at N = 128 and 32 elevations it took 105 MB and 12 s). An anisotropic source's
/// grid starts from 9 azimuths × 16 elevations whether they fit or not (48 wavelengths: 118 MB,
/// where the even 17 × 16 on 128² warps took 236 MB) and grows only while it fits.
pub const PLACED_BYTES: usize = 32 << 20;

/// The number of incident elevations of an anisotropic source given its count of azimuths
/// (even in cos θi); otherwise elevations are placed ([`elevations`], [`azimuths`]).
pub const DEFAULT_THETA_I: usize = 16;

/// Rows and columns of an anisotropic file's VNDF slices when its azimuths and elevations are
/// placed ([`azimuths::place`]): 64 × 64 leaves [`PLACED_BYTES`] room for 409 RGB slices at
/// N = 64, against 256 at 128 × 128, and the interpolation over azimuths is where such a file's
/// error is (the NDF and σ keep 128 columns).
pub const GRID_VNDF: usize = 64;

/// The most f32 values a written file may hold (1 GiB), so that no option allocates without bound.
pub const MAX_FLOATS: usize = 1 << 28;

pub use crate::progress::Progress;

/// The stored values and their validity bits.
#[derive(Debug, Clone)]
pub struct Values {
    /// φi × θi × channels × N × N.
    pub data: Vec<f32>,
    /// One bit per (φi, θi, j, i), packed.
    pub valid: Vec<u8>,
}

/// What [`write()`] wrote.
#[derive(Debug, Clone)]
pub struct Written {
    /// File size in bytes.
    pub bytes: usize,
    /// The fields written.
    pub fields: Fields,
}

/// Encodes `brdf` and writes the `.bsdf` file at `path` (through a temporary file renamed into
/// place).
pub fn write(
    brdf: &dyn Brdf,
    path: impl AsRef<Path>,
    opts: &Options,
    progress: &dyn Progress,
) -> Result<Written> {
    let path = path.as_ref();
    let fields = encode(brdf, opts, progress)?;
    // A source that failed while it was read (a corrupt table chunk) gave zeros: write nothing.
    brdf.health()?;
    let bytes = fields.to_bytes();
    crate::files::write_atomic(path, &bytes)?;
    Ok(Written {
        bytes: bytes.len(),
        fields,
    })
}

#[cfg(test)]
mod tests;
