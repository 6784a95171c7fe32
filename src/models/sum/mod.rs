//! A weighted sum of models: f_r = Σ_j w_j f_j, e.g. a diffuse base plus a specular lobe.
//!
//! # Flags
//!
//! A sum has a symmetry only when every term has it: `reciprocal`, `isotropic` and `bilateral`
//! are the AND of the terms' flags (of every term, whatever its weight). `delta` is set only when *every* term is a delta (then the
//! sum is a delta model); `transmission` is set when *any* term transmits.
//!
//! # Delta terms
//!
//! A sum may mix delta terms (a mirror) with smooth ones. [`Brdf::eval`] returns only the smooth
//! part (delta terms evaluate to 0, as the trait requires), and [`Brdf::pdf`] only the smooth
//! density. [`Brdf::sample`] may choose a delta term; it then returns that term's direction with
//! `delta: true`, weight w_j·(term weight)/p_j and pdf = p_j · (term's pdf), where p_j is the
//! discrete probability of choosing the term.
//!
//! # Sampling
//!
//! One-sample mixture: for viewing direction wo a term is chosen with probability p_j(wo), a
//! table over [`TABLE_SIZE`] equal bins of cos θo holding w_j · â_j normalized over the terms,
//! where â_j is an estimate of the term's albedo at the bin centre (k + ½)/[`TABLE_SIZE`],
//! precomputed at construction (a bin where no term reflects borrows the nearest bin's
//! probabilities). The table is piecewise constant rather than interpolated so that the sampler
//! can rescale u with a precomputed reciprocal: the choice of term then costs a table read, not
//! a division, on the sampler's critical path. â_j is the term's own Monte Carlo estimate of its
//! albedo: the mean over channels and a stratified 8 × 8 grid (4 × 4 for delta terms) of its
//! sample weights f cos θi / pdf, averaged over φo = 0 and π/2 for anisotropic terms. Each â_j
//! is floored at 10⁻³ of its own maximum so that a term that reflects anywhere is never
//! entirely excluded by a poor estimate. For a smooth sample wi the density is the full mixture
//! pdf = Σ_j p_j pdf_j(wi, wo) and the weight is computed from the whole sum, f_r(wi, wo)
//! cos θi / pdf, so the estimator stays unbiased however poor the albedo estimates are — they
//! only affect variance.
//!
//! The estimate is not [`Brdf::albedo`]: for most models that is a quadrature to 1e-6 (5,000 to
//! a few 100,000 evaluations), 24 of them per term made opening a plastic spec take 0.1 s and a
//! flat sum of 16 glossy terms 0.8 s, and a nested sum's albedo is its terms' albedos, so the
//! cost grew with the square of the nesting depth: a 1 KB spec nesting 20 sums took 49 s to
//! open (issue #23). With sample weights a sum's construction costs 24 × 64 samples of each
//! term (× 2 for anisotropic terms), a nested sum's sample costing one draw and one evaluation
//! of its terms.

use glam::{DVec2, DVec3};

use crate::brdf::{Brdf, BrdfSample, Flags};
use crate::error::{Error, Result};
use crate::spectrum::{Channels, MAX_CHANNELS};

mod eval;
mod sample;
mod selection;
#[cfg(test)]
mod tests;

use selection::{normalized, selection_row};

/// Number of cos θo bins in the term-selection table.
pub const TABLE_SIZE: usize = 24;

/// The most terms a sum may have (nest sums for more): the per-call selection weights live in
/// a fixed array on the stack.
pub const MAX_TERMS: usize = 16;

/// A weighted sum of BRDFs.
pub struct Sum {
    channels: Channels,
    terms: Vec<Box<dyn Brdf + Send + Sync>>,
    weights: Vec<f64>,
    /// Per term: the probability of choosing it in cos θo bin k (w_j · â_j at the bin centre,
    /// normalized over the terms; all zero when no term reflects anywhere).
    select: Vec<[f64; TABLE_SIZE]>,
    /// For two terms, per bin: (p_0, 1/p_0, 1/(1 − p_0)), the choice and the rescaling of u.x.
    pair: [[f64; 3]; TABLE_SIZE],
    /// Whether any term reflects anywhere (else `select` is all zero and nothing is sampled).
    reflects: bool,
    flags: Flags,
}

impl std::fmt::Debug for Sum {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.describe())
    }
}

