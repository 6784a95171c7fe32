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
use std::f64::consts::FRAC_PI_2;

use crate::brdf::{Brdf, BrdfSample, Flags};
use crate::error::{Error, Result};
use crate::geometry;
use crate::spectrum::{Channels, MAX_CHANNELS};

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

    /// The selection-table bin of cos θo.
    #[inline]
    fn bin(cos_o: f64) -> usize {
        ((cos_o * TABLE_SIZE as f64) as usize).min(TABLE_SIZE - 1)
    }

    /// The probabilities p_j(cos θo) of choosing each term into `sel`, and their sum: 1 up to
    /// rounding, or 0 when no term reflects. With two terms the second is 1 − p_0 exactly and
    /// the sum exactly 1, as in the pair sampler.
    #[inline]
    fn selections(&self, cos_o: f64, sel: &mut [f64; MAX_TERMS]) -> f64 {
        let k = Self::bin(cos_o);
        let mut total = 0.0;
        for (s, row) in sel.iter_mut().zip(&self.select) {
            *s = row[k];
            total += *s;
        }
        if self.terms.len() == 2 && total > 0.0 {
            sel[1] = 1.0 - sel[0];
            total = 1.0;
        }
        total
    }

    /// The probabilities p_j(wo) of choosing each term, normalized (for inspection and tests).
    /// All zero when no term reflects towards `wo`.
    pub fn selection_probabilities(&self, wo: DVec3) -> Vec<f64> {
        let cos_o = geometry::normalize(wo).map_or(0.0, |w| w.z);
        let mut sel = [0.0; MAX_TERMS];
        let total = self.selections(cos_o, &mut sel);
        let n = self.terms.len();
        if total > 0.0 {
            sel[..n].iter().map(|x| x / total).collect()
        } else {
            vec![0.0; n]
        }
    }

    /// [`Brdf::sample`], telling which term drew and from which numbers (`chosen`).
    fn sample_chosen(
        &self,
        wo: DVec3,
        u: DVec2,
        weight: &mut [f32],
        chosen: &mut (usize, DVec2),
    ) -> Option<BrdfSample> {
        if !geometry::in_unit_square(u) {
            return None;
        }
        if let ([a, b], 3) = (self.terms.as_slice(), self.channels.len()) {
            return self.sample_pair_rgb([a.as_ref(), b.as_ref()], wo, u, weight, chosen);
        }
        if self.channels.len() <= 4 {
            self.sample_n::<4>(wo, u, weight, chosen)
        } else {
            self.sample_n::<MAX_CHANNELS>(wo, u, weight, chosen)
        }
    }

    /// [`Brdf::sample`] with scratch arrays of `N` ≥ channels entries (4 for RGB, so the
    /// per-call scratch is not a kilobyte of zeroes).
    ///
    /// Written for latency: the selection weights are computed once, the chosen term writes its
    /// weight straight into `weight`, and the mixture density is normalized by one division.
    /// `chosen` receives the term drawn from and the numbers it was given (for
    /// [`Brdf::sample_wavelengths`]' delta draws).
    fn sample_n<const N: usize>(
        &self,
        wo: DVec3,
        u: DVec2,
        weight: &mut [f32],
        chosen: &mut (usize, DVec2),
    ) -> Option<BrdfSample> {
        let wo = geometry::unit(wo)?;
        if wo.z <= 0.0 {
            return None;
        }
        let mut sel = [0.0; MAX_TERMS];
        let total = self.selections(wo.z, &mut sel);
        if !(total > 0.0 && total < f64::INFINITY) {
            return None;
        }
        let n = self.terms.len();
        // Choose term j by u.x and reuse the remainder of u.x within its interval. Terms with
        // weight 0 are passed over (target ≥ cum always holds); rounding can leave target ≥ the
        // accumulated total, and then the last term with a positive weight is the one.
        let target = u.x * total;
        let mut j = 0;
        let mut cum = 0.0;
        while j + 1 < n && target >= cum + sel[j] {
            cum += sel[j];
            j += 1;
        }
        let mut ux = (target - cum) / sel[j];
        if !(sel[j] > 0.0) {
            j = sel[..n].iter().rposition(|&s| s > 0.0)?;
            ux = 1.0;
        }
        let ux = ux.clamp(0.0, 1.0 - f64::EPSILON);
        *chosen = (j, DVec2::new(ux, u.y));
        let c = self.channels.len();
        // Only the fields are read from the returned sample (not the whole `Option`), so no
        // load of its padding waits on the callee's narrower stores.
        let (wi, tpdf, delta) =
            match self.terms[j].sample(wo, DVec2::new(ux, u.y), &mut weight[..c]) {
                Some(s) => (s.wi, s.pdf, s.delta),
                None => return None,
            };
        let pj = sel[j] / total;
        if delta {
            let scale = self.weights[j] / pj;
            for w in &mut weight[..c] {
                *w = (scale * *w as f64) as f32;
            }
            return Some(BrdfSample {
                wi,
                pdf: pj * tpdf,
                delta: true,
            });
        }
        // The chosen term already knows its density and, through its weight, its f·cos θi =
        // weight · pdf: only the other terms are evaluated. `mix` is Σ_k sel_k pdf_k, the
        // mixture density times `total`.
        let mut mix = sel[j] * tpdf;
        let mut fcos = [0.0f64; N];
        let wj = self.weights[j] * tpdf;
        for (f, &w) in fcos[..c].iter_mut().zip(&weight[..c]) {
            *f = wj * w as f64;
        }
        let cos_i = wi.z.abs();
        let mut tmp = [0.0f32; N];
        for (k, t) in self.terms.iter().enumerate() {
            if k == j {
                continue;
            }
            let w = self.weights[k];
            if w != 0.0 {
                let pk = t.eval_pdf(wi, wo, &mut tmp[..c]);
                let wc = w * cos_i;
                for (f, &x) in fcos[..c].iter_mut().zip(&tmp[..c]) {
                    *f += wc * x as f64;
                }
                mix += sel[k] * pk;
            } else if sel[k] > 0.0 {
                mix += sel[k] * t.pdf(wi, wo);
            }
        }
        let pdf = mix / total;
        if !(pdf > 0.0 && pdf < f64::INFINITY) {
            return None;
        }
        let inv = total / mix;
        for (o, &f) in weight[..c].iter_mut().zip(&fcos[..c]) {
            *o = (f * inv) as f32;
        }
        Some(BrdfSample {
            wi,
            pdf,
            delta: false,
        })
    }

    /// [`Brdf::sample`] for the common case, two RGB terms (a diffuse base and a specular lobe):
    /// the same mixture as [`Sum::sample_n`], written as straight-line code. A sample of a sum
    /// costs the chosen term's sample plus the other term's `eval_pdf`; this keeps what the sum
    /// itself adds to a few dozen instructions.
    fn sample_pair_rgb(
        &self,
        terms: [&dyn Brdf; 2],
        wo: DVec3,
        u: DVec2,
        weight: &mut [f32],
        chosen: &mut (usize, DVec2),
    ) -> Option<BrdfSample> {
        let wo = geometry::unit(wo)?;
        if wo.z <= 0.0 {
            return None;
        }
        if !self.reflects {
            return None;
        }
        let [s0, inv0, inv1] = self.pair[Self::bin(wo.z)];
        let s1 = 1.0 - s0;
        // Term 0 owns [0, s0) of u.x, term 1 the rest; a term with probability 0 is never chosen.
        let first = if s1 > 0.0 { u.x < s0 } else { true };
        let (j, sj, sk, ux) = if first {
            (0, s0, s1, u.x * inv0)
        } else {
            (1, s1, s0, (u.x - s0) * inv1)
        };
        let ux = ux.clamp(0.0, 1.0 - f64::EPSILON);
        *chosen = (j, DVec2::new(ux, u.y));
        let w = &mut weight[..3];
        let (wi, tpdf, delta) = match terms[j].sample(wo, DVec2::new(ux, u.y), w) {
            Some(s) => (s.wi, s.pdf, s.delta),
            None => return None,
        };
        if delta {
            let pj = sj;
            let scale = self.weights[j] / pj;
            for x in w.iter_mut() {
                *x = (scale * *x as f64) as f32;
            }
            return Some(BrdfSample {
                wi,
                pdf: pj * tpdf,
                delta: true,
            });
        }
        let wj = self.weights[j] * tpdf;
        let mut f = [wj * w[0] as f64, wj * w[1] as f64, wj * w[2] as f64];
        let mut mix = sj * tpdf;
        let wk = self.weights[1 - j];
        if wk != 0.0 {
            let mut e = [0.0f32; 3];
            let pk = terms[1 - j].eval_pdf(wi, wo, &mut e);
            let wc = wk * wi.z.abs();
            f[0] += wc * e[0] as f64;
            f[1] += wc * e[1] as f64;
            f[2] += wc * e[2] as f64;
            mix += sk * pk;
        } else if sk > 0.0 {
            mix += sk * terms[1 - j].pdf(wi, wo);
        }
        let pdf = mix;
        if !(pdf > 0.0 && pdf < f64::INFINITY) {
            return None;
        }
        w[0] = (f[0] / mix) as f32;
        w[1] = (f[1] / mix) as f32;
        w[2] = (f[2] / mix) as f32;
        Some(BrdfSample {
            wi,
            pdf,
            delta: false,
        })
    }

    /// [`Brdf::eval`] with scratch arrays of `N` ≥ channels entries.
    fn eval_n<const N: usize>(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let c = self.channels.len();
        let mut acc = [0.0f64; N];
        let mut tmp = [0.0f32; N];
        for (t, &w) in self.terms.iter().zip(&self.weights) {
            if w == 0.0 {
                continue;
            }
            t.eval(wi, wo, &mut tmp[..c]);
            for (a, &x) in acc[..c].iter_mut().zip(&tmp[..c]) {
                *a += w * x as f64;
            }
        }
        for (o, a) in out[..c].iter_mut().zip(&acc[..c]) {
            *o = *a as f32;
        }
    }

    /// [`Brdf::eval_pdf`] with scratch arrays of `N` ≥ channels entries.
    fn eval_pdf_n<const N: usize>(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) -> f64 {
        let c = self.channels.len();
        let mut sel = [0.0; MAX_TERMS];
        let total = match geometry::unit(wo) {
            Some(v) if v.z > 0.0 => self.selections(v.z, &mut sel),
            _ => 0.0,
        };
        if !(total > 0.0 && total < f64::INFINITY) {
            // No density towards `wo`; f may still be defined (the terms decide).
            self.eval_n::<N>(wi, wo, out);
            return 0.0;
        }
        let mut acc = [0.0f64; N];
        let mut tmp = [0.0f32; N];
        let mut mix = 0.0;
        for ((t, &w), &s) in self.terms.iter().zip(&self.weights).zip(&sel) {
            if w != 0.0 {
                let p = t.eval_pdf(wi, wo, &mut tmp[..c]);
                for (a, &x) in acc[..c].iter_mut().zip(&tmp[..c]) {
                    *a += w * x as f64;
                }
                if s > 0.0 {
                    mix += s * p;
                }
            } else if s > 0.0 {
                mix += s * t.pdf(wi, wo);
            }
        }
        for (o, a) in out[..c].iter_mut().zip(&acc[..c]) {
            *o = *a as f32;
        }
        mix / total
    }

    /// The smooth mixture density Σ_j p_j pdf_j(wi, wo), or 0 when `wo` is invalid, below the
    /// horizon, or no term reflects towards it.
    fn mixture_pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let Some(wo) = geometry::unit(wo) else {
            return 0.0;
        };
        if wo.z <= 0.0 {
            return 0.0;
        }
        let mut sel = [0.0; MAX_TERMS];
        let total = self.selections(wo.z, &mut sel);
        if !(total > 0.0 && total < f64::INFINITY) {
            return 0.0;
        }
        let mut mix = 0.0;
        for (t, &s) in self.terms.iter().zip(&sel) {
            if s > 0.0 {
                mix += s * t.pdf(wi, wo);
            }
        }
        mix / total
    }
}

