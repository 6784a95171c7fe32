//! Resampling a BRDF onto the MERL grid as *cell means*: what a MERL file holds when it is
//! written from a source that is not on that grid (an RGL measurement, an analytic model, a
//! table on another grid).
//!
//! Why means and not the value at the cell's centre: a MERL reader looks values up by cell
//! (the truncating index of [`super::merl`]), so every pair in a cell gets the one stored
//! value, and the value that keeps the directional albedos a renderer integrates is a mean over
//! the cell's pairs. A centre sample is that only where f_r is smooth across the cell. Near the
//! horizon it is not: measured f_r grows like 1/cos θo there (the RGL reader's does), and a
//! cell whose centre lay just above the horizon held many times its neighbours' values for the
//! whole cell. Written from the shipped `paper_white` file, the albedo at θ′ = 89° came out
//! 3.7× the source's; from `colodur_napoli_4f`, 4.8× (BENCHMARKS.md, "MERL files written as
//! cell means").
//!
//! # The mean
//!
//! - **Both orientations.** The reader folds φd + π onto φd: a cell holds a pair (ωi, ωo) and
//!   its reciprocal (ωo, ωi), so one value stands for f_r of both. For a source not flagged
//!   reciprocal (a measurement) each point is evaluated both ways.
//! - **Weights.** Over the pairs, dωi dωo = 4 cos θd dωh dωd (Rusinkiewicz 1998); a cell spans
//!   every φh (the reader ignores it: an isotropic source is evaluated at φh = 0, an anisotropic
//!   one at [`PHI_H_POINTS`] azimuths per point, its mean over φh), and θh = (π/2)(u/90)²
//!   on the index u. Each evaluation f_r(ωi, ωo) weighs cos θo of its own orientation — its
//!   share of the directional albedo a(ωi) = ∫ f_r cos θo dωo —, so the weight of a point is
//!   cos θd sin θd sin θh · u · cos θo (and cos θi for the reciprocal orientation). Weighting
//!   by cos θi cos θo instead (the rendering measure, symmetric in the orientations) gave a
//!   non-reciprocal measurement's f_r(ωi, ωo) with ωo near the horizon, which grows like
//!   1/cos θo, the weight of its reciprocal, and the albedo at θ′ = 89° of the file written
//!   from `paper_white` was 2.4× the source's; weighted by cos θo it is within 8 %.
//! - **Points.** [`POINTS_PER_AXIS`]³ stratified points in index space; those with a direction
//!   below the horizon are left out. The cell's value is Σ w f_r / Σ w; a cell none of whose
//!   points lies above the horizon has no value (−1, unmeasured, as in the database). A constant
//!   f_r (Lambert) is kept exactly.
//!
//! A measurement that is not reciprocal cannot be kept by any MERL file (the format is
//! reciprocal by its fold): cc_ibiza_sunset's f_r(1°, 0°) and f_r(0°, 1°) differ by 12 % in
//! green, and its file's albedo near normal incidence stays 13 % below the source's.
//!
//! A mean is not the value at any one point of the cell: where f_r is unbounded at the horizon
//! the file's albedo at a single grazing angle follows the cells' means. Isotropic Ward
//! (α = 0.3), whose albedo grows without bound towards 90°, comes out 13 % high at θ′ = 89°
//! (centre samples: 4.4 %), while its whole-hemisphere and grazing-band figures improve.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use rayon::prelude::*;

use std::sync::atomic::{AtomicUsize, Ordering};

use crate::brdf::Brdf;
use crate::geometry::{self, HalfDiff};
use crate::progress::{Progress, Silent, Stage};
use crate::spectrum::{Channels, MAX_CHANNELS};

use super::merl::{MerlBrdf, RES_PHI_D, RES_THETA_D, RES_THETA_H, SAMPLES, SCALE, cell_center};

impl MerlBrdf {
    /// Resamples any BRDF onto the MERL grid and stores f_r / scale.
    ///
    /// An isotropic source that stores a value at the cell centre ([`BakeSource::stored_node`](crate::brdf::BakeSource::stored_node): a MERL
    /// measurement, a `halfdiff` table on the MERL grid) gives it as stored, so MERL → MERL and
    /// MERL → table → MERL keep every cell — to f32 precision, the precision of
    /// [`BakeSource::stored_node`](crate::brdf::BakeSource::stored_node) — and every unmeasured cell: a negative stored value is written as
    /// the database's −1. Any other source gives each cell the mean of its f_r over the cell
    /// ([`merl_resample::cell_mean`](super::merl_resample::cell_mean): both orientations of
    /// every pair, weighted for the directional albedos; RGB channels as they are, a spectral
    /// source's channels projected to linear sRGB); a cell with no
    /// point above the horizon is stored as −1 (unmeasured), as in the database. The format is
    /// isotropic: an anisotropic source's cells hold its mean over φh as well. Runs in
    /// parallel.
    ///
    /// ```
    /// use brdftab::Brdf;
    /// let lambert = brdftab::source::open(r#"{"model": "lambert", "kd": 0.25}"#)?;
    /// let merl = brdftab::measured::MerlBrdf::from_brdf(lambert.as_ref());
    /// let mut f = [0f32; 3];
    /// let (wi, wo) = (brdftab::geometry::spherical(0.3, 0.0), brdftab::geometry::spherical(1.2, 2.0));
    /// merl.eval(wi, wo, &mut f);
    /// // The mean of a constant is the constant (to the file's f64 and f32 roundings).
    /// assert!(f.iter().all(|x| (x - 0.25).abs() < 1e-6));
    /// # Ok::<(), brdftab::Error>(())
    /// ```
    pub fn from_brdf(brdf: &dyn Brdf) -> Self {
        Self::from_brdf_with(brdf, &Silent)
    }

