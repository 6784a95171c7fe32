//! Model specs: the one JSON schema that names an analytic BRDF and its parameters.
//!
//! The same schema is used by the CLI (`brdftab eval '{"model": "lambert", "kd": 0.3}'`), stored
//! in database metadata as a table's provenance, and produced by fitting, so a fitted result can
//! be used directly as a source. A spec is parsed with [`ModelSpec::parse`] (errors name the field
//! path, e.g. `terms[1].fresnel.n`), validated, and turned into a `Box<dyn Brdf + Send + Sync>` for a channel
//! set with [`ModelSpec::build`].
//!
//! ```
//! use brdftab::{spec::ModelSpec, spectrum::Channels};
//! let spec = ModelSpec::parse(r#"{"model": "lambert", "kd": [0.2, 0.1, 0.05]}"#).unwrap();
//! let brdf = spec.build(&Channels::Rgb).unwrap();
//! assert!(brdf.flags().reciprocal);
//! assert!(ModelSpec::parse(r#"{"model": "lambert", "kd": -1}"#).is_err());
//! ```

use serde::{Deserialize, Serialize};

use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::fresnel::FresnelSpec;
pub use crate::models::phong::PumpX;
use crate::spectrum::{Channels, Value};

mod build;
mod catalogue;
mod json;
#[cfg(test)]
mod tests;

pub(crate) use build::build;
pub use catalogue::{Bound, Kind, MODELS, ModelInfo, ParamInfo, model_info};
use catalogue::{GGX_RULE, check_param};

fn one() -> Value {
    Value::Grey(1.0)
}

/// An analytic BRDF model and its parameters. Serialized with a `"model"` tag, e.g.
/// `{"model": "reciprocal_phong", "ks": 0.5, "n": 50}`.
///
/// Values (`kd`, `ks`, ...) are grey numbers, RGB triples or sampled spectra ([`Value`]).
/// Angles (`sigma`) are in radians. Unknown fields are rejected.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(remote = "Self", rename_all = "snake_case", deny_unknown_fields)]
pub enum ModelSpec {
    /// Diffuse: f = k_d.
    Lambert {
        /// Diffuse reflectance coefficient k_d (the BRDF value; albedo k_d·π).
        kd: Value,
    },
    /// Ideal mirror (delta): reflects to 2(N·V)N − V with k_r = Fresnel.
    Mirror {
        /// The Fresnel term (default `"none"`: k_r = 1).
        #[serde(default)]
        fresnel: FresnelSpec,
    },
    /// Ideal refraction (delta) into a dielectric of relative index `eta`, weighted by 1 − F.
    Refractor {
        /// Relative index of refraction (inside / outside).
        eta: Value,
    },
    /// Original Phong: k_s cos^n ψ / cos θ′ (not reciprocal).
    Phong {
        /// Specular coefficient k_s.
        ks: Value,
        /// Exponent n.
        n: f64,
    },
    /// Reciprocal Phong: k_s cos^n ψ.
    ReciprocalPhong {
        /// Specular coefficient k_s.
        ks: Value,
        /// Exponent n.
        n: f64,
    },
    /// Max Phong: k_s cos^n ψ / max(cos θ′, cos θ).
    MaxPhong {
        /// Specular coefficient k_s.
        ks: Value,
        /// Exponent n.
        n: f64,
    },
    /// Pumped-up reciprocal Phong: k_s cos^n ψ / X.
    PumpedPhong {
        /// Specular coefficient k_s.
        ks: Value,
        /// Exponent n.
        n: f64,
        /// Which symmetric X.
        x: PumpX,
    },
    /// Cook-Torrance: D·G·F / (4 (N·V)(N·L)) with normalized Beckmann D and V-cavity G.
    CookTorrance {
        /// Beckmann roughness m (RMS slope).
        m: f64,
        /// Scale k_s (default 1).
        #[serde(default = "one")]
        ks: Value,
        /// The Fresnel term at L·H (default `"none"`).
        #[serde(default)]
        fresnel: FresnelSpec,
    },
    /// Normalized Blinn-Phong: k_s (n + 8)/(8π) cos^n θh.
    BlinnPhong {
        /// Specular coefficient k_s (≈ normal-incidence albedo).
        ks: Value,
        /// Exponent n.
        n: f64,
    },
    /// GGX (Trowbridge-Reitz) microfacet model with Smith masking-shadowing; isotropic with
    /// `alpha`, anisotropic with `alpha_x` and `alpha_y` (tangent = local x).
    Ggx {
        /// Isotropic roughness α (exclusive with alpha_x / alpha_y).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        alpha: Option<f64>,
        /// Roughness along x.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        alpha_x: Option<f64>,
        /// Roughness along y.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        alpha_y: Option<f64>,
        /// Scale k_s (default 1).
        #[serde(default = "one")]
        ks: Value,
        /// The Fresnel term (default `"none"`).
        #[serde(default)]
        fresnel: FresnelSpec,
    },
    /// Ward (1992) anisotropic Gaussian lobe.
    Ward {
        /// Specular reflectance ρ_s.
        ks: Value,
        /// Roughness along x.
        alpha_x: f64,
        /// Roughness along y.
        alpha_y: f64,
    },
    /// Oren-Nayar (1994, qualitative model) rough diffuse; `kd` as in Lambert (σ = 0 is Lambert).
    OrenNayar {
        /// Diffuse coefficient (the BRDF value at σ = 0).
        kd: Value,
        /// Roughness σ in radians (standard deviation of facet slope angle).
        sigma: f64,
    },
    /// A weighted sum of models, e.g. diffuse + specular.
    Sum {
        /// The terms.
        terms: Vec<ModelSpec>,
        /// Optional weight per term (default 1 each).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        weights: Option<Vec<f64>>,
    },
}

