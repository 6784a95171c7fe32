//! The microfacet NDF of any source, recovered from its retro-reflection by power iteration
//! (Dupuy, Heitz, Iehl, Poulin, Ostromoukhov, "Extracting Microfacet-based BRDF Parameters from
//! Arbitrary Materials with Power Iterations", 2015), and its projected area σ.
//!
//! For a microfacet BRDF at retro-reflection (ωi = ωo = ω, so h = ω and masking equals
//! shadowing), f(ω, ω) = F D(ω) G1(ω) / (4 cos² θ) with G1(ω) = cos θ / σ(ω) and
//! σ(ω) = ∫ D(m) max(0, m·ω) dm. Up to the (nearly constant) Fresnel factor,
//!
//! ```text
//! D(ω) ∝ f(ω, ω) cos θ σ(ω)   — D is the dominant eigenvector of the operator on the right.
//! ```
//!
//! Iterating D ← f(ω, ω) cos θ σ_D(ω), normalized to ∫ D cos θ dω = 1 (so σ(normal) = 1, as in
//! the published files), converges to it. The source's luminance (Rec. 709 Y; for spectra the
//! photometric Y under D65, [`luminance_weights`]) stands for f; where f(ω, ω) is 0 (a hole in measured data) the mean of four
//! pairs 2° from retro-reflection stands in. Any source works — for non-microfacet ones D is simply an adapted
//! sampling density — because the values stored later are divided by the same tables.
//!
//! The tables live on the readers' unit square: column u = sqrt(2θ/π), row v = (φ + π)/2π,
//! interpolated bilinearly. σ and the iteration integrate with the midpoint rule over that square
//! (dω = 2π² u sin θ du dv).

use std::f64::consts::{FRAC_PI_2, PI};

use glam::DVec3;
use rayon::prelude::*;

use super::Layout;
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::geometry;
use crate::spectrum::{Channels, MAX_CHANNELS};

/// Largest incident elevation at which the source is evaluated (radians): at exactly 90° every
/// BRDF is 0 by convention.
pub const MAX_EVAL_THETA: f64 = 89.5 * PI / 180.0;

/// Angle of the near-retro pairs used where f(ω, ω) itself is 0 (radians).
pub const NEAR_RETRO: f64 = 2.0 * PI / 180.0;

/// Floor of D relative to its maximum, so that warps cover the whole hemisphere.
pub const NDF_FLOOR: f64 = 1e-5;

/// The fraction of what each incidence needs that D is raised to (isotropic sources, see
/// [`recover`]). The recovered D of Lambert, Cook-Torrance gold, GGX copper and Lambert + GGX
/// gives every incidence up to 80° at least 1/2.5 of its need, so at a tenth their files are
/// untouched (at a quarter gold's error within 80° grew from 0.31 to 0.42 %); reciprocal
/// Phong's need is 1.3·10⁴ × its recovered (floored) D, and its error within 80° fell from 4.7
/// to 1.1 %.
pub const COVERAGE: f64 = 0.1;

/// Incidences at which `coverage` looks (even in θi from 0 to [`COVERAGE_MAX_THETA`]).
const COVERAGE_INCIDENCES: usize = 32;

/// The most grazing incidence whose need [`recover`] looks at (radians): beyond 80° a measured
/// file's cells next to the horizon (f_r growing like 1/cos θ) claimed the warp — a MERL file
/// of Lambert + Cook-Torrance went from 1.2 % to 2.6 % within 80° with incidences up to 89.5° —
/// while Phong's lobe needs covering well before (1.0 % within 80° up to 80°, 1.5 % to 89.5°).
pub const COVERAGE_MAX_THETA: f64 = 80.0 * PI / 180.0;

/// Power iteration stops when the largest change relative to the maximum falls below this.
pub const TOLERANCE: f64 = 1e-5;

/// The recovered distribution and projected area, on `ny` rows (φ) × `nx` columns (θ).
#[derive(Debug, Clone)]
pub struct Ndf {
    /// Columns (elevations).
    pub nx: usize,
    /// Rows (azimuths; 2 identical rows when isotropic).
    pub ny: usize,
    /// Isotropic: rows identical, azimuths relative to φi.
    pub isotropic: bool,
    /// D at the nodes, row-major.
    pub ndf: Vec<f32>,
    /// σ at the nodes, row-major.
    pub sigma: Vec<f32>,
    /// Iterations run.
    pub iterations: usize,
    /// Final relative change (below [`TOLERANCE`] when converged).
    pub change: f64,
}

