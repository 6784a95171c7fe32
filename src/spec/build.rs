//! From a spec to a model: the constructor of each family in [`crate::models`] called with the
//! spec's parameters.

use super::{GGX_RULE, ModelSpec};
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::models::{
    blinn_phong, cook_torrance, ggx, lambert, mirror, oren_nayar, phong, sum, ward,
};
use crate::spectrum::Channels;

/// Builds the model a (validated) spec describes for a channel set: the constructor of each
/// family in [`crate::models`].
pub(crate) fn build(spec: &ModelSpec, channels: &Channels) -> Result<Box<dyn Brdf + Send + Sync>> {
    Ok(match spec {
        ModelSpec::Lambert { kd } => Box::new(lambert::Lambert::new(kd.clone(), channels)?),
        ModelSpec::Mirror { fresnel } => Box::new(mirror::Mirror::new(fresnel, channels)?),
        ModelSpec::Refractor { eta } => Box::new(mirror::Refractor::new(eta.clone(), channels)?),
        ModelSpec::Phong { ks, n } => Box::new(phong::Phong::original(ks.clone(), *n, channels)?),
        ModelSpec::ReciprocalPhong { ks, n } => {
            Box::new(phong::Phong::reciprocal(ks.clone(), *n, channels)?)
        }
        ModelSpec::MaxPhong { ks, n } => Box::new(phong::Phong::max(ks.clone(), *n, channels)?),
        ModelSpec::PumpedPhong { ks, n, x } => {
            Box::new(phong::Phong::pumped(ks.clone(), *n, *x, channels)?)
        }
        ModelSpec::CookTorrance { m, ks, fresnel } => Box::new(cook_torrance::CookTorrance::new(
            *m,
            ks.clone(),
            fresnel,
            channels,
        )?),
        ModelSpec::BlinnPhong { ks, n } => {
            Box::new(blinn_phong::BlinnPhong::new(ks.clone(), *n, channels)?)
        }
        ModelSpec::Ggx {
            alpha,
            alpha_x,
            alpha_y,
            ks,
            fresnel,
        } => {
            let (ax, ay) = match (alpha, alpha_x, alpha_y) {
                (Some(a), None, None) => (*a, *a),
                (None, Some(ax), Some(ay)) => (*ax, *ay),
                _ => return Err(Error::spec("alpha", GGX_RULE)),
            };
            Box::new(ggx::Ggx::new(
                ax,
                ay,
                ks.clone(),
                fresnel.clone(),
                channels,
            )?)
        }
        ModelSpec::Ward {
            ks,
            alpha_x,
            alpha_y,
        } => Box::new(ward::Ward::new(ks.clone(), *alpha_x, *alpha_y, channels)?),
        ModelSpec::OrenNayar { kd, sigma } => {
            Box::new(oren_nayar::OrenNayar::new(kd.clone(), *sigma, channels)?)
        }
        ModelSpec::Sum { terms, weights } => {
            let built = terms
                .iter()
                .enumerate()
                .map(|(i, t)| build(t, channels).map_err(|e| prefix_field(e, i)))
                .collect::<Result<Vec<_>>>()?;
            Box::new(sum::Sum::new(built, weights.clone(), channels)?)
        }
    })
}

/// Prefixes the field of a spec error from term `i` of a sum with `terms[i].`.
fn prefix_field(e: Error, i: usize) -> Error {
    match e {
        Error::Spec { field, msg } => Error::spec(format!("terms[{i}].{field}"), msg),
        other => other,
    }
}
