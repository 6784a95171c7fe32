//! What to write: the [`Options`] a host gives and the checked [`Layout`] they make for a source.

use super::{DATABASE_THETA_I, DEFAULT_RESOLUTION, DEFAULT_THETA_I, Parameterization};
use crate::error::{Error, Result};

/// What to write.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Options {
    /// Reflectance table resolution N (N × N per incident direction), 2..=1024; `None`:
    /// [`DEFAULT_RESOLUTION`] ([`FINE_RESOLUTION`] when elevations are placed, a figure stays
    /// past its bar at N = 64, N = 128 does better and fits [`PLACED_BYTES`]), or the
    /// parameterization's own.
    ///
    /// [`FINE_RESOLUTION`]: super::FINE_RESOLUTION
    /// [`PLACED_BYTES`]: super::PLACED_BYTES
    pub resolution: Option<usize>,
    /// Number of incident elevations θi (from 0 to 90°), 2..=256; `None`: placed per source
    /// ([`elevations::place`], 16 to 32, when it is isotropic; [`azimuths::place`] with its
    /// azimuths when it is not and `phi_i` is `None`), else [`DEFAULT_THETA_I`]. 8 gives
    /// the database's spacing, other counts are even in cos θi. Must be `None` with a
    /// parameterization (which fixes them).
    ///
    /// [`elevations::place`]: super::elevations::place
    /// [`azimuths::place`]: super::azimuths::place
    pub theta_i: Option<usize>,
    /// Number of incident azimuths: `None` = 1 for isotropic sources; for anisotropic ones
    /// placed with the elevations ([`azimuths::place`]) when `theta_i` is `None`, else 17. 1 writes an
    /// isotropic file (φi = 0), and is the only value an isotropic source takes; 3 or more an
    /// anisotropic one (evenly over [−π, π]), for anisotropic sources. 2 is not allowed
    /// (readers take ≤ 2 azimuths as isotropic).
    ///
    /// [`azimuths::place`]: super::azimuths::place
    pub phi_i: Option<usize>,
    /// Resolution of the NDF, σ and VNDF warp grids along each axis, 4..=1024; `None`: 128
    /// (the VNDF warps [`GRID_VNDF`] when an anisotropic source's azimuths are placed).
    ///
    /// [`GRID_VNDF`]: super::GRID_VNDF
    pub ndf_resolution: Option<usize>,
    /// The `description` field (default: the source's description).
    pub description: Option<String>,
    /// Resample into this existing parameterization (incident directions, NDF, σ, VNDF) instead
    /// of recovering one from the source — what re-encoding an RGL file uses, so that its values
    /// are resampled at the very positions they were stored at.
    pub parameterization: Option<Parameterization>,
}

/// Checked layout of a file to write.
#[derive(Debug, Clone)]
pub struct Layout {
    /// Reflectance table resolution N.
    pub n: usize,
    /// Incident elevations.
    pub theta_i: Vec<f32>,
    /// Incident azimuths.
    pub phi_i: Vec<f32>,
    /// At most 2 φi (an isotropic file, azimuths relative to φi).
    pub isotropic: bool,
    /// NDF/σ columns (θ).
    pub ndf_nx: usize,
    /// NDF/σ rows (φ).
    pub ndf_ny: usize,
    /// VNDF slice shape [rows (φ), columns (θ)].
    pub vndf: [usize; 2],
}

impl Options {
    /// When `source` names a `.bsdf` file and no incident-direction or NDF-grid option is set,
    /// resample into the file's own parameterization (re-encoding: values land where they were
    /// stored); otherwise the options as they are.
    pub fn reuse_source_file(mut self, source: impl AsRef<std::ffi::OsStr>) -> Result<Self> {
        let source = source.as_ref();
        let fixed = self.theta_i.is_none() && self.phi_i.is_none() && self.ndf_resolution.is_none();
        if fixed
            && self.parameterization.is_none()
            && source
                .as_encoded_bytes()
                .to_ascii_lowercase()
                .ends_with(b".bsdf")
        {
            self.parameterization = Some(Parameterization::from_file(source)?);
        }
        Ok(self)
    }

