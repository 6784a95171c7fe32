//! Analytic BRDF models, one family per file, all behind the [`Brdf`](crate::Brdf) trait.
//!
//! Each model is written with the names of its paper or of the lecture so a reader can check it
//! against the equation. Models are built from a [`ModelSpec`] with [`build`]; parameters are
//! resolved per channel at construction so `eval` never allocates.

pub mod lambert;

use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::spec::ModelSpec;
use crate::spectrum::Channels;

/// Builds the model a (validated) spec describes for a channel set.
pub fn build(spec: &ModelSpec, channels: &Channels) -> Result<Box<dyn Brdf>> {
    Ok(match spec {
        ModelSpec::Lambert { kd } => Box::new(lambert::Lambert::new(kd.clone(), channels)?),
        other => {
            return Err(Error::Unsupported(format!(
                "model `{}` is not implemented yet",
                other.name()
            )));
        }
    })
}