impl Sum {
    /// The sum Σ w_j f_j of `terms` with `weights` (default 1 each; finite and ≥ 0). Every term
    /// must use `channels`.
    pub fn new(
        terms: Vec<Box<dyn Brdf + Send + Sync>>,
        weights: Option<Vec<f64>>,
        channels: &Channels,
    ) -> Result<Self> {
        channels.validate()?;
        if terms.is_empty() {
            return Err(Error::spec("terms", "a sum needs at least one term"));
        }
        if terms.len() > MAX_TERMS {
            return Err(Error::spec(
                "terms",
                format!(
                    "{} terms, at most {MAX_TERMS} (nest sums for more)",
                    terms.len()
                ),
            ));
        }
        let weights = weights.unwrap_or_else(|| vec![1.0; terms.len()]);
        if weights.len() != terms.len() {
            return Err(Error::spec(
                "weights",
                format!("{} weights for {} terms", weights.len(), terms.len()),
            ));
        }
        for (i, &w) in weights.iter().enumerate() {
            if !(w.is_finite() && w >= 0.0) {
                return Err(Error::spec(
                    format!("weights[{i}]"),
                    format!("{w} must be a finite number ≥ 0"),
                ));
            }
            crate::spectrum::check_range(w, &format!("weights[{i}]"))?;
        }
        for (i, t) in terms.iter().enumerate() {
            if t.channels() != channels {
                return Err(Error::spec(
                    format!("terms[{i}]"),
                    "term has different channels from the sum",
                ));
            }
        }
        let fl: Vec<Flags> = terms.iter().map(|t| t.flags()).collect();
        let flags = Flags {
            delta: fl.iter().all(|f| f.delta),
            reciprocal: fl.iter().all(|f| f.reciprocal),
            isotropic: fl.iter().all(|f| f.isotropic),
            bilateral: fl.iter().all(|f| f.bilateral),
            transmission: fl.iter().any(|f| f.transmission),
            lobes: fl
                .iter()
                .fold(crate::brdf::Lobes::default(), |a, f| a.union(f.lobes)),
        };
        let select = normalized(
            terms
                .iter()
                .zip(&weights)
                .map(|(t, &w)| selection_row(t.as_ref(), w))
                .collect(),
        );
        Ok(Sum {
            channels: channels.clone(),
            terms,
            weights,
            reflects: select.iter().any(|r| r.iter().any(|&p| p > 0.0)),
            pair: std::array::from_fn(|k| {
                let p0 = select[0][k];
                [p0, 1.0 / p0, 1.0 / (1.0 - p0)]
            }),
            select,
            flags,
        })
    }

    /// The terms and their weights.
    pub fn terms(&self) -> impl Iterator<Item = (&dyn Brdf, f64)> {
        self.terms
            .iter()
            .map(|t| -> &dyn Brdf { t.as_ref() })
            .zip(self.weights.iter().copied())
    }
}

impl Brdf for Sum {
    fn channels(&self) -> &Channels {
        &self.channels
    }

    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        if self.channels.len() <= 4 {
            self.eval_n::<4>(wi, wo, out)
        } else {
            self.eval_n::<MAX_CHANNELS>(wi, wo, out)
        }
    }

    fn eval_wavelength(&self, wi: DVec3, wo: DVec3, nm: f64) -> f64 {
        if !crate::spectrum::is_wavelength(nm) {
            return f64::NAN; // also with every weight 0
        }
        self.terms
            .iter()
            .zip(&self.weights)
            .filter(|(_, w)| **w != 0.0)
            .map(|(t, &w)| w * t.eval_wavelength(wi, wo, nm))
            .sum()
    }

    fn flags(&self) -> Flags {
        self.flags
    }

    /// When any term does (a sum is as unbounded as its worst term).
    fn grows_at_horizon(&self) -> bool {
        self.terms.iter().any(|t| t.grows_at_horizon())
    }

    fn describe(&self) -> String {
        let parts: Vec<String> = self
            .terms
            .iter()
            .zip(&self.weights)
            .map(|(t, w)| format!("{w}×({})", t.describe()))
            .collect();
        format!("sum {}", parts.join(" + "))
    }

    /// Σ_j w_j a_j(wi), from each term's own albedo.
    fn albedo(&self, wi: DVec3, out: &mut [f64]) {
        let c = self.channels.len();
        out[..c].fill(0.0);
        let mut tmp = [0.0f64; MAX_CHANNELS];
        for (t, &w) in self.terms.iter().zip(&self.weights) {
            if w == 0.0 {
                continue;
            }
            t.albedo(wi, &mut tmp[..c]);
            for k in 0..c {
                out[k] += w * tmp[k];
            }
        }
    }

    fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
        self.sample_chosen(wo, u, weight, &mut (0, DVec2::ZERO))
    }

    /// A smooth draw weighs the sum's f_r at each wavelength ([`Brdf::eval_wavelength`]) by
    /// cos θi / pdf; a delta draw is the chosen term's, at each wavelength, scaled as
    /// [`Brdf::sample`] scales it (term weight / probability of the choice).
    fn sample_wavelengths(
        &self,
        wo: DVec3,
        u: DVec2,
        nm: &[f64],
        weight: &mut [f32],
    ) -> Option<BrdfSample> {
        let mut buf = [0.0f32; MAX_CHANNELS];
        let mut chosen = (0, DVec2::ZERO);
        let s = self.sample_chosen(wo, u, &mut buf[..self.channels.len()], &mut chosen)?;
        if s.delta {
            let (j, uj) = chosen;
            let t = self.terms[j].sample_wavelengths(wo, uj, nm, weight)?;
            // s.pdf = p_j · (the term's pdf): the term's weight times w_j / p_j.
            let scale = self.weights[j] * t.pdf / s.pdf;
            for w in &mut weight[..nm.len()] {
                *w = (scale * *w as f64) as f32;
            }
        } else {
            let k = s.wi.z.abs() / s.pdf;
            for (w, &x) in weight.iter_mut().zip(nm) {
                *w = (self.eval_wavelength(s.wi, wo, x) * k) as f32;
            }
        }
        Some(s)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.mixture_pdf(wi, wo)
    }

    /// f_r and the mixture density in one pass over the terms (each term's own `eval_pdf`).
    fn eval_pdf(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) -> f64 {
        if self.channels.len() <= 4 {
            self.eval_pdf_n::<4>(wi, wo, out)
        } else {
            self.eval_pdf_n::<MAX_CHANNELS>(wi, wo, out)
        }
    }
}