/// The rows w_j â_j normalized over the terms at each table entry. An entry where no term
/// reflects takes the probabilities of the nearest entry where one does; all rows stay zero when
/// none does anywhere.
fn normalized(rows: Vec<[f64; TABLE_SIZE]>) -> Vec<[f64; TABLE_SIZE]> {
    let totals: Vec<f64> = (0..TABLE_SIZE)
        .map(|k| rows.iter().map(|r| r[k]).sum())
        .collect();
    let good = |k: usize| totals[k] > 0.0 && totals[k].is_finite();
    let mut out = vec![[0.0; TABLE_SIZE]; rows.len()];
    for k in 0..TABLE_SIZE {
        let Some(src) = (0..TABLE_SIZE)
            .filter(|&i| good(i))
            .min_by_key(|&i| i.abs_diff(k))
        else {
            return out;
        };
        for (o, r) in out.iter_mut().zip(&rows) {
            o[k] = r[src] / totals[src];
        }
    }
    out
}

/// w · â(cos θo) at the bin centres, floored at 10⁻³ of the row's maximum.
fn selection_row(term: &dyn Brdf, w: f64) -> [f64; TABLE_SIZE] {
    let mut row = [0.0; TABLE_SIZE];
    if w == 0.0 {
        return row;
    }
    let flags = term.flags();
    let phis: &[f64] = if flags.isotropic {
        &[0.0]
    } else {
        &[0.0, FRAC_PI_2]
    };
    for (k, r) in row.iter_mut().enumerate() {
        let mu = (k as f64 + 0.5) / TABLE_SIZE as f64;
        let s = (1.0 - mu * mu).sqrt();
        let mut acc = 0.0;
        for &phi in phis {
            let wo = DVec3::new(s * phi.cos(), s * phi.sin(), mu);
            let a = mean_sample_weight(term, wo, if flags.delta { 4 } else { 8 });
            if a.is_finite() && a > 0.0 {
                acc += a;
            }
        }
        *r = w * acc / phis.len() as f64;
    }
    let max = row.iter().copied().fold(0.0, f64::max);
    for r in &mut row {
        *r = r.max(1e-3 * max);
    }
    row
}