    /// Checks the options and computes the file's layout for a source (isotropic or not).
    pub fn layout(&self, source_isotropic: bool) -> Result<Layout> {
        let n = self.resolution.unwrap_or(
            self.parameterization
                .as_ref()
                .map_or(DEFAULT_RESOLUTION, |p| p.resolution),
        );
        if !(2..=1024).contains(&n) {
            return Err(Error::arg("resolution", format!("{n} is not in 2..=1024")));
        }
        if let Some(p) = &self.parameterization {
            if self.theta_i.is_some() || self.phi_i.is_some() || self.ndf_resolution.is_some() {
                return Err(Error::arg(
                    "theta_i",
                    "the incident directions and NDF grid are fixed by the given parameterization",
                ));
            }
            return Ok(Layout {
                n,
                theta_i: p.theta_i.clone(),
                phi_i: p.phi_i.clone(),
                isotropic: p.phi_i.len() <= 2,
                ndf_nx: p.ndf_shape[1],
                ndf_ny: p.ndf_shape[0],
                vndf: p.vndf_shape,
            });
        }
        let n_theta = self.theta_i.unwrap_or(DEFAULT_THETA_I);
        if !(2..=256).contains(&n_theta) {
            return Err(Error::arg(
                "theta_i",
                format!("{n_theta} incident elevations: 2..=256 are allowed"),
            ));
        }
        let nv = self.ndf_resolution.unwrap_or(128);
        if !(4..=1024).contains(&nv) {
            return Err(Error::arg(
                "ndf_resolution",
                format!("{nv} is not in 4..=1024"),
            ));
        }
        let n_phi = self.phi_i.unwrap_or(if source_isotropic { 1 } else { 17 });
        if n_phi == 2 || n_phi == 0 || n_phi > 360 {
            return Err(Error::arg(
                "phi_i",
                format!(
                    "{n_phi} incident azimuths: 1 (isotropic) or 3..=360 (anisotropic) are allowed"
                ),
            ));
        }
        // More azimuths for an isotropic source only repeat it: n_phi times the bytes, and the
        // anisotropic layout's even elevations in place of the placed ones (a GGX α = 0.3 file
        // with 4 φi: 4× the bytes, whole-hemisphere error 7.3 % against 0.41 % with 1).
        if n_phi > 1 && source_isotropic {
            return Err(Error::arg(
                "phi_i",
                format!(
                    "the source is isotropic: {n_phi} incident azimuths would repeat it {n_phi} \
                     times and lose the elevations placed for it (leave it unset, or 1)"
                ),
            ));
        }
        if n_phi == 1 && !source_isotropic {
            return Err(Error::arg(
                "phi_i",
                "the source is anisotropic: one incident azimuth would lose its azimuthal dependence (use 3 or more)",
            ));
        }
        let theta_i: Vec<f32> = if n_theta == DATABASE_THETA_I.len() {
            DATABASE_THETA_I.to_vec()
        } else {
            let m = (n_theta - 1) as f64;
            (0..n_theta)
                .map(|k| (1.0 - k as f64 / m).clamp(0.0, 1.0).acos() as f32)
                .collect()
        };
        let isotropic = n_phi == 1;
        let phi_i: Vec<f32> = if isotropic {
            vec![0.0]
        } else {
            let pi = std::f64::consts::PI;
            (0..n_phi)
                .map(|k| (-pi + 2.0 * pi * k as f64 / (n_phi - 1) as f64) as f32)
                .collect()
        };
        Ok(Layout {
            n,
            theta_i,
            phi_i,
            isotropic,
            ndf_nx: nv,
            ndf_ny: if isotropic { 2 } else { (nv / 2).max(4) },
            vndf: [nv, nv],
        })
    }
}
