//! Where an anisotropic file's incident azimuths and elevations go: placed together where the
//! file's own reader is farthest from the source.
//!
//! An anisotropic `.bsdf` file stores slices on a product grid of incident azimuths φi and
//! elevations θi, and its readers (brdftab's, Mitsuba 3's `measured`, pbrt-v4's
//! `MeasuredBxDF`) find the interval around a direction's φi and θi by binary search over the
//! stored values and interpolate linearly in both: neither needs to be even, provided the
//! azimuths run from −π to π (the readers derive a symmetry reduction from their span, and
//! pbrt-v4 takes none but 1). Unlike an isotropic file, whose half vectors are stored relative
//! to φi, an anisotropic file's are absolute: two slices a step apart in φi store, at one point
//! of their warps, the same half vector for incidences a step apart, so the outgoing directions
//! they were evaluated at differ, most near the horizon. That interpolation, not the one over
//! θi, is where an anisotropic file's error is (BENCHMARKS.md "Anisotropic files placed over
//! azimuths and elevations").
//!
//! [`place`] extends [`elevations::place`] to the grid: from
//! [`START_PHI`] azimuths evenly over [−π, π] and [`elevations::START`] elevations even in
//! cos θi, it writes the file in memory, reads it back and measures every cell (an azimuth
//! interval × an elevation interval), every elevation over each azimuth interval and every
//! azimuth over each elevation interval, with the figures of `elevations` (the light of the
//! cell's albedo at its middle azimuth). The figure farthest past its bar, where more slices
//! can lower it, decides: of splitting an elevation interval (a slice per azimuth) or an
//! azimuth interval (a slice per elevation), the one whose error above its slices' is largest
//! per slice added is split in the middle — for a bilateral source (unchanged under φ → −φ of
//! both directions) together with its mirror image, so that the file keeps the symmetry the
//! estimates' noise alone would break. It stops when no figure qualifies or when no split fits
//! `max_slices`.

mod grid;
mod slices;

use grid::{Grid, Job, run};
pub use slices::Encoded;
use slices::{encoded, reader};

use std::collections::HashMap;
use std::f64::consts::PI;

use super::elevations::{self, Errors, IMPROVABLE, MARGIN, MIN_STEP, Placement, Slice, figures};
use super::ndf::Ndf;
use super::{Layout, Progress, Values, container, fields_of};
use crate::brdf::Brdf;
use crate::error::Result;

/// Azimuths placement starts from (evenly over [−π, π], both ends included: 8 intervals).
pub const START_PHI: usize = 9;

/// The albedo quadrature of the measurements (azimuths about the mirror direction, nodes per
/// segment): a quarter of the evaluations of the isotropic placement's, which measures far
/// fewer cells.
const ALBEDO_RULE: [usize; 2] = [64, 4];

/// The closest two azimuths may be (radians).
pub const MIN_PHI_STEP: f64 = 0.5 * PI / 180.0;

/// The incident azimuths `n` evenly over [−π, π] (both ends).
pub fn even_azimuths(n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| -PI + 2.0 * PI * k as f64 / (n - 1) as f64)
        .collect()
}

