//! Where a written file's incident elevations go: placed where the file's own reader is
//! farthest from the source.
//!
//! A `.bsdf` reader interpolates the stored values linearly in θi between two incident slices,
//! at the same point of their warps' input squares. How far apart the slices may be depends on
//! the source: a Lambertian's interpolation error is largest near normal incidence, a rough
//! conductor's near grazing, where its lobe runs into the horizon. One spacing for every
//! source cannot serve both (16 elevations even in cos θi: Cook-Torrance gold's albedo 4.5 % off
//! at 89°; even in θi: its grazing band 10 %, BENCHMARKS.md "Written files placed where they
//! are wrong").
//!
//! [`place`] starts from [`START`] elevations even in cos θi (the count written before) and,
//! one step at a time, writes the file in memory, reads it back with brdftab's RGL reader and
//! measures it against the source on each interval between elevations and at each elevation —
//! the figures of [`analysis::fidelity`](crate::analysis::fidelity): the cos θi cos θo-weighted
//! relative RMSE within 80°, over the whole hemisphere and over the grazing band (pairs uniform
//! in solid angle, half of them drawn near the mirror direction and weighted back), and the
//! directional albedo at the whole degrees inside the interval. Of the figures past
//! [`MARGIN`] × their bar ([`BARS`]) whose error is not mostly what the slices themselves give
//! (more elevations cannot lower that part; [`IMPROVABLE`]), the one farthest past its bar
//! decides: the interval whose error there exceeds its slices' the most is split in the middle
//! (in θi). It stops when no figure qualifies or at the most elevations allowed. A split
//! changes the reader only between the two slices around it, so only the two new intervals and
//! the new elevation are measured, and every slice is encoded once.

mod readback;

use readback::WHOLE_CIRCLE;
pub(super) use readback::{Azimuths, measure};

use std::collections::HashMap;
use std::f64::consts::{PI, TAU};

use super::ndf::Ndf;
use super::{Layout, Progress, report, values, warps};
use crate::brdf::Brdf;
use crate::error::Result;
use crate::measured::RglBrdf;
use crate::measured::tensor::TensorFile;
use crate::progress::Quiet;

/// Elevations placement starts from (even in cos θi).
pub const START: usize = 16;

/// The most elevations [`place`] uses by default.
pub const MAX: usize = 32;

/// The bars, relative: within 80°, whole hemisphere, grazing band (cos θi cos θo-weighted
/// relative RMSEs) and directional albedo (a channel darker than [`DARK_FLOOR`] judged
/// against it) — those of the measured tables (issue 22).
pub const BARS: [f64; 4] = [0.01, 0.015, 0.03, 0.01];

/// Placement stops when every figure is within this fraction of its bar (the per-interval
/// estimates are noisier than the final report's).
pub const MARGIN: f64 = 0.7;

/// Albedos darker than this are judged against it.
pub const DARK_FLOOR: f64 = 0.02;

/// A figure is worth splitting for while more than this fraction of it lies above what its
/// slices alone give.
pub const IMPROVABLE: f64 = 0.1;

/// The closest two elevations may be (radians): a reader's slices 0.25° apart already
/// interpolate the last degree before the horizon in four steps.
pub const MIN_STEP: f64 = 0.25 * PI / 180.0;

/// Pairs drawn per interval and step.
pub(super) const PAIRS: usize = 3000;

/// Angle of the cone about the mirror direction that half the pairs are drawn in (radians):
/// a sharp lobe is then seen on every step, not by lottery.
const CONE: f64 = 20.0 * PI / 180.0;

/// What one interval between elevations measured: squared errors and squared references of
/// f_r cos θi cos θo (within 80°, whole, grazing band), integrated over the interval's
/// incidences, and the worst albedo error at the whole degrees inside it (its middle when
/// there are none). For one elevation alone (θi exactly there) the same per unit solid angle.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Errors {
    pub(super) err: [f64; 3],
    pub(super) reference: [f64; 3],
    pub(super) albedo: f64,
}