    /// [`MerlBrdf::from_brdf`], reporting the θh rows done (of 90) to `progress` as a stage
    /// `"resampling on the MERL grid"` (a file from a measurement takes seconds: 54 evaluations
    /// per cell). A cancelled `progress` ([`Progress::cancelled`]) stops it within a row of
    /// θd: the cells not reached are then 0, and the caller returns
    /// [`crate::Error::Cancelled`] rather than use them.
    pub fn from_brdf_with(brdf: &dyn Brdf, progress: &dyn Progress) -> Self {
        let _stage = Stage::begin(progress, "resampling on the MERL grid", RES_THETA_H as u64);
        let done = AtomicUsize::new(0);
        let rgb = *brdf.channels() == Channels::Rgb;
        let weights = rgb_weights(brdf.channels());
        let to_rgb = weights.as_deref();
        // A stored node is one φh of its cell: only an isotropic source's is the cell's value.
        let stored = rgb && brdf.flags().isotropic;
        let plane = RES_THETA_D * RES_PHI_D;
        let mut cells = vec![[0.0f64; 3]; SAMPLES];
        crate::par::install(|| {
            cells
                .par_chunks_mut(plane)
                .enumerate()
                .for_each(|(ith, chunk)| {
                    for itd in 0..RES_THETA_D {
                        if progress.cancelled() {
                            return;
                        }
                        for ipd in 0..RES_PHI_D {
                            let hd = cell_center(ith, itd, ipd);
                            let cell = &mut chunk[ipd + RES_PHI_D * itd];
                            let mut f = [0.0f32; 3];
                            if stored
                                && brdf
                                    .bake_source()
                                    .is_some_and(|b| b.stored_node(hd, &mut f))
                            {
                                for c in 0..3 {
                                    cell[c] = if f[c] < 0.0 {
                                        -1.0
                                    } else if f[c].is_finite() {
                                        f[c] as f64 / SCALE[c]
                                    } else {
                                        0.0
                                    };
                                }
                                continue;
                            }
                            *cell = match cell_mean_with(brdf, to_rgb, ith, itd, ipd) {
                                Some(m) => std::array::from_fn(|c| m[c] / SCALE[c]),
                                // No point of the cell above the horizon: unmeasured, as in
                                // the database.
                                None => [-1.0; 3],
                            };
                        }
                    }
                    progress.set((done.fetch_add(1, Ordering::Relaxed) + 1) as u64);
                })
        });
        let mut data = vec![0.0f64; 3 * SAMPLES];
        for (k, cell) in cells.iter().enumerate() {
            for c in 0..3 {
                data[c * SAMPLES + k] = cell[c];
            }
        }
        MerlBrdf {
            name: format!("resampled {}", brdf.describe()),
            data,
            channels: Channels::Rgb,
            sampler: std::sync::OnceLock::new(),
        }
    }
}

/// Points per axis of a cell (`n`; `n`³ points, each evaluated in both orientations for a
/// source not flagged reciprocal). Where f_r has an integrable singularity at the horizon
/// (Ward's 1/√(cos θi cos θo)) too few points make the means noisy: a file written from
/// isotropic Ward (α = 0.3) was 18 % off its source in the grazing band with two points per
/// axis, 5.4 % with three and 5.2 % with five (and 6.5 % from centre samples). For the shipped
/// RGL measurements two and three gave the same figures (BENCHMARKS.md).
pub const POINTS_PER_AXIS: usize = 3;

/// Azimuths φh of the half vector at which an anisotropic source (one not flagged isotropic) is
/// evaluated per point: a MERL cell spans every φh and the reader ignores it, so the file holds
/// the mean over φh. Equally spaced nodes are the trapezoidal rule of a periodic function, exact
/// for its harmonics below this order (the cos 2φh and cos 4φh of an elliptical lobe); each
/// point rotates them by its own offset. (Cells were filled at φh = 0 alone: the file of GGX
/// with α = (0.1, 0.4) was its α_x slice, a third of the φh-mean at θh = 8.6°.)
pub const PHI_H_POINTS: usize = 8;