/// Bilinear interpolation of a `ny` × `nx` row-major table at unit point `u` = (column, row),
/// exactly as the readers interpolate `ndf` and `sigma`.
#[inline]
pub fn bilinear(t: &[f32], nx: usize, ny: usize, u: [f64; 2]) -> f64 {
    let locate = |u: f64, n: usize| {
        let p = u * (n - 1) as f64;
        let i = if p > 0.0 { (p as usize).min(n - 2) } else { 0 };
        (i, p - i as f64)
    };
    let (ix, fx) = locate(u[0], nx);
    let (iy, fy) = locate(u[1], ny);
    let o = ix + iy * nx;
    let v = |k: usize| t[k] as f64;
    (1.0 - fy) * ((1.0 - fx) * v(o) + fx * v(o + 1))
        + fy * ((1.0 - fx) * v(o + nx) + fx * v(o + nx + 1))
}

impl Ndf {
    /// The tables of an existing parameterization.
    pub fn given(p: &super::Parameterization, isotropic: bool) -> Self {
        Ndf {
            nx: p.ndf_shape[1],
            ny: p.ndf_shape[0],
            isotropic,
            ndf: p.ndf.clone(),
            sigma: p.sigma.clone(),
            iterations: 0,
            change: 0.0,
        }
    }

    /// D at unit point `u` (bilinear).
    #[inline]
    pub fn d(&self, u: [f64; 2]) -> f64 {
        bilinear(&self.ndf, self.nx, self.ny, u)
    }

    /// σ at unit point `u` (bilinear).
    #[inline]
    pub fn sigma(&self, u: [f64; 2]) -> f64 {
        bilinear(&self.sigma, self.nx, self.ny, u)
    }
}

/// Scalar weights turning a channel vector into the luminance used for D and for sampling:
/// Rec. 709 Y of RGB; of sampled spectra, the photometric Y of the spectrum they sample under
/// D65 (the same Y of its projection to linear sRGB, [`crate::colour::srgb_weights`]; the
/// weights sum to 1), so that a renderer samples a spectral file by what it shows.
pub fn luminance_weights(channels: &Channels) -> Vec<f64> {
    const Y: [f64; 3] = [0.2126, 0.7152, 0.0722];
    match channels {
        Channels::Rgb => Y.to_vec(),
        c => {
            let nm: Vec<f64> = (0..c.len()).map(|i| c.wavelength(i)).collect();
            crate::colour::srgb_weights(&nm)
                .iter()
                .map(|w| (Y[0] * w[0] + Y[1] * w[1] + Y[2] * w[2]).max(0.0))
                .collect()
        }
    }
}

/// The direction of node (column `ix` of `nx`, row `iy` of `ny`).
fn node_dir(ix: usize, nx: usize, iy: usize, ny: usize) -> (f64, f64) {
    let u = ix as f64 / (nx - 1) as f64;
    let v = iy as f64 / (ny - 1) as f64;
    (u * u * FRAC_PI_2, 2.0 * PI * v - PI)
}

/// Midpoint quadrature of the unit square: directions, dω weights and unit coordinates.
struct Quadrature {
    dirs: Vec<DVec3>,
    weights: Vec<f64>,
    uv: Vec<[f64; 2]>,
}

fn quadrature(qt: usize, qp: usize) -> Quadrature {
    let mut q = Quadrature {
        dirs: Vec::with_capacity(qt * qp),
        weights: Vec::with_capacity(qt * qp),
        uv: Vec::with_capacity(qt * qp),
    };
    for b in 0..qp {
        let v = (b as f64 + 0.5) / qp as f64;
        for a in 0..qt {
            let u = (a as f64 + 0.5) / qt as f64;
            let theta = u * u * FRAC_PI_2;
            q.dirs.push(geometry::spherical(theta, 2.0 * PI * v - PI));
            q.weights
                .push(2.0 * PI * PI * u * theta.sin() / (qt * qp) as f64);
            q.uv.push([u, v]);
        }
    }
    q
}