/// The four figures divided by their bars, and the part of each that splitting cannot lower:
/// what the slices themselves give.
pub(super) fn figures(iv: &[Errors], floors: &[Errors]) -> ([f64; 4], [f64; 4]) {
    let (mut fig, mut floor) = ([0.0; 4], [0.0; 4]);
    for (k, bar) in BARS.iter().enumerate().take(3) {
        let e: f64 = iv.iter().map(|i| i.err[k]).sum();
        let f: f64 = floors.iter().map(|i| i.err[k]).sum();
        let r: f64 = iv.iter().map(|i| i.reference[k]).sum();
        if r > 0.0 {
            fig[k] = (e / r).sqrt() / bar;
            floor[k] = (f.min(e) / r).sqrt() / bar;
        }
    }
    fig[3] = iv.iter().map(|i| i.albedo).fold(0.0, f64::max) / BARS[3];
    floor[3] = floors.iter().map(|i| i.albedo).fold(0.0, f64::max) / BARS[3];
    (fig, floor)
}

/// The slice-limited errors of the interval between elevations `ta` and `tb`: the mean of the
/// two slices' densities over the interval's solid angle, the larger albedo error.
fn floor_of(a: &Errors, b: &Errors, ta: f64, tb: f64) -> Errors {
    floor_over(a, b, TAU * (ta.cos() - tb.cos()))
}

/// The slice-limited errors of a cell of solid angle `measure` between two slices (or rows of
/// slices) whose densities are `a` and `b`.
pub(super) fn floor_over(a: &Errors, b: &Errors, measure: f64) -> Errors {
    let mut out = Errors::default();
    for k in 0..3 {
        out.err[k] = measure * 0.5 * (a.err[k] + b.err[k]);
        out.reference[k] = measure * 0.5 * (a.reference[k] + b.reference[k]);
    }
    out.albedo = a.albedo.max(b.albedo);
    out
}

/// One elevation's encoded slices (every azimuth): VNDF densities, values and validity.
pub(super) struct Slice {
    pub(super) vndf: Vec<f32>,
    pub(super) values: Vec<f32>,
    pub(super) valid: Vec<bool>,
}

/// What [`place`] chose and measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// The elevations in increasing order (radians), the first 0 and the last 90°.
    pub theta_i: Vec<f32>,
    /// Its estimates of the four figures (within 80°, whole, grazing band, albedo), each
    /// divided by its bar ([`BARS`]).
    pub figures: [f64; 4],
    /// The part of each that the slices themselves give (more elevations cannot lower it; a
    /// finer table can).
    pub floors: [f64; 4],
}

impl Placement {
    /// Whether a figure stays past its bar: the slices alone keep it there, or the most
    /// elevations allowed did not bring it down.
    pub fn past_bar(&self) -> bool {
        self.worst() > 1.0
    }

    /// The largest of the four figures (each divided by its bar).
    pub fn worst(&self) -> f64 {
        self.figures.iter().fold(0.0, |m, &f| m.max(f))
    }
}

