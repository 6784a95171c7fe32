//! The term-selection table of a [`Sum`]: its rows built at construction from each term's
//! estimated albedo, and read per call to choose a term (see the parent module's docs,
//! "Sampling").

use glam::{DVec2, DVec3};
use std::f64::consts::FRAC_PI_2;

use super::{MAX_TERMS, Sum, TABLE_SIZE};
use crate::brdf::Brdf;
use crate::geometry;
use crate::spectrum::MAX_CHANNELS;

impl Sum {
    /// The selection-table bin of cos θo.
    #[inline]
    pub(super) fn bin(cos_o: f64) -> usize {
        ((cos_o * TABLE_SIZE as f64) as usize).min(TABLE_SIZE - 1)
    }

    /// The probabilities p_j(cos θo) of choosing each term into `sel`, and their sum: 1 up to
    /// rounding, or 0 when no term reflects. With two terms the second is 1 − p_0 exactly and
    /// the sum exactly 1, as in the pair sampler.
    #[inline]
    pub(super) fn selections(&self, cos_o: f64, sel: &mut [f64; MAX_TERMS]) -> f64 {
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
}

/// The rows w_j â_j normalized over the terms at each table entry. An entry where no term
/// reflects takes the probabilities of the nearest entry where one does; all rows stay zero when
/// none does anywhere.
pub(super) fn normalized(rows: Vec<[f64; TABLE_SIZE]>) -> Vec<[f64; TABLE_SIZE]> {
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
pub(super) fn selection_row(term: &dyn Brdf, w: f64) -> [f64; TABLE_SIZE] {
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