impl std::str::FromStr for ModelSpec {
    type Err = Error;

    /// [`ModelSpec::parse`]: `r#"{"model": "lambert", "kd": 0.5}"#.parse::<ModelSpec>()`.
    fn from_str(json: &str) -> Result<Self> {
        ModelSpec::parse(json)
    }
}

impl ModelSpec {
    /// Parses a spec from JSON text; errors name the field path.
    pub fn parse(json: &str) -> Result<Self> {
        let value: serde_json::Value = serde_json::from_str(json).map_err(|e| Error::Json {
            context: "spec".into(),
            source: e,
        })?;
        let spec = serde_json::from_value::<ModelSpec>(value).map_err(|e| {
            let msg = e.to_string();
            match msg.strip_prefix("at `").and_then(|r| r.split_once("`: ")) {
                Some((path, rest)) => Error::spec(path, rest),
                None => Error::spec("model", msg),
            }
        })?;
        spec.validate()?;
        Ok(spec)
    }

    /// Reads a spec from a `.json` file.
    pub fn from_file(path: impl AsRef<std::path::Path>) -> Result<Self> {
        crate::files::require_regular(path.as_ref())?;
        let text = std::fs::read_to_string(path.as_ref()).map_err(|e| Error::io(&path, e))?;
        Self::parse(&text).map_err(|e| match e {
            Error::Json { source, .. } => Error::Json {
                context: path.as_ref().display().to_string(),
                source,
            },
            other => other,
        })
    }

    /// The `"model"` tag of this spec (the serde form's tag: a test checks that they agree for
    /// every model). Not read from the serde form: that serializes the whole spec, and the
    /// serializer asks each nested spec its name, so the work doubled with every level of
    /// nested sums (a 1 KB spec nesting 20 sums took 29 s to parse; issue #23).
    pub fn name(&self) -> &'static str {
        match self {
            ModelSpec::Lambert { .. } => "lambert",
            ModelSpec::Mirror { .. } => "mirror",
            ModelSpec::Refractor { .. } => "refractor",
            ModelSpec::Phong { .. } => "phong",
            ModelSpec::ReciprocalPhong { .. } => "reciprocal_phong",
            ModelSpec::MaxPhong { .. } => "max_phong",
            ModelSpec::PumpedPhong { .. } => "pumped_phong",
            ModelSpec::CookTorrance { .. } => "cook_torrance",
            ModelSpec::BlinnPhong { .. } => "blinn_phong",
            ModelSpec::Ggx { .. } => "ggx",
            ModelSpec::Ward { .. } => "ward",
            ModelSpec::OrenNayar { .. } => "oren_nayar",
            ModelSpec::Sum { .. } => "sum",
        }
    }

    /// The entry of [`MODELS`] for this spec.
    pub fn info(&self) -> &'static ModelInfo {
        model_info(self.name()).expect("every variant has an entry in MODELS (tested)")
    }

    /// The externally tagged serde form split into (tag, fields).
    fn tagged(&self) -> (Option<String>, serde_json::Map<String, serde_json::Value>) {
        match ModelSpec::serialize(self, serde_json::value::Serializer) {
            Ok(serde_json::Value::Object(o)) => match o.into_iter().next() {
                Some((tag, serde_json::Value::Object(fields))) => (Some(tag), fields),
                Some((tag, _)) => (Some(tag), serde_json::Map::new()),
                None => (None, serde_json::Map::new()),
            },
            _ => (None, serde_json::Map::new()),
        }
    }

    /// The spec as compact JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("specs always serialize")
    }

    /// Checks every parameter (finite, in range), naming the field on error.
    pub fn validate(&self) -> Result<()> {
        self.validate_at("")
    }

    fn validate_at(&self, prefix: &str) -> Result<()> {
        let (_, fields) = self.tagged();
        for p in self.info().params {
            if let Some(v) = fields.get(p.name) {
                check_param(p, &format!("{prefix}{}", p.name), v)?;
            }
        }
        // The rules between parameters (ModelInfo::rule).
        match self {
            ModelSpec::Ggx {
                alpha,
                alpha_x,
                alpha_y,
                ..
            } => match (alpha, alpha_x, alpha_y) {
                (Some(_), None, None) | (None, Some(_), Some(_)) => Ok(()),
                _ => Err(Error::spec(format!("{prefix}alpha"), GGX_RULE)),
            },
            ModelSpec::Sum { terms, weights } => {
                if terms.is_empty() {
                    return Err(Error::spec(
                        format!("{prefix}terms"),
                        "a sum needs at least one term",
                    ));
                }
                if let Some(w) = weights
                    && w.len() != terms.len()
                {
                    return Err(Error::spec(
                        format!("{prefix}weights"),
                        format!("{} weights for {} terms", w.len(), terms.len()),
                    ));
                }
                for (i, t) in terms.iter().enumerate() {
                    t.validate_at(&format!("{prefix}terms[{i}]."))?;
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// Builds the model for `channels` (validating first).
    pub fn build(&self, channels: &Channels) -> Result<Box<dyn Brdf + Send + Sync>> {
        self.validate()?;
        channels.validate()?;
        build(self, channels)
    }
}
