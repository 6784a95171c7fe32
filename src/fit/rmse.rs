//! The fit's error measure: the cosine-weighted relative RMSE of a model against a source
//! ([`relative_rmse`]) on a set of pairs, and a start's score (its objective and that RMSE).

use nalgebra::DVector;

use super::Pairs;
use super::problem::{Problem, eval_cos};
use crate::brdf::Brdf;
use crate::error::{Error, Result};

/// Cosine-weighted relative RMSE of `model` against `source` over `pairs`:
/// sqrt(Σ (f̂ − f)² cos² θi / Σ f² cos² θi), summed over every channel. Both must have the same
/// channel count.
pub fn relative_rmse(source: &dyn Brdf, model: &dyn Brdf, pairs: &Pairs) -> Result<f64> {
    let c = source.channels().len();
    if model.channels().len() != c {
        return Err(Error::arg(
            "model",
            format!("{} channels, the source has {c}", model.channels().len()),
        ));
    }
    let f = eval_cos(source, pairs);
    let g = eval_cos(model, pairs);
    // Zeros from a source that failed while it was read (a corrupt table chunk) are its error.
    source.health()?;
    Ok(rel_rmse(&g, &f))
}

pub(super) fn rel_rmse(model: &[f64], target: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (a, b) in model.iter().zip(target) {
        num += (a - b) * (a - b);
        den += b * b;
    }
    if den > 0.0 {
        (num / den).sqrt()
    } else if num == 0.0 {
        0.0
    } else {
        f64::INFINITY
    }
}

/// The objective ½ Σ r² / (pairs · channels) and the relative RMSE against `target_lin`
/// (the source's f_r cos θi, linear) of the model at `t`; both infinite where the model
/// does not build or evaluate there.
pub(super) fn score(problem: &Problem<'_>, t: &DVector<f64>, target_lin: &[f64]) -> (f64, f64) {
    let Some(m) = problem.model_values(t) else {
        return (f64::INFINITY, f64::INFINITY);
    };
    let obj = 0.5
        * m.iter()
            .zip(&problem.target)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
        * problem.scale
        * problem.scale;
    let lin: Vec<f64> = if problem.log {
        m.iter().map(|&y| y.exp_m1()).collect()
    } else {
        m
    };
    (obj, rel_rmse(&lin, target_lin))
}