/// Chooses the incident elevations for `brdf` (at most `max`, at least [`START`]), with `base`
/// giving every other part of the layout.
pub fn place(
    brdf: &dyn Brdf,
    ndf: &Ndf,
    base: &Layout,
    max: usize,
    progress: &dyn Progress,
) -> Result<Placement> {
    let start = START.min(max).max(2);
    let mut theta: Vec<f64> = (0..start)
        .map(|k| (1.0 - k as f64 / (start - 1) as f64).clamp(0.0, 1.0).acos())
        .collect();
    let mut cache: HashMap<u64, Slice> = HashMap::new();
    let _stage = crate::progress::Stage::begin(progress, "placing elevations", max as u64);
    let mut file = reader(brdf, ndf, base, &theta, &mut cache, progress)?;
    let check = || crate::progress::check(progress);
    let mut at: Vec<Errors> = (0..theta.len())
        .map(|k| {
            check()?;
            Ok(measure(
                &file,
                brdf,
                theta[k],
                theta[k],
                &WHOLE_CIRCLE,
                k as u64,
            ))
        })
        .collect::<Result<_>>()?;
    let mut iv: Vec<Errors> = (0..theta.len() - 1)
        .map(|k| {
            check()?;
            Ok(measure(
                &file,
                brdf,
                theta[k],
                theta[k + 1],
                &WHOLE_CIRCLE,
                100 + k as u64,
            ))
        })
        .collect::<Result<_>>()?;
    let floors = |theta: &[f64], at: &[Errors]| -> Vec<Errors> {
        (0..theta.len() - 1)
            .map(|k| floor_of(&at[k], &at[k + 1], theta[k], theta[k + 1]))
            .collect()
    };
    loop {
        progress.set(theta.len() as u64);
        crate::progress::check(progress)?;
        let fl = floors(&theta, &at);
        let (fig, floor) = figures(&iv, &fl);
        let done = Placement {
            theta_i: theta.iter().map(|&t| t as f32).collect(),
            figures: fig,
            floors: floor,
        };
        if theta.len() >= max {
            return Ok(done);
        }
        // The figure farthest past its bar among those that splitting can still lower.
        let Some(worst) = (0..4)
            .filter(|&k| fig[k] > MARGIN && fig[k] - floor[k] > IMPROVABLE * fig[k])
            .max_by(|&a, &b| fig[a].total_cmp(&fig[b]))
        else {
            return Ok(done);
        };
        let gain = |j: usize| match worst {
            3 => iv[j].albedo - fl[j].albedo,
            k => iv[j].err[k] - fl[j].err[k],
        };
        let Some(j) = (0..iv.len())
            .filter(|&k| theta[k + 1] - theta[k] > 2.0 * MIN_STEP)
            .max_by(|&a, &b| gain(a).total_cmp(&gain(b)))
        else {
            return Ok(done);
        };
        let mid = 0.5 * (theta[j] + theta[j + 1]);
        theta.insert(j + 1, mid);
        file = reader(brdf, ndf, base, &theta, &mut cache, progress)?;
        let seed = theta.len() as u64 * 1000;
        check()?;
        at.insert(j + 1, measure(&file, brdf, mid, mid, &WHOLE_CIRCLE, seed));
        check()?;
        let left = measure(&file, brdf, theta[j], mid, &WHOLE_CIRCLE, seed + 1);
        check()?;
        let right = measure(&file, brdf, mid, theta[j + 2], &WHOLE_CIRCLE, seed + 2);
        iv.splice(j..=j, [left, right]);
    }
}

/// The file of `base` with elevations `theta`, read back by brdftab's RGL reader; slices
/// not in `cache` are encoded and kept there (`progress` asked to stop as each is sampled).
fn reader(
    brdf: &dyn Brdf,
    ndf: &Ndf,
    base: &Layout,
    theta: &[f64],
    cache: &mut HashMap<u64, Slice>,
    progress: &dyn Progress,
) -> Result<RglBrdf> {
    let nch = brdf.channels().len();
    let (np, n) = (base.phi_i.len(), base.n);
    let plane = n * n;
    let vplane = base.vndf[0] * base.vndf[1];
    for &t in theta {
        if cache.contains_key(&t.to_bits()) {
            continue;
        }
        let layout = Layout {
            theta_i: vec![t as f32],
            ..base.clone()
        };
        let w = warps::vndf(ndf, &layout)?;
        let v = values::sample(brdf, ndf, &w, &layout, None, &Quiet(progress))?;
        let valid = super::container::unpack_bits(&v.valid, np * plane);
        cache.insert(
            t.to_bits(),
            Slice {
                vndf: w.data,
                values: v.data,
                valid,
            },
        );
    }
    let nt = theta.len();
    let mut vndf = Vec::with_capacity(np * nt * vplane);
    let mut data = Vec::with_capacity(np * nt * nch * plane);
    let mut valid = Vec::with_capacity(np * nt * plane);
    for p in 0..np {
        for &t in theta {
            let s = &cache[&t.to_bits()];
            vndf.extend_from_slice(&s.vndf[p * vplane..(p + 1) * vplane]);
            data.extend_from_slice(&s.values[p * nch * plane..(p + 1) * nch * plane]);
            valid.extend_from_slice(&s.valid[p * plane..(p + 1) * plane]);
        }
    }
    let layout = Layout {
        theta_i: theta.iter().map(|&t| t as f32).collect(),
        ..base.clone()
    };
    let values = super::Values {
        data,
        valid: super::container::pack_bits(&valid),
    };
    let fields = super::fields_of(String::new(), &layout, ndf, vndf, values, brdf.channels());
    let tf = TensorFile::from_bytes("(placing elevations)", fields.to_bytes())?;
    RglBrdf::from_tensor_unhashed(&tf)
}

#[cfg(test)]
mod tests;
