//! Evaluation of a [`Sum`]: f_r as the weighted sum of its terms, with and without the
//! mixture density the sampler draws from.

use glam::DVec3;

use super::{MAX_TERMS, Sum};
use crate::geometry;

impl Sum {
    /// [`Brdf::eval`] with scratch arrays of `N` ≥ channels entries.
    pub(super) fn eval_n<const N: usize>(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
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
    pub(super) fn eval_pdf_n<const N: usize>(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) -> f64 {
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
    pub(super) fn mixture_pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
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
