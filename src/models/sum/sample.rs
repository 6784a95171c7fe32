//! The one-sample mixture sampler of a [`Sum`]: the general path over any number of terms and
//! channels, and the straight-line path for two RGB terms.

use glam::{DVec2, DVec3};

use super::{MAX_TERMS, Sum};
use crate::brdf::{Brdf, BrdfSample};
use crate::geometry;
use crate::spectrum::MAX_CHANNELS;

impl Sum {
    /// [`Brdf::sample`], telling which term drew and from which numbers (`chosen`).
    pub(super) fn sample_chosen(
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
    pub(super) fn sample_n<const N: usize>(
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
}