/// The mean over channels and a stratified n × n grid of the term's sample weights at `wo`:
/// an unbiased estimate of ∫ f cos θi dωi (exact when the weight is constant: a Lambert term,
/// a delta term).
fn mean_sample_weight(term: &dyn Brdf, wo: DVec3, n: usize) -> f64 {
    let c = term.channels().len().min(MAX_CHANNELS);
    let mut sum = 0.0;
    for a in 0..n {
        for b in 0..n {
            let u = DVec2::new((a as f64 + 0.5) / n as f64, (b as f64 + 0.5) / n as f64);
            let mut w = [0.0f32; MAX_CHANNELS];
            if term.sample(wo, u, &mut w[..c]).is_some() {
                let m = w[..c].iter().map(|&x| x as f64).sum::<f64>() / c as f64;
                if m.is_finite() {
                    sum += m;
                }
            }
        }
    }
    sum / (n * n) as f64
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fresnel::FresnelSpec;
    use crate::models::test_util::*;
    use crate::models::{
        blinn_phong::BlinnPhong, ggx::Ggx, lambert::Lambert, oren_nayar::OrenNayar, ward::Ward,
    };
    use crate::rng::Pcg32;
    use crate::spec::ModelSpec;
    use crate::spectrum::Value;
    use proptest::prelude::*;

    fn lambert(kd: f64) -> Box<dyn Brdf + Send + Sync> {
        Box::new(Lambert::new(Value::Grey(kd), &Channels::Rgb).unwrap())
    }

    fn ggx(ax: f64, ay: f64) -> Box<dyn Brdf + Send + Sync> {
        Box::new(
            Ggx::new(
                ax,
                ay,
                Value::Rgb([0.9, 0.7, 0.5]),
                FresnelSpec::None,
                &Channels::Rgb,
            )
            .unwrap(),
        )
    }

    fn plastic() -> Sum {
        Sum::new(
            vec![lambert(0.2), ggx(0.1, 0.1)],
            Some(vec![1.0, 0.5]),
            &Channels::Rgb,
        )
        .unwrap()
    }

    fn three() -> Sum {
        Sum::new(
            vec![
                Box::new(Ward::new(Value::Grey(0.3), 0.08, 0.4, &Channels::Rgb).unwrap()),
                Box::new(BlinnPhong::new(Value::Grey(0.4), 60.0, &Channels::Rgb).unwrap()),
                Box::new(OrenNayar::new(Value::Grey(0.15), 0.5, &Channels::Rgb).unwrap()),
            ],
            None,
            &Channels::Rgb,
        )
        .unwrap()
    }

    /// A test-only mirror (delta) with constant reflectance, for the delta-term rules.
    struct TestMirror(Channels, f32);
    impl Brdf for TestMirror {
        fn channels(&self) -> &Channels {
            &self.0
        }
        fn eval(&self, _: DVec3, _: DVec3, out: &mut [f32]) {
            out[..3].fill(0.0);
        }
        fn flags(&self) -> Flags {
            Flags {
                delta: true,
                lobes: crate::brdf::Lobes::DELTA,
                ..Flags::SMOOTH_SYMMETRIC
            }
        }
        fn describe(&self) -> String {
            "test mirror".into()
        }
        fn sample(&self, wo: DVec3, _: DVec2, w: &mut [f32]) -> Option<BrdfSample> {
            let wo = geometry::normalize(wo).filter(|w| w.z > 0.0)?;
            w[..3].fill(self.1);
            Some(BrdfSample {
                wi: geometry::reflect_z(wo),
                pdf: 1.0,
                delta: true,
            })
        }
        fn pdf(&self, _: DVec3, _: DVec3) -> f64 {
            0.0
        }
    }

    #[test]
    fn sum_equals_weighted_terms() {
        let s = plastic();
        let (a, b) = (lambert(0.2), ggx(0.1, 0.1));
        let mut rng = Pcg32::new(8);
        for _ in 0..2000 {
            let wi = geometry::uniform_sphere(rng.next_dvec2());
            let wo = geometry::uniform_sphere(rng.next_dvec2());
            let (mut f, mut fa, mut fb) = ([0.0f32; 3], [0.0f32; 3], [0.0f32; 3]);
            s.eval(wi, wo, &mut f);
            a.eval(wi, wo, &mut fa);
            b.eval(wi, wo, &mut fb);
            for c in 0..3 {
                let expect = fa[c] as f64 + 0.5 * fb[c] as f64;
                assert!(
                    (f[c] as f64 - expect).abs() <= 1e-7 * expect,
                    "{} vs {expect}",
                    f[c]
                );
            }
            let expect = a.eval_wavelength(wi, wo, 500.0) + 0.5 * b.eval_wavelength(wi, wo, 500.0);
            assert!((s.eval_wavelength(wi, wo, 500.0) - expect).abs() <= 1e-12 * expect);
        }
    }

    #[test]
    fn built_from_spec_with_default_weights() {
        let spec = ModelSpec::parse(
            r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.1},
                {"model": "oren_nayar", "kd": 0.2, "sigma": 0.0}]}"#,
        )
        .unwrap();
        let s = spec.build(&Channels::Rgb).unwrap();
        let mut f = [0.0f32; 3];
        s.eval(
            DVec3::new(0.1, 0.2, 1.0),
            DVec3::new(-0.5, 0.0, 0.5),
            &mut f,
        );
        assert!((f[0] as f64 - 0.3).abs() < 1e-7);
    }

    #[test]
    fn flags_are_the_and_of_terms_and_lobes_their_union() {
        let both = crate::brdf::Lobes::DIFFUSE.union(crate::brdf::Lobes::GLOSSY);
        assert_eq!(
            plastic().flags(),
            Flags {
                lobes: both,
                ..Flags::SMOOTH_SYMMETRIC
            }
        );
        let aniso = Sum::new(vec![lambert(0.2), ggx(0.1, 0.3)], None, &Channels::Rgb).unwrap();
        assert!(!aniso.flags().isotropic && aniso.flags().reciprocal && !aniso.flags().delta);
        let mirror = || -> Box<dyn Brdf + Send + Sync> { Box::new(TestMirror(Channels::Rgb, 0.5)) };
        let mixed = Sum::new(vec![lambert(0.2), mirror()], None, &Channels::Rgb).unwrap();
        assert!(!mixed.flags().delta);
        let all = Sum::new(vec![mirror(), mirror()], None, &Channels::Rgb).unwrap();
        assert!(all.flags().delta);
        let lobes = mixed.flags().lobes;
        assert!(lobes.diffuse && lobes.delta && !lobes.glossy);
    }

    #[test]
    fn delta_terms_are_skipped_by_eval_and_chosen_by_sample() {
        let s = Sum::new(
            vec![lambert(0.2), Box::new(TestMirror(Channels::Rgb, 0.5))],
            Some(vec![1.0, 2.0]),
            &Channels::Rgb,
        )
        .unwrap();
        let wo = geometry::spherical(0.6, 0.2);
        let mut f = [0.0f32; 3];
        s.eval(geometry::reflect_z(wo), wo, &mut f);
        assert!((f[0] - 0.2).abs() < 1e-7);
        // Albedos: Lambert 0.2π, mirror 2 · 0.5 = 1.
        let p = s.selection_probabilities(wo);
        let expect_mirror = 1.0 / (1.0 + 0.2 * std::f64::consts::PI);
        assert!((p[1] - expect_mirror).abs() < 1e-3, "{p:?}");
        // The mean sample weight is the total reflectance towards wo: 0.2π + 1.
        let mut rng = Pcg32::new(2);
        let (n, mut sum, mut deltas) = (100_000, 0.0, 0);
        for _ in 0..n {
            let mut w = [0.0f32; 3];
            if let Some(smp) = s.sample(wo, rng.next_dvec2(), &mut w) {
                if smp.delta {
                    deltas += 1;
                    assert!((smp.wi - geometry::reflect_z(wo)).length() < 1e-12);
                    assert!((smp.pdf - p[1]).abs() < 1e-12);
                }
                sum += w[0] as f64;
            }
        }
        let mean = sum / n as f64;
        let expect = 0.2 * std::f64::consts::PI + 1.0;
        // Weights are 1/p per branch: the estimator is exact per branch, the only variance is the
        // branch choice (σ ≈ 1e-3 here) — allow 5σ.
        assert!((mean - expect).abs() < 5e-3, "{mean} vs {expect}");
        assert!((deltas as f64 / n as f64 - p[1]).abs() < 0.01);
    }

    /// Counts every call of a term's eval, sample and pdf, and integrates its albedo by the
    /// trait's default quadrature through the counted `eval` (as every model but Lambert and
    /// the deltas does).
    struct Counting(
        Box<dyn Brdf + Send + Sync>,
        std::sync::Arc<std::sync::atomic::AtomicUsize>,
    );

    impl Counting {
        fn tick(&self) {
            self.1.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
    }

    impl Brdf for Counting {
        fn channels(&self) -> &Channels {
            self.0.channels()
        }
        fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
            self.tick();
            self.0.eval(wi, wo, out)
        }
        fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
            self.tick();
            self.0.sample(wo, u, weight)
        }
        fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
            self.tick();
            self.0.pdf(wi, wo)
        }
        fn flags(&self) -> Flags {
            self.0.flags()
        }
        fn describe(&self) -> String {
            self.0.describe()
        }
    }

    #[test]
    fn nested_sums_are_built_in_bounded_work() {
        // Issue #23: the selection table took each term's `Brdf::albedo` at 24 angles — a
        // 1e-6 quadrature of thousands of evaluations each, and for a nested sum the albedos
        // of all its terms, so the work grew with the square of the depth (a 1 KB spec nesting
        // 20 sums took 49 s to open). Now each level draws 24 × 64 samples of each term (× 2
        // for anisotropic ones), a nested sum's sample costing at most one draw, one pdf and
        // one evaluation of each of its leaves.
        let calls = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let leaf = |a: f64| -> Box<dyn Brdf + Send + Sync> {
            Box::new(Counting(ggx(a, a), calls.clone()))
        };
        let depth = 12;
        let mut chain = leaf(0.1);
        for k in 0..depth {
            chain = Box::new(
                Sum::new(
                    vec![leaf(0.05 + 0.01 * k as f64), chain],
                    None,
                    &Channels::Rgb,
                )
                .unwrap(),
            );
        }
        let n = calls.load(std::sync::atomic::Ordering::Relaxed);
        let leaves = depth + 1;
        let bound = depth * TABLE_SIZE * 64 * 3 * leaves;
        assert!(
            n <= bound,
            "{n} calls of the leaves for a depth {depth} chain (bound {bound})"
        );
        // Still a working sampler: the mean weight is the albedo.
        let wo = geometry::spherical(0.5, 0.3);
        let mut rng = Pcg32::new(5);
        let (m, mut mean) = (20_000, 0.0);
        for _ in 0..m {
            let mut w = [0.0f32; 3];
            if chain.sample(wo, rng.next_dvec2(), &mut w).is_some() {
                mean += w[0] as f64 / m as f64;
            }
        }
        let mut a = [0.0; 3];
        chain.albedo(wo, &mut a);
        assert!(
            (mean - a[0]).abs() < 0.05 * a[0],
            "{mean} vs albedo {}",
            a[0]
        );
    }

    #[test]
    fn selection_estimates_follow_the_albedo() {
        // The sample-weight estimate of a glossy term's albedo is within a few percent of the
        // quadrature, at every bin, so the selection is close to the ideal one.
        let s = Sum::new(vec![lambert(0.1), ggx(0.2, 0.2)], None, &Channels::Rgb).unwrap();
        for k in 0..TABLE_SIZE {
            let mu = (k as f64 + 0.5) / TABLE_SIZE as f64;
            let wo = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let mut a = [0.0; 3];
            ggx(0.2, 0.2).albedo(wo, &mut a);
            let mean = a.iter().sum::<f64>() / 3.0;
            let ideal = mean / (mean + 0.1 * std::f64::consts::PI);
            let p = s.selection_probabilities(wo);
            assert!((p[1] - ideal).abs() < 0.01, "bin {k}: {p:?} vs {ideal}");
        }
    }

    #[test]
    fn lambert_plus_real_mirror_from_spec() {
        // The mean sample weight is the reflectance towards wo: k_d π + F(cos θo).
        let spec = ModelSpec::parse(
            r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.1},
                {"model": "mirror", "fresnel": {"n": 1.5, "k": 0.0}}]}"#,
        )
        .unwrap();
        let s = spec.build(&Channels::Rgb).unwrap();
        assert!(!s.flags().delta);
        let mut rng = Pcg32::new(21);
        for deg in [10.0f64, 70.0] {
            let wo = geometry::spherical(deg.to_radians(), 1.0);
            let expect = 0.1 * std::f64::consts::PI + crate::fresnel::dielectric(wo.z, 1.5);
            let n = 50_000;
            let mut sum = 0.0;
            for _ in 0..n {
                let mut w = [0.0f32; 3];
                if s.sample(wo, rng.next_dvec2(), &mut w).is_some() {
                    sum += w[0] as f64;
                }
            }
            let mean = sum / n as f64;
            // Each branch's weight is its reflectance / p_j; only the branch choice varies.
            assert!(
                (mean - expect).abs() < 0.02 * expect,
                "{deg}°: {mean} vs {expect}"
            );
        }
    }

    /// The mean weight of `sample_wavelengths` over stratified numbers is the reflectance
    /// towards wo at each wavelength — k_d π plus each mirror's Fresnel term there — for the
    /// two-term RGB path and the general one. Each branch's weight is its reflectance over its
    /// choice probability, so the strata leave an error of at most two strata's weights.
    #[test]
    fn spectral_sample_weights_of_delta_terms_are_the_terms_reflectance() {
        let mirror = |m: &str| -> Box<dyn Brdf + Send + Sync> {
            Box::new(
                crate::models::mirror::Mirror::new(
                    &FresnelSpec::Conductor(m.into()),
                    &Channels::Rgb,
                )
                .unwrap(),
            )
        };
        let nm = [420.0, 480.0, 530.0, 610.0, 700.0];
        let sums = [
            Sum::new(vec![lambert(0.1), mirror("Au")], None, &Channels::Rgb).unwrap(),
            Sum::new(
                vec![lambert(0.1), mirror("Au"), mirror("Cu")],
                Some(vec![1.0, 0.5, 0.5]),
                &Channels::Rgb,
            )
            .unwrap(),
        ];
        let fresnel = |m: &str, cos: f64, x: f64| {
            crate::fresnel::Fresnel::new(&FresnelSpec::Conductor(m.into()), &Channels::Rgb, "f")
                .unwrap()
                .eval_at(cos, x)
        };
        for (k, s) in sums.iter().enumerate() {
            for deg in [5.0f64, 60.0] {
                let wo = geometry::spherical(deg.to_radians(), 0.4);
                let n = 8192;
                let (mut sum, mut most) = ([0.0f64; 5], 0.0f64);
                for i in 0..n {
                    let u = DVec2::new((i as f64 + 0.5) / n as f64, 0.37);
                    let mut w = [0.0f32; 5];
                    let d = s.sample_wavelengths(wo, u, &nm, &mut w).unwrap();
                    if d.delta {
                        assert!((d.wi - geometry::reflect_z(wo)).length() < 1e-12);
                    }
                    for (a, &x) in sum.iter_mut().zip(&w) {
                        *a += x as f64;
                        most = most.max(x as f64);
                    }
                }
                for (j, &x) in nm.iter().enumerate() {
                    let metals = match k {
                        0 => fresnel("Au", wo.z, x),
                        _ => 0.5 * (fresnel("Au", wo.z, x) + fresnel("Cu", wo.z, x)),
                    };
                    let expect = 0.1 * std::f64::consts::PI + metals;
                    let mean = sum[j] / n as f64;
                    let tol = 2.0 * most / n as f64;
                    assert!(
                        (mean - expect).abs() <= tol,
                        "sum {k}, {deg}°, {x} nm: {mean} vs {expect} (± {tol})"
                    );
                }
            }
        }
    }

    #[test]
    fn selection_follows_albedo() {
        // A white Lambert (albedo 1) and a GGX with F = 1 weighted by 0 gets nothing.
        let s = Sum::new(
            vec![lambert(1.0 / std::f64::consts::PI), ggx(0.2, 0.2)],
            Some(vec![1.0, 0.0]),
            &Channels::Rgb,
        )
        .unwrap();
        assert_eq!(s.selection_probabilities(DVec3::Z), vec![1.0, 0.0]);
        // Equal albedo terms get (nearly) equal probability.
        let s = Sum::new(vec![lambert(0.1), lambert(0.3)], None, &Channels::Rgb).unwrap();
        let p = s.selection_probabilities(geometry::spherical(0.4, 0.0));
        assert!((p[0] - 0.25).abs() < 1e-6, "{p:?}");
    }

    #[test]
    fn invalid_construction_is_an_error() {
        assert!(Sum::new(vec![], None, &Channels::Rgb).is_err());
        assert!(Sum::new(vec![lambert(0.1)], Some(vec![1.0, 2.0]), &Channels::Rgb).is_err());
        assert!(Sum::new(vec![lambert(0.1)], Some(vec![-1.0]), &Channels::Rgb).is_err());
        assert!(Sum::new(vec![lambert(0.1)], Some(vec![f64::NAN]), &Channels::Rgb).is_err());
        let ch = Channels::linspace(400.0, 700.0, 4).unwrap();
        assert!(Sum::new(vec![lambert(0.1)], None, &ch).is_err());
        let many = (0..=MAX_TERMS).map(|_| lambert(0.01)).collect();
        let err = Sum::new(many, None, &Channels::Rgb)
            .unwrap_err()
            .to_string();
        assert!(err.contains("at most 16"), "{err}");
        let most = (0..MAX_TERMS).map(|_| lambert(0.01)).collect();
        assert!(Sum::new(most, None, &Channels::Rgb).is_ok());
    }

    #[test]
    fn nothing_is_sampled_when_no_term_reflects() {
        // Weights 0: f = 0 everywhere, no term can be chosen, the density is 0 — for the pair
        // sampler and the general one.
        for n in [2, 3] {
            let s = Sum::new(
                (0..n).map(|_| lambert(0.2)).collect(),
                Some(vec![0.0; n]),
                &Channels::Rgb,
            )
            .unwrap();
            let wo = geometry::spherical(0.3, 0.1);
            let mut w = [1.0f32; 3];
            assert!(s.sample(wo, DVec2::new(0.3, 0.7), &mut w).is_none());
            assert_eq!(s.pdf(DVec3::Z, wo), 0.0);
            assert_eq!(s.eval_pdf(DVec3::Z, wo, &mut w), 0.0);
            assert_eq!(w, [0.0; 3]);
            assert_eq!(s.selection_probabilities(wo), vec![0.0; n]);
        }
    }

    #[test]
    fn pair_sampler_agrees_with_the_general_one() {
        // For two RGB terms `sample` takes the pair path; `sample_n` is the general one. Both
        // choose with the same probabilities, so for every u they give the same direction, pdf
        // and weight, up to the rounding of the rescaled u.x (a multiplication by a reciprocal
        // against a division: one unit in the last place, which the warps amplify to ≲ 10⁻¹³).
        let s = plastic();
        let mut rng = Pcg32::new(77);
        for _ in 0..20_000 {
            let wo = geometry::cosine_hemisphere(rng.next_dvec2());
            let u = rng.next_dvec2();
            let (mut a, mut b) = ([0.0f32; 3], [0.0f32; 3]);
            match (
                s.sample(wo, u, &mut a),
                s.sample_n::<4>(wo, u, &mut b, &mut (0, DVec2::ZERO)),
            ) {
                (Some(x), Some(y)) => {
                    assert!((x.wi - y.wi).length() < 1e-12, "{x:?} vs {y:?}");
                    assert!((x.pdf - y.pdf).abs() <= 1e-10 * x.pdf, "{x:?} vs {y:?}");
                    for c in 0..3 {
                        assert!((a[c] - b[c]).abs() <= 1e-6 * a[c].abs(), "{a:?} vs {b:?}");
                    }
                }
                (None, None) => {}
                other => panic!("{other:?}"),
            }
        }
    }

    #[test]
    fn below_horizon_and_nan_give_zero() {
        check_invalid_inputs_give_zero(&plastic());
        check_invalid_inputs_give_zero(&three());
    }

    #[test]
    fn spectral_parameters_follow_eval_wavelength() {
        let ch = Channels::linspace(400.0, 700.0, 4).unwrap();
        let s = Sum::new(
            vec![
                Box::new(Lambert::new(Value::Rgb([0.1, 0.2, 0.3]), &ch).unwrap()),
                Box::new(Ward::new(Value::Rgb([0.3, 0.2, 0.1]), 0.1, 0.2, &ch).unwrap()),
            ],
            Some(vec![0.5, 2.0]),
            &ch,
        )
        .unwrap();
        check_eval_wavelength_matches_channels(&s);
    }

    #[test]
    fn albedo_is_the_weighted_sum() {
        let s = plastic();
        let wi = geometry::spherical(0.7, 0.1);
        let (mut a, mut q) = ([0.0; 3], [0.0; 3]);
        s.albedo(wi, &mut a);
        crate::analysis::albedo::quadrature(&s, wi, &mut q);
        for c in 0..3 {
            assert!((a[c] - q[c]).abs() < 1e-6, "{a:?} vs {q:?}");
        }
    }

    #[test]
    fn sample_weight_and_pdf_are_consistent() {
        check_sampling_consistency(&plastic(), &test_wos(), 2000);
        check_sampling_consistency(&three(), &test_wos(), 2000);
    }

    #[test]
    fn mixture_sampler_passes_chi_square_plastic() {
        chi2_models(&[&plastic()]);
    }

    #[test]
    fn mixture_sampler_passes_chi_square_three_terms() {
        chi2_models(&[&*THREE]);
    }

    static THREE: std::sync::LazyLock<Sum> = std::sync::LazyLock::new(three);

    proptest! {
        #[test]
        fn reciprocal(a in dir_strategy(), b in dir_strategy()) {
            check_reciprocity(&*THREE, a, b)?;
        }
    }
}
