//! MERL BRDF database files (`.binary`, Matusik et al., "A Data-Driven Reflectance Model",
//! SIGGRAPH 2003): read, evaluate exactly as the reference reader, and write.
//!
//! # Format
//!
//! ```text
//! i32[3]  dims = (90, 90, 180)            θh, θd, φd resolutions (product 1,458,000)
//! f64[3 × 1,458,000]                      channel-planar R, then G, then B; little-endian
//! ```
//!
//! 34,992,012 bytes in all. Sample (θh, θd, φd) of channel c is at `c·N + φd + 180·θd + 180·90·θh`
//! and scales to f_r by R 1/1500, G 1.15/1500, B 1.66/1500. The angles are the Rusinkiewicz
//! half/difference angles of ([`geometry::to_half_diff`], with the
//! MERL reader's "in" direction = our `wi`), indexed as the reference reader `BRDFRead.cpp` does:
//!
//! - θh: `int(sqrt(θh / (π/2)) · 90)`, 0 when θh ≤ 0 — a square-root axis, dense near the
//!   specular peak;
//! - θd: `int(θd / (π/2) · 90)`;
//! - φd: plus π when negative (reciprocity, φd ≡ φd + π), then `int(φd / π · 180)`;
//!
//! each clamped to its range. Index `i` therefore covers a cell whose centre — in index space
//! `i + ½` — is where [`MerlBrdf::from_brdf`] samples a model and where a table's nodes must sit
//! for nearest-node lookup to reproduce this truncating lookup.
//!
//! # Missing measurements
//!
//! Negative stored values (the database uses −1) mark cells that were never measured (mostly at
//! grazing θd). [`MerlBrdf`] keeps them as stored — writing a file back is bit-exact — exposes
//! them through [`MerlBrdf::is_valid`], and evaluates them as 0: no reflectance is negative. (The
//! reference reader, `BRDFRead.cpp`, returns the scaled negative value and prints "Below
//! horizon.".)
//!
//! A sample no lookup can use — NaN, ±∞, or finite but beyond f32 once scaled to f_r — is a
//! corrupt file: [`MerlBrdf::open`] fails naming its channel and byte offset (it would otherwise
//! evaluate to ∞ in the cells it holds).
//!
//! A table of the file on [`Grid::merl`](crate::table::Grid::merl) ([`MerlBrdf::to_table`], or
//! a bake on that grid, which copies the cells through [`BakeSource::stored_node`]) keeps them too, as
//! negative values (−1 × scale), so MERL → table → MERL gives the file back (to f32 precision,
//! and within the codec's bound for lossy codecs, which keep the sign). Lookups in such a table
//! see them as 0 ([`TabulatedBrdf`](crate::table::TabulatedBrdf)): a *nearest* lookup gives the
//! reader's value (unmeasured → 0); a *linear* lookup next to an unmeasured cell blends towards
//! 0 over the half cell between the two centres, so measured values bordering the unmeasured
//! region are darkened slightly and nothing is extrapolated into it.
//!
//! # Below the horizon
//!
//! Many cells — most at large θh and small θd — have a centre whose direction pair dips below
//! the horizon (e.g. θh index 83, θd 15, φd 145), though directions above it still fall in them.
//! Such cells are measured data like any other: MERL → MERL and the tables above keep them, and
//! a linear lookup above the horizon interpolates them with their neighbours. `eval` of either
//! a file or a table is 0 when a direction itself is below the horizon. Only a source that is
//! *not* on the MERL grid (an analytic model, an RGL file, a table on another grid) is resampled
//! by directions, as cell means ([`super::merl_resample`]), and there a cell none of whose
//! points lies above the horizon has no value and is written as −1, as the database does.
//!
//! # Identification
//!
//! [`material_of`] names a file from its SHA-256 using [`MERL_FILES`](super::merl_manifest::MERL_FILES),
//! the checksums of the 100 published files.

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

use glam::DVec3;

use crate::brdf::{BakeSource, Brdf, Flags};
use crate::error::{Error, Result};
use crate::geometry::{self, HalfDiff};
use crate::spectrum::Channels;
use crate::table::sampling::TableSampler;