/// Retro-reflection luminance f(ω, ω) at every node (rows of an isotropic source are equal).
fn retro(brdf: &dyn Brdf, nx: usize, ny: usize, isotropic: bool) -> Result<Vec<f64>> {
    let wts = luminance_weights(brdf.channels());
    let c = wts.len();
    let rows = if isotropic { 1 } else { ny };
    let mut out = vec![0.0; nx * ny];
    let mut f = [0.0f32; MAX_CHANNELS];
    for iy in 0..rows {
        for ix in 0..nx {
            let (theta, phi) = node_dir(ix, nx, iy, ny);
            let phi = if isotropic { 0.0 } else { phi };
            let w = geometry::spherical(theta.min(MAX_EVAL_THETA), phi);
            let mut lum = |wo: DVec3| -> Result<f64> {
                brdf.eval(w, wo, &mut f[..c]);
                let mut y = 0.0;
                for k in 0..c {
                    let v = f[k] as f64;
                    if !v.is_finite() {
                        return Err(Error::arg(
                            "source",
                            format!(
                                "the source returns {v} near the retro-reflection θ = {:.2}°, φ = {:.2}°",
                                theta.to_degrees(),
                                phi.to_degrees()
                            ),
                        ));
                    }
                    y += wts[k] * v.max(0.0);
                }
                Ok(y)
            };
            let mut y = lum(w)?;
            if y <= 0.0 {
                // A hole exactly at retro-reflection (e.g. unmeasured MERL cells, which the
                // lookup hits for every θ at θd = 0): the mean of the four pairs 2° away.
                let frame = geometry::Frame::from_normal(w);
                let (s, co) = NEAR_RETRO.sin_cos();
                let mut sum = 0.0;
                for (dx, dy) in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)] {
                    sum += lum(frame.to_world(DVec3::new(dx * s, dy * s, co)))?;
                }
                y = 0.25 * sum;
            }
            out[ix + iy * nx] = y;
        }
    }
    if isotropic {
        let (first, rest) = out.split_at_mut(nx);
        for row in rest.chunks_mut(nx) {
            row.copy_from_slice(first);
        }
    }
    Ok(out)
}

/// σ at every node for the distribution `d_q` given at the quadrature points.
fn project(q: &Quadrature, d_q: &[f64], nx: usize, ny: usize, isotropic: bool) -> Vec<f64> {
    let rows = if isotropic { 1 } else { ny };
    let mut s: Vec<f64> = crate::par::install(|| {
        (0..nx * rows)
            .into_par_iter()
            .map(|k| {
                let (ix, iy) = (k % nx, k / nx);
                let (theta, phi) = node_dir(ix, nx, iy, ny);
                let w = geometry::spherical(theta, if isotropic { 0.0 } else { phi });
                let mut acc = 0.0;
                for ((m, &wt), &d) in q.dirs.iter().zip(&q.weights).zip(d_q) {
                    acc += wt * d * m.dot(w).max(0.0);
                }
                acc
            })
            .collect()
    });
    if isotropic {
        let first = s.clone();
        s.extend_from_slice(&first);
        s.truncate(nx * ny);
    }
    s
}

/// Runs the power iteration for `brdf` on the layout's NDF grid. For an isotropic source, D is
/// then raised to [`COVERAGE`] of what any incidence up to [`COVERAGE_MAX_THETA`] needs for its
/// visible normals to follow its f_r cos θo, and floored at [`NDF_FLOOR`] of its maximum.
pub fn recover(brdf: &dyn Brdf, layout: &Layout) -> Result<Ndf> {
    let (nx, ny, iso) = (layout.ndf_nx, layout.ndf_ny, layout.isotropic);
    let f = retro(brdf, nx, ny, iso)?;
    // Zeros from a source that failed while it was read (a corrupt table chunk) are that
    // failure, not a black material.
    brdf.health()?;
    let fmax = f.iter().cloned().fold(0.0, f64::max);
    if fmax <= 0.0 {
        return Err(Error::arg(
            "source",
            "the source reflects nothing back along any incident direction (retro-reflection is 0 everywhere): no NDF to recover",
        ));
    }
    let (qt, qp) = if iso { (nx, 64) } else { (nx.min(64), 64) };
    let q = quadrature(qt, qp);
    let at_q = |d: &[f32]| -> Vec<f64> { q.uv.iter().map(|&u| bilinear(d, nx, ny, u)).collect() };
    let normalize = |d: &mut Vec<f32>| {
        let dq = at_q(d);
        let s: f64 = q
            .dirs
            .iter()
            .zip(&q.weights)
            .zip(&dq)
            .map(|((m, w), d)| w * d * m.z)
            .sum();
        if s > 0.0 && s.is_finite() {
            d.iter_mut().for_each(|v| *v = (*v as f64 / s) as f32);
        }
    };
    let cos: Vec<f64> = (0..nx * ny)
        .map(|k| node_dir(k % nx, nx, k / nx, ny).0.cos().max(0.0))
        .collect();
    let mut d = vec![(1.0 / PI) as f32; nx * ny];
    let max_it = if iso { 200 } else { 32 };
    let (mut iterations, mut change) = (0, f64::INFINITY);
    while iterations < max_it && change > TOLERANCE {
        let sigma = project(&q, &at_q(&d), nx, ny, iso);
        let mut next: Vec<f32> = (0..nx * ny)
            .map(|k| (f[k] * cos[k] * sigma[k]) as f32)
            .collect();
        normalize(&mut next);
        let dmax = next.iter().cloned().fold(0.0f32, f32::max) as f64;
        change = next
            .iter()
            .zip(&d)
            .map(|(a, b)| (*a as f64 - *b as f64).abs())
            .fold(0.0, f64::max)
            / dmax.max(1e-300);
        d = next;
        iterations += 1;
    }
    if d.iter().any(|v| !v.is_finite()) || d.iter().all(|&v| v <= 0.0) {
        return Err(Error::arg(
            "source",
            "power iteration on the retro-reflection gave no usable NDF",
        ));
    }
    if iso {
        // Raise D where some incidence's reflectance needs more visible normals than the
        // retro-reflection gave (a non-microfacet lobe, e.g. Phong's, widens with θi).
        let sigma = project(&q, &at_q(&d), nx, ny, iso);
        let need = coverage(brdf, nx, ny, &sigma)?;
        for (k, v) in d.iter_mut().enumerate() {
            *v = v.max((COVERAGE * need[k % nx]) as f32);
        }
        normalize(&mut d);
    }
    let dmax = d.iter().cloned().fold(0.0f32, f32::max);
    let floor = (dmax as f64 * NDF_FLOOR) as f32;
    d.iter_mut().for_each(|v| *v = v.max(floor));
    normalize(&mut d);
    let sigma: Vec<f32> = project(&q, &at_q(&d), nx, ny, iso)
        .into_iter()
        .map(|s| s as f32)
        .collect();
    Ok(Ndf {
        nx,
        ny,
        isotropic: iso,
        ndf: d,
        sigma,
        iterations,
        change,
    })
}

