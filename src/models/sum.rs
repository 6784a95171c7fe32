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
//! One-sample mixture: for viewing direction wo a term is chosen with probability
//! p_j(wo) ∝ w_j · â_j(cos θo), where â_j is an estimate of the term's albedo precomputed at
//! construction at [`TABLE_SIZE`] values of cos θo (cell centres, (k + ½)/[`TABLE_SIZE`]) and
//! interpolated linearly (constant beyond the first and last centres). â_j is the mean over
//! channels of the term's [`Brdf::albedo`] (averaged over φo = 0 and π/2 for anisotropic terms);
//! for delta terms, which [`Brdf::albedo`] may not cover, it is the mean sample weight over a
//! stratified 4 × 4 grid. Each â_j is floored at 10⁻³ of its own maximum so that a term that
//! reflects anywhere is never entirely excluded by a poor estimate. For a smooth sample wi the
//! density is the full mixture pdf = Σ_j p_j pdf_j(wi, wo) and the weight is computed from the
//! whole sum, f_r(wi, wo) cos θi / pdf, so the estimator stays unbiased however poor the
//! albedo estimates are — they only affect variance.

use glam::{DVec2, DVec3};
use std::f64::consts::FRAC_PI_2;

use crate::brdf::{Brdf, BrdfSample, Flags};
use crate::error::{Error, Result};
use crate::geometry;
use crate::spectrum::{Channels, MAX_CHANNELS};

/// Number of cos θo entries in each term's albedo table.
pub const TABLE_SIZE: usize = 24;