mod file;

/// θh resolution.
pub const RES_THETA_H: usize = 90;
/// θd resolution.
pub const RES_THETA_D: usize = 90;
/// φd resolution (over [0, π): the other half follows by reciprocity).
pub const RES_PHI_D: usize = 180;
/// Samples per channel.
pub const SAMPLES: usize = RES_THETA_H * RES_THETA_D * RES_PHI_D;
/// Size of every MERL file in bytes.
pub const FILE_SIZE: u64 = 12 + 3 * SAMPLES as u64 * 8;
/// Scale from stored values to f_r, per channel R, G, B.
pub const SCALE: [f64; 3] = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];

/// θh index: `int(sqrt(θh / (π/2)) · 90)`, 0 for θh ≤ 0, clamped to [0, 89].
#[inline]
pub fn theta_h_index(theta_h: f64) -> usize {
    if theta_h.is_nan() || theta_h <= 0.0 {
        return 0;
    }
    let x = (theta_h / FRAC_PI_2).sqrt() * RES_THETA_H as f64;
    (x as usize).min(RES_THETA_H - 1)
}

/// θd index: `int(θd / (π/2) · 90)`, clamped to [0, 89].
#[inline]
pub fn theta_d_index(theta_d: f64) -> usize {
    let x = theta_d / FRAC_PI_2 * RES_THETA_D as f64;
    if x.is_nan() || x <= 0.0 {
        return 0;
    }
    (x as usize).min(RES_THETA_D - 1)
}

/// φd index: φd + π when negative, then `int(φd / π · 180)`, clamped to [0, 179].
#[inline]
pub fn phi_d_index(phi_d: f64) -> usize {
    let p = if phi_d < 0.0 { phi_d + PI } else { phi_d };
    let x = p / PI * RES_PHI_D as f64;
    if x.is_nan() || x <= 0.0 {
        return 0;
    }
    (x as usize).min(RES_PHI_D - 1)
}

/// Linear sample index of (θh, θd, φd) indices within a channel plane.
#[inline]
pub fn sample_index(ith: usize, itd: usize, ipd: usize) -> usize {
    ipd + RES_PHI_D * itd + RES_PHI_D * RES_THETA_D * ith
}

/// The cell whose centre is at `hd` (to within 1e-6 of a cell in index space on every axis;
/// φh is ignored, φd is taken modulo π as the reader does), or `None` when `hd` is no cell
/// centre. The inverse of [`cell_center`].
pub fn cell_at_center(hd: HalfDiff) -> Option<(usize, usize, usize)> {
    const EPS: f64 = 1e-6;
    let node = |x: f64, n: usize| -> Option<usize> {
        let s = x - 0.5;
        let i = s.round();
        ((s - i).abs() <= EPS && i >= 0.0 && i < n as f64).then_some(i as usize)
    };
    let pd = if hd.phi_d < 0.0 {
        hd.phi_d + PI
    } else if hd.phi_d >= PI {
        hd.phi_d - PI
    } else {
        hd.phi_d
    };
    Some((
        node(
            (hd.theta_h.max(0.0) / FRAC_PI_2).sqrt() * RES_THETA_H as f64,
            RES_THETA_H,
        )?,
        node(hd.theta_d / FRAC_PI_2 * RES_THETA_D as f64, RES_THETA_D)?,
        node(pd / PI * RES_PHI_D as f64, RES_PHI_D)?,
    ))
}

/// The half/difference angles at the centre of cell (ith, itd, ipd) (φh = 0).
pub fn cell_center(ith: usize, itd: usize, ipd: usize) -> HalfDiff {
    let u = (ith as f64 + 0.5) / RES_THETA_H as f64;
    HalfDiff {
        theta_h: u * u * FRAC_PI_2,
        phi_h: 0.0,
        theta_d: (itd as f64 + 0.5) / RES_THETA_D as f64 * FRAC_PI_2,
        phi_d: (ipd as f64 + 0.5) / RES_PHI_D as f64 * PI,
    }
}