/// Chooses the incident azimuths and elevations of an anisotropic `brdf` (at most
/// `max_slices` slices), with `base` giving every other part of the layout. Returns the
/// placement (its `theta_i`), the azimuths, and the chosen grid's VNDF slices and values as
/// placement encoded them (φi-major, the file's order), which are the file's: each slice is
/// encoded alone, as [`warps::vndf`](super::warps::vndf) and
/// [`values::sample`](super::values::sample) encode it in the whole layout.
pub fn place(
    brdf: &dyn Brdf,
    ndf: &Ndf,
    base: &Layout,
    max_slices: usize,
    progress: &dyn Progress,
) -> Result<(Placement, Vec<f32>, Encoded)> {
    let nt0 = elevations::START;
    let mut g = Grid {
        phi: even_azimuths(START_PHI),
        theta: (0..nt0)
            .map(|k| (1.0 - k as f64 / (nt0 - 1) as f64).clamp(0.0, 1.0).acos())
            .collect(),
        cell: Vec::new(),
        at_theta: Vec::new(),
        at_phi: Vec::new(),
    };
    let mut cache: HashMap<(u64, u64), Slice> = HashMap::new();
    let _stage = crate::progress::Stage::begin(
        progress,
        "placing azimuths and elevations",
        max_slices as u64,
    );
    let mut file = reader(brdf, ndf, base, &g.phi, &g.theta, &mut cache, progress)?;
    let mirror = brdf.flags().bilateral;
    let (np, nt) = (g.phi.len(), g.theta.len());
    let mut seed = 1u64;
    let mut next_seed = || {
        seed += 1;
        seed
    };
    let jobs: Vec<Job> = (0..np - 1)
        .flat_map(|i| (0..nt - 1).map(move |j| (i, j)))
        .map(|(i, j)| g.cell_job(i, j, next_seed()))
        .collect();
    let r = run(&file, brdf, &jobs, progress)?;
    g.cell = r.chunks(nt - 1).map(<[Errors]>::to_vec).collect();
    let jobs: Vec<Job> = (0..np - 1)
        .flat_map(|i| (0..nt).map(move |j| (i, j)))
        .map(|(i, j)| g.at_theta_job(i, j, next_seed()))
        .collect();
    let r = run(&file, brdf, &jobs, progress)?;
    g.at_theta = r.chunks(nt).map(<[Errors]>::to_vec).collect();
    let jobs: Vec<Job> = (0..np)
        .flat_map(|i| (0..nt - 1).map(move |j| (i, j)))
        .map(|(i, j)| g.at_phi_job(i, j, next_seed()))
        .collect();
    let r = run(&file, brdf, &jobs, progress)?;
    g.at_phi = r.chunks(nt - 1).map(<[Errors]>::to_vec).collect();
    loop {
        crate::progress::check(progress)?;
        let (np, nt) = (g.phi.len(), g.theta.len());
        progress.set((np * nt) as u64);
        let (mut cells, mut floors) = (Vec::new(), Vec::new());
        for i in 0..np - 1 {
            for j in 0..nt - 1 {
                let (ft, fp) = g.floors(i, j);
                let mut f = ft;
                for k in 0..3 {
                    f.err[k] = ft.err[k].min(fp.err[k]);
                }
                f.albedo = ft.albedo.min(fp.albedo);
                cells.push(g.cell[i][j]);
                floors.push(f);
            }
        }
        let (mut fig, floor) = figures(&cells, &floors);
        // The albedo with the light at a stored azimuth is what a renderer sees there too (the
        // fidelity report's φ′ = 0 is one): more elevations lower it.
        let at_nodes = (g.at_phi.iter().flatten()).fold(0.0, |m: f64, e| m.max(e.albedo));
        fig[3] = fig[3].max(at_nodes / elevations::BARS[3]);
        let done = |cache: &HashMap<(u64, u64), Slice>| {
            (
                Placement {
                    theta_i: g.theta.iter().map(|&t| t as f32).collect(),
                    figures: fig,
                    floors: floor,
                },
                g.phi.iter().map(|&p| p as f32).collect::<Vec<f32>>(),
                encoded(&g.phi, &g.theta, cache),
            )
        };
        let Some(worst) = (0..4)
            .filter(|&k| fig[k] > MARGIN && fig[k] - floor[k] > IMPROVABLE * fig[k])
            .max_by(|&a, &b| fig[a].total_cmp(&fig[b]))
        else {
            return Ok(done(&cache));
        };
        let excess = |e: &Errors, f: &Errors| match worst {
            3 => e.albedo - f.albedo,
            k => e.err[k] - f.err[k],
        };
        // Per slice added: an elevation adds one per azimuth, an azimuth one per elevation.
        let by_theta = (0..nt - 1)
            .filter(|&j| {
                g.theta[j + 1] - g.theta[j] > 2.0 * MIN_STEP && (nt + 1) * np <= max_slices
            })
            .map(|j| {
                let gains = (0..np - 1).map(|i| {
                    let mut e = g.cell[i][j];
                    e.albedo = (e.albedo)
                        .max(g.at_phi[i][j].albedo)
                        .max(g.at_phi[i + 1][j].albedo);
                    excess(&e, &g.floors(i, j).0)
                });
                let gain = if worst == 3 {
                    gains.fold(0.0, f64::max)
                } else {
                    gains.sum()
                };
                (gain / np as f64, j)
            })
            .max_by(|a, b| a.0.total_cmp(&b.0));
        // A bilateral source's error at −φi is its error at φi: its azimuths are split in
        // mirrored pairs (the start is even about 0, a node), so that the file keeps the
        // symmetry where the two estimates' noise alone would pick a side.
        let pair = |i: usize| (mirror && np - 2 - i != i).then(|| np - 2 - i);
        let by_phi = (0..np - 1)
            .filter(|&i| {
                let added = if pair(i).is_some() { 2 } else { 1 };
                g.phi[i + 1] - g.phi[i] > 2.0 * MIN_PHI_STEP && (np + added) * nt <= max_slices
            })
            .map(|i| {
                let gain_of = |i: usize| {
                    let gains = (0..nt - 1).map(|j| excess(&g.cell[i][j], &g.floors(i, j).1));
                    if worst == 3 {
                        gains.fold(0.0, f64::max)
                    } else {
                        gains.sum()
                    }
                };
                let gain = match pair(i) {
                    Some(m) => 0.5 * (gain_of(i) + gain_of(m)),
                    None => gain_of(i),
                };
                (gain / nt as f64, i)
            })
            .max_by(|a, b| a.0.total_cmp(&b.0));
        let split_theta = match (by_theta, by_phi) {
            (None, None) => return Ok(done(&cache)),
            (Some((gt, j)), Some((gp, i))) => {
                if gt >= gp {
                    Ok(j)
                } else {
                    Err(i)
                }
            }
            (Some((_, j)), None) => Ok(j),
            (None, Some((_, i))) => Err(i),
        };
        match split_theta {
            Ok(j) => {
                let mid = 0.5 * (g.theta[j] + g.theta[j + 1]);
                g.theta.insert(j + 1, mid);
                file = reader(brdf, ndf, base, &g.phi, &g.theta, &mut cache, progress)?;
                let mut jobs = Vec::new();
                for i in 0..np - 1 {
                    jobs.push(g.cell_job(i, j, next_seed()));
                    jobs.push(g.cell_job(i, j + 1, next_seed()));
                    jobs.push(g.at_theta_job(i, j + 1, next_seed()));
                }
                for i in 0..np {
                    jobs.push(g.at_phi_job(i, j, next_seed()));
                    jobs.push(g.at_phi_job(i, j + 1, next_seed()));
                }
                let r = run(&file, brdf, &jobs, progress)?;
                for i in 0..np - 1 {
                    g.cell[i].splice(j..=j, [r[3 * i], r[3 * i + 1]]);
                    g.at_theta[i].insert(j + 1, r[3 * i + 2]);
                }
                let o = 3 * (np - 1);
                for i in 0..np {
                    g.at_phi[i].splice(j..=j, [r[o + 2 * i], r[o + 2 * i + 1]]);
                }
            }
            Err(i) => {
                // Original indices of the split intervals, ascending; each gains its middle.
                let mut split = vec![i];
                split.extend(pair(i));
                split.sort_unstable();
                for &k in split.iter().rev() {
                    g.phi.insert(k + 1, 0.5 * (g.phi[k] + g.phi[k + 1]));
                }
                file = reader(brdf, ndf, base, &g.phi, &g.theta, &mut cache, progress)?;
                // Per split, at its new index k: both halves' cells and elevations, then the
                // new azimuth over each elevation interval.
                let mut jobs = Vec::new();
                for (n, &k) in split.iter().enumerate() {
                    let k = k + n;
                    for k in [k, k + 1] {
                        for j in 0..nt - 1 {
                            jobs.push(g.cell_job(k, j, next_seed()));
                        }
                        for j in 0..nt {
                            jobs.push(g.at_theta_job(k, j, next_seed()));
                        }
                    }
                    for j in 0..nt - 1 {
                        jobs.push(g.at_phi_job(k + 1, j, next_seed()));
                    }
                }
                let r = run(&file, brdf, &jobs, progress)?;
                let row = (nt - 1) + nt;
                for (n, &k) in split.iter().enumerate().rev() {
                    let r = &r[n * (2 * row + nt - 1)..(n + 1) * (2 * row + nt - 1)];
                    let (left, right) = (&r[..row], &r[row..2 * row]);
                    g.cell
                        .splice(k..=k, [left[..nt - 1].to_vec(), right[..nt - 1].to_vec()]);
                    g.at_theta
                        .splice(k..=k, [left[nt - 1..].to_vec(), right[nt - 1..].to_vec()]);
                    g.at_phi.insert(k + 1, r[2 * row..].to_vec());
                }
            }
        }
    }
}
