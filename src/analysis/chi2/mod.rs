//! Chi-square goodness-of-fit tests for BRDF samplers — the definition of a correct sampler.
//!
//! A sampler is correct when the directions [`Brdf::sample`] draws are distributed with the density
//! [`Brdf::pdf`] reports. The test (after Mitsuba 3's `ChiSquareTest`) draws many samples for a fixed
//! `wo`, histograms `wi` into equal-area bins over the sphere (uniform in cos θ and φ), integrates
//! the pdf over each bin for the expected counts, pools bins whose expected count is below 5, and
//! computes the p-value of Pearson's statistic from the regularized incomplete gamma function.
//! Samples the sampler refuses (`None`) are a bin of their own whose expectation is the pdf mass
//! missing from the sphere, so a pdf that does not integrate to the sampling probability fails too.
//!
//! Use [`sidak`] to correct the significance level when many cases are tested together.

use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

use crate::brdf::Brdf;
use crate::rng::Pcg32;
use crate::spectrum::MAX_CHANNELS;

mod expected;
mod gamma;

pub use expected::{adaptive_simpson, expected_mass};
pub use gamma::{gamma_q, ln_gamma};

/// Settings of a chi-square test.
#[derive(Debug, Clone, Copy)]
pub struct Chi2Options {
    /// Number of samples drawn.
    pub samples: usize,
    /// Bins in cos θ over [−1, 1].
    pub cos_bins: usize,
    /// Bins in φ over [0, 2π).
    pub phi_bins: usize,
    /// Seed of the sample stream.
    pub seed: u64,
    /// Minimum expected count per pooled bin.
    pub min_expected: f64,
}

impl Default for Chi2Options {
    fn default() -> Self {
        Chi2Options {
            samples: 1_000_000,
            cos_bins: 40,
            phi_bins: 80,
            seed: 1,
            min_expected: 5.0,
        }
    }
}

/// The outcome of a chi-square test.
#[derive(Debug, Clone)]
pub struct Chi2Result {
    /// Pearson's statistic Σ (observed − expected)² / expected over the pooled bins.
    pub chi2: f64,
    /// Degrees of freedom (pooled bins − 1).
    pub dof: usize,
    /// Probability of a statistic at least this large if the sampler is correct.
    pub p_value: f64,
    /// Samples the sampler refused (`None`).
    pub refused: usize,
    /// Integral of the pdf over the sphere (should be the fraction of accepted samples).
    pub pdf_integral: f64,
    /// Samples whose reported pdf was not positive and finite, or whose direction was not unit.
    pub invalid: usize,
}

impl Chi2Result {
    /// True when the test passes at significance `alpha` and no sample was invalid.
    pub fn passes(&self, alpha: f64) -> bool {
        self.invalid == 0 && self.p_value > alpha
    }
}

/// Šidák-corrected significance for each of `m` independent tests with overall level `alpha`:
/// 1 − (1 − alpha)^(1/m).
pub fn sidak(alpha: f64, m: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / m.max(1) as f64)
}

fn bin_of(w: DVec3, o: &Chi2Options) -> usize {
    let c = ((w.z + 1.0) * 0.5 * o.cos_bins as f64) as isize;
    let c = c.clamp(0, o.cos_bins as isize - 1) as usize;
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let p = ((phi / (2.0 * PI)) * o.phi_bins as f64) as isize;
    let p = p.clamp(0, o.phi_bins as isize - 1) as usize;
    c * o.phi_bins + p
}

/// Histogram of sampled directions: `(counts per bin, refused, invalid)`.
pub fn histogram<B: Brdf + ?Sized>(
    brdf: &B,
    wo: DVec3,
    o: &Chi2Options,
) -> (Vec<u64>, usize, usize) {
    let nbins = o.cos_bins * o.phi_bins;
    let chunks = 64usize;
    let per = o.samples.div_ceil(chunks);
    let c = brdf.channels().len().min(MAX_CHANNELS);
    let parts: Vec<(Vec<u64>, usize, usize)> = crate::par::install(|| {
        (0..chunks)
            .into_par_iter()
            .map(|k| {
                let mut rng = Pcg32::with_stream(o.seed, k as u64 + 1);
                let mut counts = vec![0u64; nbins];
                let (mut refused, mut invalid) = (0, 0);
                let mut weight = [0.0f32; MAX_CHANNELS];
                let n = per.min(o.samples.saturating_sub(k * per));
                for _ in 0..n {
                    let u = rng.next_dvec2();
                    match brdf.sample(wo, u, &mut weight[..c]) {
                        None => refused += 1,
                        Some(s) => {
                            let ok = s.pdf.is_finite()
                                && s.pdf > 0.0
                                && (s.wi.length() - 1.0).abs() < 1e-6
                                && !s.delta;
                            if ok {
                                counts[bin_of(s.wi, o)] += 1;
                            } else {
                                invalid += 1;
                            }
                        }
                    }
                }
                (counts, refused, invalid)
            })
            .collect()
    });
    let mut counts = vec![0u64; nbins];
    let (mut refused, mut invalid) = (0, 0);
    for (c, r, i) in parts {
        for (a, b) in counts.iter_mut().zip(c) {
            *a += b;
        }
        refused += r;
        invalid += i;
    }
    (counts, refused, invalid)
}

/// Runs the chi-square test of `brdf`'s sampler for outgoing direction `wo`.
pub fn test<B: Brdf + ?Sized>(brdf: &B, wo: DVec3, o: &Chi2Options) -> Chi2Result {
    let (counts, refused, invalid) = histogram(brdf, wo, o);
    let mass = expected_mass(brdf, wo, o);
    let n = o.samples as f64;
    let pdf_integral: f64 = mass.iter().sum();
    // Pairs (observed, expected), the refused samples as their own bin.
    let mut cells: Vec<(f64, f64)> = counts
        .iter()
        .zip(&mass)
        .map(|(&c, &m)| (c as f64, m * n))
        .collect();
    cells.push((refused as f64, (1.0 - pdf_integral).max(0.0) * n));
    // Pool small expected counts: sort by expectation, merge the smallest until ≥ min_expected.
    cells.sort_by(|a, b| a.1.total_cmp(&b.1));
    let mut chi2 = 0.0;
    let mut dof: isize = -1;
    let (mut po, mut pe) = (0.0, 0.0);
    for (obs, exp) in cells {
        if exp < o.min_expected {
            po += obs;
            pe += exp;
            continue;
        }
        chi2 += (obs - exp) * (obs - exp) / exp;
        dof += 1;
    }
    if pe > 0.0 || po > 0.0 {
        if pe < o.min_expected {
            // Not enough mass to form a bin: any observations there are evidence against.
            if po > 0.0 && pe <= 1e-12 {
                chi2 = f64::INFINITY;
            } else {
                chi2 += (po - pe) * (po - pe) / pe.max(1e-12);
                dof += 1;
            }
        } else {
            chi2 += (po - pe) * (po - pe) / pe;
            dof += 1;
        }
    }
    let dof = dof.max(1) as usize;
    let p_value = if chi2.is_finite() {
        gamma_q(dof as f64 / 2.0, chi2 / 2.0)
    } else {
        0.0
    };
    Chi2Result {
        chi2,
        dof,
        p_value,
        refused,
        pdf_integral,
        invalid,
    }
}

#[cfg(test)]
mod tests;
