//! The grid of azimuths and elevations being placed, the measurements its cells and lines need,
//! and running them in parallel.

use rayon::prelude::*;

use super::ALBEDO_RULE;
use crate::brdf::Brdf;
use crate::error::Result;
use crate::measured::RglBrdf;
use crate::measured::rgl_write::Progress;
use crate::measured::rgl_write::elevations::{Azimuths, Errors, floor_over, measure};

/// One measurement to make: elevations (`a`, `b`) and azimuths `az`.
#[derive(Clone, Copy)]
pub(super) struct Job {
    a: f64,
    b: f64,
    az: Azimuths,
    seed: u64,
}

/// The grid and what was measured on it.
pub(super) struct Grid {
    pub(super) phi: Vec<f64>,
    pub(super) theta: Vec<f64>,
    /// Cells, `[azimuth interval][elevation interval]`.
    pub(super) cell: Vec<Vec<Errors>>,
    /// Each elevation over each azimuth interval, `[azimuth interval][elevation]`.
    pub(super) at_theta: Vec<Vec<Errors>>,
    /// Each azimuth over each elevation interval, `[azimuth][elevation interval]`.
    pub(super) at_phi: Vec<Vec<Errors>>,
}

impl Grid {
    /// The job over elevations `a`–`b` and azimuths `from`–`to` (the light midway).
    fn job(a: f64, b: f64, from: f64, to: f64, seed: u64) -> Job {
        let light = 0.5 * (from + to);
        let az = Azimuths {
            from,
            to,
            light,
            rule: ALBEDO_RULE,
        };
        Job { a, b, az, seed }
    }
    pub(super) fn cell_job(&self, i: usize, j: usize, seed: u64) -> Job {
        let (t, p) = (&self.theta, &self.phi);
        Self::job(t[j], t[j + 1], p[i], p[i + 1], seed)
    }
    pub(super) fn at_theta_job(&self, i: usize, j: usize, seed: u64) -> Job {
        let (t, p) = (&self.theta, &self.phi);
        Self::job(t[j], t[j], p[i], p[i + 1], seed)
    }
    pub(super) fn at_phi_job(&self, i: usize, j: usize, seed: u64) -> Job {
        let (t, p) = (&self.theta, &self.phi);
        Self::job(t[j], t[j + 1], p[i], p[i], seed)
    }
    /// Solid angle of cell (`i`, `j`).
    fn area(&self, i: usize, j: usize) -> f64 {
        (self.phi[i + 1] - self.phi[i]) * (self.theta[j].cos() - self.theta[j + 1].cos())
    }
    /// The slice-limited errors of cell (`i`, `j`) along elevations and along azimuths.
    pub(super) fn floors(&self, i: usize, j: usize) -> (Errors, Errors) {
        let area = self.area(i, j);
        (
            floor_over(&self.at_theta[i][j], &self.at_theta[i][j + 1], area),
            floor_over(&self.at_phi[i][j], &self.at_phi[i + 1][j], area),
        )
    }
}

/// Runs `jobs` on the file in parallel, asking `progress` to stop before each.
pub(super) fn run(
    file: &RglBrdf,
    src: &dyn Brdf,
    jobs: &[Job],
    progress: &dyn Progress,
) -> Result<Vec<Errors>> {
    crate::par::install(|| {
        jobs.par_iter()
            .map(|j| {
                crate::progress::check(progress)?;
                Ok(measure(file, src, j.a, j.b, &j.az, j.seed))
            })
            .collect()
    })
}
