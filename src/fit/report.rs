//! What a fit reports: [`FitResult`], its parameters ([`FittedParam`]) and starts
//! ([`StartResult`]), and the notes on parameters that ended at a bound.

use serde::Serialize;

use super::Bounds;
use super::params::Param;
use super::problem::from_free;
use crate::spec::ModelSpec;

/// A fitted parameter's final value(s).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FittedParam {
    /// Path into the spec.
    pub path: String,
    /// One value per channel, or one.
    pub value: Vec<f64>,
    /// The bounds in force.
    pub bounds: Bounds,
    /// True when a value ended within 0.1% (of the range, in its scale) of a bound.
    pub at_bound: bool,
}

impl FittedParam {
    /// The parameters `params` at the free variables `t` of a fit (one entry per parameter,
    /// `at_bound` where a value's position in its bounds is within 10⁻³ of either end).
    pub(super) fn all(params: &[Param], t: &[f64]) -> Vec<FittedParam> {
        let x = from_free(params, t);
        let mut off = 0;
        params
            .iter()
            .map(|p| {
                let value = x[off..off + p.width].to_vec();
                off += p.width;
                FittedParam {
                    path: p.path.clone(),
                    at_bound: value.iter().any(|&v| {
                        let u = p.bounds.to_unit(v);
                        !(1e-3..=1.0 - 1e-3).contains(&u)
                    }),
                    value,
                    bounds: p.bounds,
                }
            })
            .collect()
    }
}

/// The outcome of one start.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StartResult {
    /// Parameter values at the start (flattened, in parameter order).
    pub initial: Vec<f64>,
    /// Parameter values at the end.
    pub fitted: Vec<f64>,
    /// The least-squares objective ½ Σ r² / (pairs · channels) at the end.
    pub objective: f64,
    /// Relative RMSE on the fitting pairs.
    pub rmse: f64,
    /// LM iterations (Jacobian evaluations).
    pub iterations: usize,
    /// Model evaluations over all pairs (residual vectors, including those of the Jacobians).
    pub evaluations: usize,
    /// Why LM stopped.
    pub termination: String,
}

/// The result of [`fit`](super::fit).
#[derive(Debug, Clone, Serialize)]
pub struct FitResult {
    /// The fitted spec (valid, builds, usable as a SOURCE).
    pub spec: ModelSpec,
    /// Cosine-weighted relative RMSE of the fitted spec against the source on held-out pairs
    /// drawn like the fitting pairs (see the module docs).
    pub rmse: f64,
    /// `analysis::accuracy::compare` on uniform pairs over the whole hemisphere: relative RMSE.
    pub rmse_uniform: f64,
    /// `analysis::accuracy::compare`: maximum relative error.
    pub max_rel_uniform: f64,
    /// Relative RMSE on the fitting pairs.
    pub rmse_fit: f64,
    /// The objective of the best start.
    pub objective: f64,
    /// LM iterations of the best start.
    pub iterations: usize,
    /// Model evaluations over all starts.
    pub evaluations: usize,
    /// Index of the best start.
    pub best_start: usize,
    /// The fitted parameters.
    pub params: Vec<FittedParam>,
    /// Every start.
    pub starts: Vec<StartResult>,
    /// Number of pairs.
    pub pairs: usize,
    /// Log-space residuals were used.
    pub log: bool,
    /// Wall-clock time of the fit in seconds.
    pub seconds: f64,
}

impl FitResult {
    /// One line per parameter whose value ended at a bound (`kd = [..] ended at a bound of
    /// 0..0.38 (...)`): the data pushed against it, and a wider `--params` range may fit
    /// better. What the CLI notes on stderr.
    ///
    /// A value held at a lower bound of 0 (a `kd` or `ks` of 0) is another case: the data
    /// would take it below 0, which no bound may allow, so the note does not suggest wider
    /// bounds. It says what this means: the source has no such term, or the model lacks
    /// something the source has and the term was given up to make room. (A lambert+ggx fit to
    /// the clear-coated RGL paint `cc_ibiza_sunset` ends with `kd = 0`, the true minimum of
    /// the loss — scipy's bounded least squares on the same pairs agrees to 8 digits — because
    /// its lobe has no Fresnel term for the clear coat's grazing rise; with `--fresnel schlick`
    /// the diffuse term comes back, kd ≈ (0.13, 0.002, 0.05), and the RMSE falls from 0.55 to
    /// 0.19.)
    pub fn bound_notes(&self) -> Vec<String> {
        (self.params.iter().filter(|p| p.at_bound))
            .map(|p| {
                let at_zero = p.bounds.lo == 0.0
                    && (p.value.iter())
                        .filter(|&&v| !(1e-3..=1.0 - 1e-3).contains(&p.bounds.to_unit(v)))
                        .all(|&v| p.bounds.to_unit(v) < 0.5);
                if at_zero {
                    format!(
                        "{} = {:?} ended at its lower bound 0: the data would take it below 0. \
                         The source has no such term, or the model lacks something the source \
                         has (a Fresnel term: --fresnel schlick; another lobe) and gave this \
                         term up to make room",
                        p.path, p.value
                    )
                } else {
                    format!(
                        "{} = {:?} ended at a bound of {}..{} (--params {}=LO:HI moves it)",
                        p.path, p.value, p.bounds.lo, p.bounds.hi, p.path
                    )
                }
            })
            .collect()
    }
}