/// The material whose published file has this SHA-256 (lower-case hex), if any.
pub fn material_of(sha256: &str) -> Option<&'static str> {
    super::merl_manifest::MERL_FILES
        .iter()
        .find(|(_, h)| h.eq_ignore_ascii_case(sha256))
        .map(|(m, _)| *m)
}

/// SHA-256 of a file, lower-case hex.
pub fn sha256_file(path: impl AsRef<Path>) -> Result<String> {
    use sha2::Digest;
    use std::io::Read;
    let path = path.as_ref();
    crate::files::require_regular(path)?;
    let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut h = sha2::Sha256::new();
    let mut buf = vec![0u8; 1 << 20];
    loop {
        let n = f.read(&mut buf).map_err(|e| Error::io(path, e))?;
        if n == 0 {
            break;
        }
        h.update(&buf[..n]);
    }
    Ok(format!("{:x}", h.finalize()))
}

/// A MERL measurement: the stored samples (raw, unscaled, invalid cells negative) and the
/// reference reader's nearest lookup.
#[derive(Clone)]
pub struct MerlBrdf {
    pub(super) name: String,
    /// Raw stored values, channel-planar R, G, B (3 × [`SAMPLES`]).
    pub(super) data: Vec<f64>,
    pub(super) channels: Channels,
    /// Importance sampling of f_r cos θi given `wo`, built on first `sample`/`pdf`.
    pub(super) sampler: std::sync::OnceLock<TableSampler>,
}

impl std::fmt::Debug for MerlBrdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MerlBrdf")
            .field("name", &self.name)
            .field("invalid_cells", &self.invalid_cells())
            .finish_non_exhaustive()
    }
}

impl MerlBrdf {
    /// The sampler of [`Brdf::sample`] and [`Brdf::pdf`], built on first use (MERL data are
    /// isotropic: conditioned on θo alone, at
    /// [`SamplingResolution::binned`](crate::table::SamplingResolution::binned), as
    /// [`TableSampler::for_source`] refines it).
    pub fn sampler(&self) -> &TableSampler {
        self.sampler
            .get_or_init(|| TableSampler::for_source(self, true, true))
    }

    /// Name (file name or what it was resampled from).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The raw stored values, channel-planar R, G, B.
    pub fn raw(&self) -> &[f64] {
        &self.data
    }

    /// Whether cell (ith, itd, ipd) was measured (every channel ≥ 0).
    pub fn is_valid(&self, ith: usize, itd: usize, ipd: usize) -> bool {
        let k = sample_index(ith, itd, ipd);
        (0..3).all(|c| self.data[c * SAMPLES + k] >= 0.0)
    }

    /// Number of unmeasured cells (any channel negative).
    pub fn invalid_cells(&self) -> usize {
        (0..SAMPLES)
            .filter(|&k| (0..3).any(|c| self.data[c * SAMPLES + k] < 0.0))
            .count()
    }

    /// The stored value of cell (ith, itd, ipd) scaled to f_r per channel, as f32, unmeasured
    /// cells negative (−1 × scale).
    #[inline]
    pub fn stored_cell(&self, ith: usize, itd: usize, ipd: usize) -> [f32; 3] {
        let k = sample_index(ith, itd, ipd);
        let mut f = [0.0f32; 3];
        for (c, v) in f.iter_mut().enumerate() {
            *v = (self.data[c * SAMPLES + k] * SCALE[c]) as f32;
        }
        f
    }

    /// f_r of cell (ith, itd, ipd): scaled, invalid (negative) clamped to 0.
    #[inline]
    pub fn cell(&self, ith: usize, itd: usize, ipd: usize) -> [f32; 3] {
        self.cell_at(sample_index(ith, itd, ipd))
    }

    #[inline]
    fn cell_at(&self, k: usize) -> [f32; 3] {
        let mut f = [0.0f32; 3];
        for (c, v) in f.iter_mut().enumerate() {
            *v = (self.data[c * SAMPLES + k].max(0.0) * SCALE[c]) as f32;
        }
        f
    }
}

