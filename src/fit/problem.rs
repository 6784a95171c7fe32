//! The least-squares problem Levenberg-Marquardt solves: parameters in free (unbounded)
//! coordinates, the residuals of a spec against the source's values on the fitting pairs, and
//! their Jacobian by central differences (see the parent module's docs).

use std::cell::Cell;

use levenberg_marquardt::LeastSquaresProblem;
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use serde_json::Value as Json;

use super::pairs::Pairs;
use super::params::{self, Param};
use crate::brdf::Brdf;
use crate::error::Result;
use crate::spec::ModelSpec;
use crate::spectrum::Channels;

pub(super) fn transform(y: f64, log: bool) -> f64 {
    if log { y.max(0.0).ln_1p() } else { y }
}

pub(super) fn to_free(params: &[Param], x: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(x.len());
    let mut off = 0;
    for p in params {
        for &v in &x[off..off + p.width] {
            out.push(p.bounds.to_free(v));
        }
        off += p.width;
    }
    out
}

pub(super) fn from_free(params: &[Param], t: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(t.len());
    let mut off = 0;
    for p in params {
        for &v in &t[off..off + p.width] {
            out.push(p.bounds.from_free(v));
        }
        off += p.width;
    }
    out
}

/// The least-squares problem LM sees: free variables `t`, residuals per pair and channel.
pub(super) struct Problem<'a> {
    pub(super) base: Json,
    pub(super) params: &'a [Param],
    pub(super) channels: &'a Channels,
    pub(super) pairs: &'a Pairs,
    /// Transformed targets (f cos θi, or its log), pair-major.
    pub(super) target: Vec<f64>,
    pub(super) log: bool,
    /// 1/sqrt(number of residuals), so the objective is a mean.
    pub(super) scale: f64,
    pub(super) t: DVector<f64>,
    pub(super) iterations: Cell<usize>,
    pub(super) evaluations: Cell<usize>,
    /// The host's request to stop ([`crate::progress::Progress::cancelled`]): the model's
    /// values are then `None`, which ends the optimizer's start at its next evaluation.
    pub(super) cancel: &'a (dyn Fn() -> bool + Sync),
}

/// Central-difference step in the free variables.
const FD_STEP: f64 = 1e-3;

impl Problem<'_> {
    pub(super) fn spec_at(&self, t: &DVector<f64>) -> Result<ModelSpec> {
        let mut json = self.base.clone();
        let x = from_free(self.params, t.as_slice());
        let mut off = 0;
        for p in self.params {
            params::write(&mut json, p, &x[off..off + p.width], self.channels)?;
            off += p.width;
        }
        spec_from_json(json)
    }

    /// Transformed model values f̂ cos θi at `t`, or `None` if the model cannot be built.
    pub(super) fn model_values(&self, t: &DVector<f64>) -> Option<Vec<f64>> {
        self.evaluations.set(self.evaluations.get() + 1);
        if (self.cancel)() {
            return None;
        }
        let spec = self.spec_at(t).ok()?;
        spec.validate().ok()?;
        let mut terms = Vec::new();
        flatten(&spec, 1.0, self.channels, &mut terms).ok()?;
        let mut v = vec![0.0; self.target.len()];
        for (w, term) in &terms {
            for (a, b) in v.iter_mut().zip(eval_cos(term.as_ref(), self.pairs)) {
                *a += w * b;
            }
        }
        Some(v.into_iter().map(|y| transform(y, self.log)).collect())
    }
}

/// The terms of a (nested) sum with their combined weights, each built on its own: a `Sum`
/// precomputes albedo tables for its sampler when built, which a fit that only evaluates would pay
/// for at every step.
pub(super) fn flatten(
    spec: &ModelSpec,
    weight: f64,
    channels: &Channels,
    out: &mut Vec<(f64, Box<dyn Brdf + Send + Sync>)>,
) -> Result<()> {
    match spec {
        ModelSpec::Sum { terms, weights } => {
            for (i, t) in terms.iter().enumerate() {
                let w = weights.as_ref().map_or(1.0, |w| w[i]);
                flatten(t, weight * w, channels, out)?;
            }
        }
        other => out.push((weight, crate::spec::build(other, channels)?)),
    }
    Ok(())
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.t.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.t.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        let m = self.model_values(&self.t)?;
        Some(DVector::from_iterator(
            m.len(),
            m.iter()
                .zip(&self.target)
                .map(|(a, b)| (a - b) * self.scale),
        ))
    }

    /// Central differences. A per-channel value (width = channel count) is perturbed in all its
    /// channels at once: channel k of f̂ depends only on channel k of the value (values are
    /// resolved per channel), so one pair of evaluations gives all its columns — the classic
    /// colouring of a sparse Jacobian — instead of one pair per channel.
    fn jacobian(&self) -> Option<DMatrix<f64>> {
        self.iterations.set(self.iterations.get() + 1);
        let n = self.t.len();
        let m = self.target.len();
        let c = self.channels.len();
        let inv = self.scale / (2.0 * FD_STEP);
        let mut j = DMatrix::zeros(m, n);
        let mut off = 0;
        for p in self.params {
            let (mut tp, mut tm) = (self.t.clone(), self.t.clone());
            for k in off..off + p.width {
                tp[k] += FD_STEP;
                tm[k] -= FD_STEP;
            }
            let fp = self.model_values(&tp)?;
            let fm = self.model_values(&tm)?;
            for (row, (a, b)) in fp.iter().zip(&fm).enumerate() {
                let col = if p.width == 1 { off } else { off + row % c };
                j[(row, col)] = (a - b) * inv;
            }
            off += p.width;
        }
        Some(j)
    }
}

pub(super) fn spec_from_json(json: Json) -> Result<ModelSpec> {
    ModelSpec::parse(&json.to_string())
}

/// f·cos θi for every pair and channel (pair-major), NaN/inf mapped to 0.
pub(super) fn eval_cos(b: &dyn Brdf, pairs: &Pairs) -> Vec<f64> {
    let c = b.channels().len();
    let mut buf = vec![0.0f32; pairs.len() * c];
    b.eval_batch(&pairs.wi, &pairs.wo, &mut buf);
    buf.iter()
        .enumerate()
        .map(|(k, &v)| {
            let x = v as f64 * pairs.wi[k / c].z;
            if x.is_finite() { x } else { 0.0 }
        })
        .collect()
}