/// Per NDF column (θm) of an isotropic source: the largest D that any incidence needs for its
/// visible normals to follow the source's f_r cos θo over half vectors. The density of f_r cos θo
/// over half vectors m for incidence ωi is p(m) ∝ f_r(ωi, ωo) cos θo · 4 (ωo·m) (ωo = ωi
/// reflected about m); the readers' warp samples m with density D(m) (m·ωi) / σ(ωi), so the
/// D that matches p is p(m) σ(ωi) / (m·ωi), normalized. For a microfacet source that is its D
/// (up to G and F); for a lobe shaped around the mirror direction it widens with θi, where the
/// retro-reflection's D (its shape at ωi = ωo) is orders of magnitude too small and the file's
/// cells there grow over a whole lobe.
fn coverage(brdf: &dyn Brdf, nx: usize, ny: usize, sigma: &[f64]) -> Result<Vec<f64>> {
    let wts = luminance_weights(brdf.channels());
    let c = wts.len();
    let q = quadrature(nx, 64);
    let sig: Vec<f32> = sigma.iter().map(|&v| v as f32).collect();
    let rows: Vec<Vec<f64>> = crate::par::install(|| {
        (0..COVERAGE_INCIDENCES)
            .into_par_iter()
            .map(|k| {
                let ti = COVERAGE_MAX_THETA * k as f64 / (COVERAGE_INCIDENCES - 1) as f64;
                let wi = geometry::spherical(ti, 0.0);
                let mut f = [0.0f32; MAX_CHANNELS];
                let mut p = vec![0.0f64; q.dirs.len()];
                let mut total = 0.0;
                for (j, m) in q.dirs.iter().enumerate() {
                    let wo = geometry::reflect(wi, *m);
                    if wo.z <= 0.0 {
                        continue;
                    }
                    brdf.eval(wi, wo, &mut f[..c]);
                    let y: f64 = (0..c).map(|ch| wts[ch] * (f[ch] as f64).max(0.0)).sum();
                    let v = y * wo.z * 4.0 * wo.dot(*m).max(0.0);
                    if v.is_finite() {
                        p[j] = v;
                        total += v * q.weights[j];
                    }
                }
                let mut need = vec![0.0f64; nx];
                if total > 0.0 && total.is_finite() {
                    let u = [(ti / FRAC_PI_2).sqrt(), 0.5];
                    let s = bilinear(&sig, nx, ny, u);
                    for (j, m) in q.dirs.iter().enumerate() {
                        // Half vectors nearly perpendicular to ωi reflect it below the horizon
                        // (p = 0) or just above it; the floor keeps the quotient bounded there.
                        let x = p[j] / total * s / m.dot(wi).max(0.05);
                        need[j % nx] = need[j % nx].max(x);
                    }
                }
                need
            })
            .collect()
    });
    Ok((0..nx)
        .map(|ix| rows.iter().map(|r| r[ix]).fold(0.0, f64::max))
        .collect())
}