/// The φh nodes of [`PHI_H_POINTS`], from 0.
const PHI_H_UNIT: [f64; PHI_H_POINTS] = {
    let mut a = [0.0; PHI_H_POINTS];
    let mut j = 0;
    while j < PHI_H_POINTS {
        a[j] = TAU * j as f64 / PHI_H_POINTS as f64;
        j += 1;
    }
    a
};

/// The golden ratio's fractional part, the step of the points' φh offsets.
const GOLDEN: f64 = 0.618_033_988_749_894_8;

/// How a source's channels become the format's RGB: as they are, or (wavelength channels) the
/// projection of their spectrum to linear sRGB, [`crate::colour::srgb_weights`] — the colour a
/// spectral renderer shows, as the RGL reader gives a spectral file for RGB.
fn rgb_weights(channels: &Channels) -> Option<Vec<[f64; 3]>> {
    match channels {
        Channels::Rgb => None,
        Channels::Wavelengths(nm) => Some(crate::colour::srgb_weights(nm)),
    }
}

/// The mean of `brdf`'s f_r over MERL cell (`ith`, `itd`, `ipd`) (see the module docs), per
/// RGB channel (a spectral source's channels projected to linear sRGB, clipped at 0), or `None`
/// when no point of the cell has both directions above the horizon.
pub fn cell_mean(brdf: &dyn Brdf, ith: usize, itd: usize, ipd: usize) -> Option<[f64; 3]> {
    cell_mean_with(brdf, rgb_weights(brdf.channels()).as_deref(), ith, itd, ipd)
}

fn cell_mean_with(
    brdf: &dyn Brdf,
    to_rgb: Option<&[[f64; 3]]>,
    ith: usize,
    itd: usize,
    ipd: usize,
) -> Option<[f64; 3]> {
    let n = POINTS_PER_AXIS;
    let reciprocal = brdf.flags().reciprocal;
    let eval = |wi, wo, f: &mut [f32; 3]| match to_rgb {
        None => brdf.eval(wi, wo, f),
        Some(w) => {
            let mut buf = [0f32; MAX_CHANNELS];
            let k = w.len().min(MAX_CHANNELS);
            brdf.eval(wi, wo, &mut buf[..k]);
            for (c, fc) in f.iter_mut().enumerate() {
                let v: f64 = w.iter().zip(&buf[..k]).map(|(w, &x)| w[c] * x as f64).sum();
                *fc = v.max(0.0) as f32;
            }
        }
    };
    // A cell spans every φh: an isotropic source is the same at all of them, an anisotropic one
    // is averaged over PHI_H_POINTS equally spaced φh per point (rotated from point to point).
    let phi_h: &[f64] = if brdf.flags().isotropic {
        &[0.0]
    } else {
        &PHI_H_UNIT
    };
    let (mut sum, mut weight) = ([0.0f64; 3], 0.0f64);
    let mut add = |w: f64, f: [f32; 3]| {
        for (s, v) in sum.iter_mut().zip(f) {
            *s += w * v as f64;
        }
        weight += w;
    };
    let mut f = [0.0f32; 3];
    // Point k of n across the cell from index i, in index space.
    let at = |i: usize, k: usize| i as f64 + (k as f64 + 0.5) / n as f64;
    for a in 0..n {
        let uh = at(ith, a) / RES_THETA_H as f64;
        let theta_h = uh * uh * FRAC_PI_2;
        for b in 0..n {
            let theta_d = at(itd, b) / RES_THETA_D as f64 * FRAC_PI_2;
            // The pair measure 4 cos θd dωh dωd on the index axes (constant factors dropped).
            let measure = theta_d.cos() * theta_d.sin() * theta_h.sin() * uh;
            for c in 0..n {
                let phi_d = at(ipd, c) / RES_PHI_D as f64 * PI;
                // The point's own rotation of the φh nodes (a golden-ratio sequence over the
                // points), so that a cell sees n³ · PHI_H_POINTS distinct φh.
                let k = (a * n + b) * n + c;
                let shift = (k as f64 * GOLDEN).fract() * TAU / PHI_H_POINTS as f64;
                for &phi_h in phi_h {
                    let hd = HalfDiff {
                        theta_h,
                        phi_h: phi_h + shift,
                        theta_d,
                        phi_d,
                    };
                    let (wi, wo) = geometry::from_half_diff(hd);
                    if !(wi.z > 0.0 && wo.z > 0.0 && measure > 0.0) {
                        continue;
                    }
                    eval(wi, wo, &mut f);
                    if reciprocal {
                        // Both orientations have this f_r: their weights cos θo and cos θi at once.
                        add(measure * (wo.z + wi.z), f);
                    } else {
                        add(measure * wo.z, f);
                        eval(wo, wi, &mut f);
                        add(measure * wi.z, f);
                    }
                }
            }
        }
    }
    (weight > 0.0).then(|| sum.map(|s| s / weight))
}