/// A weighted sum of BRDFs.
pub struct Sum {
    channels: Channels,
    terms: Vec<Box<dyn Brdf>>,
    weights: Vec<f64>,
    /// Per term: w_j · â_j at cos θo = (k + ½)/TABLE_SIZE.
    select: Vec<[f64; TABLE_SIZE]>,
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
        terms: Vec<Box<dyn Brdf>>,
        weights: Option<Vec<f64>>,
        channels: &Channels,
    ) -> Result<Self> {
        if terms.is_empty() {
            return Err(Error::spec("terms", "a sum needs at least one term"));
        }
        if channels.len() > MAX_CHANNELS {
            return Err(Error::arg(
                "channels",
                format!("{} channels, at most {MAX_CHANNELS}", channels.len()),
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
        };
        let select = terms
            .iter()
            .zip(&weights)
            .map(|(t, &w)| selection_row(t.as_ref(), w))
            .collect();
        Ok(Sum {
            channels: channels.clone(),
            terms,
            weights,
            select,
            flags,
        })
    }

    /// The terms and their weights.
    pub fn terms(&self) -> impl Iterator<Item = (&dyn Brdf, f64)> {
        self.terms
            .iter()
            .map(|t| t.as_ref())
            .zip(self.weights.iter().copied())
    }

    /// The unnormalized selection weight w_j â_j(cos θo) of term `j`.
    #[inline]
    fn selection(&self, j: usize, cos_o: f64) -> f64 {
        let x = (cos_o * TABLE_SIZE as f64 - 0.5).clamp(0.0, (TABLE_SIZE - 1) as f64);
        let k = (x as usize).min(TABLE_SIZE - 2);
        let t = x - k as f64;
        let row = &self.select[j];
        (1.0 - t) * row[k] + t * row[k + 1]
    }

    /// The probabilities p_j(wo) of choosing each term, normalized (for inspection and tests).
    /// All zero when no term reflects towards `wo`.
    pub fn selection_probabilities(&self, wo: DVec3) -> Vec<f64> {
        let cos_o = geometry::normalize(wo).map_or(0.0, |w| w.z);
        let s: Vec<f64> = (0..self.terms.len())
            .map(|j| self.selection(j, cos_o))
            .collect();
        let total: f64 = s.iter().sum();
        if total > 0.0 {
            s.iter().map(|x| x / total).collect()
        } else {
            vec![0.0; s.len()]
        }
    }

    #[inline]
    fn total_selection(&self, cos_o: f64) -> f64 {
        (0..self.terms.len())
            .map(|j| self.selection(j, cos_o))
            .sum()
    }

    /// [`Brdf::sample`] with scratch arrays of `N` ≥ channels entries (4 for RGB, so the
    /// per-call scratch is not a kilobyte of zeroes).
    fn sample_n<const N: usize>(
        &self,
        wo: DVec3,
        u: DVec2,
        weight: &mut [f32],
    ) -> Option<BrdfSample> {
        let wo = geometry::unit(wo)?;
        if wo.z <= 0.0 {
            return None;
        }
        let total = self.total_selection(wo.z);
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        // Choose term j by u.x and reuse the remainder of u.x within its interval.
        let target = u.x * total;
        let mut cum = 0.0;
        let mut chosen = None;
        let mut last = None;
        for j in 0..self.terms.len() {
            let s = self.selection(j, wo.z);
            if s <= 0.0 {
                continue;
            }
            if target < cum + s {
                chosen = Some((j, s, ((target - cum) / s).clamp(0.0, 1.0 - f64::EPSILON)));
                break;
            }
            cum += s;
            last = Some(j);
        }
        // Rounding can leave target ≥ the accumulated total: that is the end of the last term.
        let chosen =
            chosen.or_else(|| last.map(|j| (j, self.selection(j, wo.z), 1.0 - f64::EPSILON)));
        let (j, s, ux) = chosen?;
        let pj = s / total;
        let c = self.channels.len();
        let mut tw = [0.0f32; N];
        let smp = self.terms[j].sample(wo, DVec2::new(ux, u.y), &mut tw[..c])?;
        if smp.delta {
            let scale = self.weights[j] / pj;
            for (o, &t) in weight[..c].iter_mut().zip(&tw[..c]) {
                *o = (scale * t as f64) as f32;
            }
            return Some(BrdfSample {
                wi: smp.wi,
                pdf: pj * smp.pdf,
                delta: true,
            });
        }
        // The chosen term already knows its density and, through its weight, its f·cos θi =
        // weight · pdf: only the other terms are evaluated.
        let mut pdf = s / total * smp.pdf;
        let mut fcos = [0.0f64; N];
        for k in 0..c {
            fcos[k] = self.weights[j] * tw[k] as f64 * smp.pdf;
        }
        let cos_i = smp.wi.z.abs();
        let mut tmp = [0.0f32; N];
        for (k, t) in self.terms.iter().enumerate() {
            if k == j {
                continue;
            }
            let sk = self.selection(k, wo.z);
            let w = self.weights[k];
            let pk = if w != 0.0 {
                let pk = t.eval_pdf(smp.wi, wo, &mut tmp[..c]);
                for ch in 0..c {
                    fcos[ch] += w * tmp[ch] as f64 * cos_i;
                }
                pk
            } else if sk > 0.0 {
                t.pdf(smp.wi, wo)
            } else {
                0.0
            };
            if sk > 0.0 {
                pdf += sk / total * pk;
            }
        }
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        for (o, &fk) in weight[..c].iter_mut().zip(&fcos[..c]) {
            *o = (fk / pdf) as f32;
        }
        Some(BrdfSample {
            wi: smp.wi,
            pdf,
            delta: false,
        })
    }

    /// The smooth mixture density Σ_j p_j pdf_j(wi, wo) for `total` = Σ_j w_j â_j.
    fn mixture_pdf(&self, wi: DVec3, wo: DVec3, total: f64) -> f64 {
        let mut pdf = 0.0;
        for (j, t) in self.terms.iter().enumerate() {
            let s = self.selection(j, wo.z);
            if s > 0.0 {
                pdf += s / total * t.pdf(wi, wo);
            }
        }
        pdf
    }
}

/// w · â(cos θo) at the table's cos θo values, floored at 10⁻³ of the row's maximum.
fn selection_row(term: &dyn Brdf, w: f64) -> [f64; TABLE_SIZE] {
    let mut row = [0.0; TABLE_SIZE];
    if w == 0.0 {
        return row;
    }
    let flags = term.flags();
    let c = term.channels().len().min(MAX_CHANNELS);
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
            let a = if flags.delta {
                mean_sample_weight(term, wo)
            } else {
                let mut a = [0.0f64; MAX_CHANNELS];
                term.albedo(wo, &mut a[..c]);
                a[..c].iter().sum::<f64>() / c as f64
            };
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

/// The mean over channels and a stratified 4 × 4 grid of the term's sample weights at `wo`:
/// an unbiased estimate of ∫ f cos θi dωi (for delta terms, exact when the weight is constant).
fn mean_sample_weight(term: &dyn Brdf, wo: DVec3) -> f64 {
    let c = term.channels().len().min(MAX_CHANNELS);
    let n = 4;
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
        let c = self.channels.len();
        let mut acc = [0.0f64; MAX_CHANNELS];
        let mut tmp = [0.0f32; MAX_CHANNELS];
        for (t, &w) in self.terms.iter().zip(&self.weights) {
            if w == 0.0 {
                continue;
            }
            t.eval(wi, wo, &mut tmp[..c]);
            for k in 0..c {
                acc[k] += w * tmp[k] as f64;
            }
        }
        for (o, a) in out[..c].iter_mut().zip(&acc[..c]) {
            *o = *a as f32;
        }
    }

    fn eval_wavelength(&self, wi: DVec3, wo: DVec3, nm: f64) -> f64 {
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
        if self.channels.len() <= 4 {
            self.sample_n::<4>(wo, u, weight)
        } else {
            self.sample_n::<MAX_CHANNELS>(wo, u, weight)
        }
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let Some(wo) = geometry::normalize(wo) else {
            return 0.0;
        };
        if wo.z <= 0.0 {
            return 0.0;
        }
        let total = self.total_selection(wo.z);
        if !(total > 0.0 && total.is_finite()) {
            return 0.0;
        }
        self.mixture_pdf(wi, wo, total)
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

    fn lambert(kd: f64) -> Box<dyn Brdf> {
        Box::new(Lambert::new(Value::Grey(kd), &Channels::Rgb).unwrap())
    }

    fn ggx(ax: f64, ay: f64) -> Box<dyn Brdf> {
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
    fn flags_are_the_and_of_terms() {
        assert_eq!(plastic().flags(), Flags::SMOOTH_SYMMETRIC);
        let aniso = Sum::new(vec![lambert(0.2), ggx(0.1, 0.3)], None, &Channels::Rgb).unwrap();
        assert!(!aniso.flags().isotropic && aniso.flags().reciprocal && !aniso.flags().delta);
        let mirror = || -> Box<dyn Brdf> { Box::new(TestMirror(Channels::Rgb, 0.5)) };
        let mixed = Sum::new(vec![lambert(0.2), mirror()], None, &Channels::Rgb).unwrap();
        assert!(!mixed.flags().delta);
        let all = Sum::new(vec![mirror(), mirror()], None, &Channels::Rgb).unwrap();
        assert!(all.flags().delta);
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
