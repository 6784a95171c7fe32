//! The error of a written `.bsdf` file against its source.
//!
//! Metric (issue 15): brdftab's own RGL reader on the written file against the source, relative
//! RMSE of f_r weighted by cos θi cos θo,
//!
//! ```text
//! sqrt( Σ ((f̂ − f) cos θi cos θo)² / Σ (f cos θi cos θo)² )     (over pairs and channels)
//! ```
//!
//! over pairs drawn uniformly with both directions within 80° of the normal (the cut
//! [`analysis::accuracy`](crate::analysis::accuracy) uses for measured data). It is the table
//! report's cosine-weighted RMSE applied to f_r·cos θo — the quantity the file stores.
//!
//! Beside it, the figures a renderer meets outside that cap ([`fidelity`]): the relative RMSE
//! of f_r cos θi cos θo over the whole hemisphere and over the grazing band (a direction past
//! 80°), and the worst directional albedo over θ′ = 1–89°. The format's cells that the horizon
//! cuts make the band the written file's weak spot (a Lambert's ~6 % there against 0.8 % within
//! 80°; BENCHMARKS.md), which a report judged inside the cap alone would hide.

use glam::DVec3;

use crate::analysis::accuracy;
use crate::analysis::fidelity::{self, Fidelity, FidelityOptions};
use crate::brdf::{Brdf, Flags};
use crate::error::Result;
use crate::spectrum::Channels;

/// Directions farther than this from the normal are left out (radians).
pub const MAX_THETA: f64 = 80.0 * std::f64::consts::PI / 180.0;

/// What [`report`] measured.
#[derive(Debug, Clone)]
pub struct Report {
    /// Pairs evaluated.
    pub pairs: usize,
    /// The relative RMSE (module docs).
    pub rel_rmse: f64,
    /// Per channel.
    pub per_channel: Vec<f64>,
    /// Largest relative error of f_r·cos θo (floored at 1% of its RMS, as in
    /// [`accuracy`]).
    pub max_rel: f64,
    /// The whole-domain figures (module docs), on as many pairs.
    pub fidelity: Fidelity,
}

/// f_r · cos θo of a BRDF (what `.bsdf` readers return).
struct CosO<'a>(&'a dyn Brdf);

impl Brdf for CosO<'_> {
    fn channels(&self) -> &Channels {
        self.0.channels()
    }
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        self.0.eval(wi, wo, out);
        let c = wo.normalize_or_zero().z.max(0.0);
        for v in &mut out[..self.0.channels().len()] {
            *v = (*v as f64 * c) as f32;
        }
    }
    fn flags(&self) -> Flags {
        self.0.flags()
    }
    fn describe(&self) -> String {
        format!("{} × cos θo", self.0.describe())
    }
    fn health(&self) -> crate::Result<()> {
        self.0.health()
    }
}

/// Compares `written` (normally the file read back by [`RglBrdf`](crate::measured::RglBrdf))
/// against `source` over `pairs` random pairs (seed `seed`).
pub fn report(written: &dyn Brdf, source: &dyn Brdf, pairs: usize, seed: u64) -> Result<Report> {
    report_with(written, source, pairs, seed, &crate::progress::Silent)
}

/// [`report`], asking `progress` to stop between blocks of the work
/// ([`crate::progress::Progress::cancelled`]: [`crate::Error::Cancelled`]).
pub fn report_with(
    written: &dyn Brdf,
    source: &dyn Brdf,
    pairs: usize,
    seed: u64,
    progress: &dyn crate::progress::Progress,
) -> Result<Report> {
    let (w, s) = (&CosO(written), &CosO(source));
    let (cap, cos) = (accuracy::Region::Cap(MAX_THETA), accuracy::Weight::CosIn);
    let a = accuracy::compare_region_with(w, s, pairs, seed, cap, cos, progress)?;
    let opts = FidelityOptions {
        pairs,
        seed,
        ..FidelityOptions::default()
    };
    Ok(Report {
        pairs: a.pairs,
        rel_rmse: a.rel_rmse,
        per_channel: a.per_channel,
        max_rel: a.max_rel,
        fidelity: fidelity::measure_with(written, source, &opts, progress)?,
    })
}