impl MerlBrdf {
    /// The measurement as a dense table on [`Grid::merl`](crate::table::Grid::merl): stored
    /// node (θh i, φh 0, θd j, φd k) holds cell (i, j, k) scaled to f_r as f32, unmeasured cells
    /// negative (−1 × scale, [`MerlBrdf::stored_cell`]), so the table keeps which cells were
    /// measured and converts back to the same MERL file.
    ///
    /// The grid's nodes use [`Nodes::CellStart`](crate::table::Nodes::CellStart), so a *nearest*
    /// lookup takes the same indices as [`MerlBrdf::eval`] (value for value, unmeasured as 0); a
    /// *linear* lookup interpolates between cells and, next to an unmeasured cell, towards 0
    /// (see the module docs).
    pub fn to_table(&self) -> crate::table::Table {
        let grid = crate::table::Grid::merl(Channels::Rgb);
        crate::table::Table::from_fn(grid, self.describe(), |idx, _, out| {
            out.copy_from_slice(&self.stored_cell(idx[0], idx[2], idx[3]));
        })
    }
}

impl Brdf for MerlBrdf {
    fn bake_source(&self) -> Option<&dyn BakeSource> {
        Some(self)
    }

    fn channels(&self) -> &Channels {
        &self.channels
    }

    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let out = &mut out[..3];
        out.fill(0.0);
        let Some((wi, wo)) = geometry::upper_pair(wi, wo) else {
            return;
        };
        let Some(hd) = geometry::to_half_diff(wi, wo) else {
            return;
        };
        let k = sample_index(
            theta_h_index(hd.theta_h),
            theta_d_index(hd.theta_d),
            phi_d_index(hd.phi_d),
        );
        out.copy_from_slice(&self.cell_at(k));
    }

    /// The channels mixed at each wavelength: one cell lookup for all of them.
    fn eval_at_wavelengths(&self, wi: DVec3, wo: DVec3, nm: &[f64], out: &mut [f32]) {
        crate::brdf::channels_at_wavelengths(self, wi, wo, nm, out)
    }

    /// Importance sampling by conditional half-vector warps of f_r cos θi given `wo`
    /// ([`TableSampler`], built from this reader on first use: 197 k lookups, about
    /// 30 ms). A MERL file carries no sampling data of its own; the cosine-weighted
    /// default the trait would give leaves a glossy measurement's weights with a coefficient of
    /// variation of 3–25 (a MERL file of `cc_ibiza_sunset`, views 3–85°), against 0.06–0.12
    /// with this sampler (BENCHMARKS.md).
    fn sample(
        &self,
        wo: DVec3,
        u: glam::DVec2,
        weight: &mut [f32],
    ) -> Option<crate::brdf::BrdfSample> {
        self.sampler().sample(self, wo, u, weight)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.sampler().pdf(wi, wo)
    }

    /// By quadrature to [`crate::analysis::albedo::Options::DATA`] (see [`Brdf::albedo`]).
    fn albedo(&self, wi: DVec3, out: &mut [f64]) {
        crate::brdf::albedo_with(self, wi, &crate::quadrature::Options::DATA, out)
    }

    fn flags(&self) -> Flags {
        // The φd ≡ φd + π fold makes every lookup reciprocal; only φd ∈ [0, π) is stored, and
        // the data are isotropic by construction (no φh).
        Flags {
            reciprocal: true,
            isotropic: true,
            lobes: crate::brdf::Lobes::GLOSSY,
            ..Flags::default()
        }
    }

    fn describe(&self) -> String {
        format!("MERL measured BRDF ({})", self.name)
    }
}

impl BakeSource for MerlBrdf {
    /// The stored cell whose centre is `hd` ([`cell_at_center`]), unmeasured cells negative.
    fn stored_node(&self, hd: HalfDiff, out: &mut [f32]) -> bool {
        match cell_at_center(hd) {
            Some((ith, itd, ipd)) if out.len() >= 3 => {
                out[..3].copy_from_slice(&self.stored_cell(ith, itd, ipd));
                true
            }
            _ => false,
        }
    }
}
