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
use crate::spectrum::{Channels, Value};

fn one() -> Value {
    Value::Grey(1.0)
}

/// How the pumped-up Phong model symmetrizes cos θ′ (the lecture's X).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PumpX {
    /// X = (cos θ′ + cos θ) / 2.
    Mean,
    /// X = cos θ′ · cos θ.
    Product,
    /// X = sqrt(cos θ′ · cos θ).
    Sqrt,
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

/// One entry of [`MODELS`]: a model's name, parameters and description (for `brdftab models`).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ModelInfo {
    /// The `"model"` tag.
    pub name: &'static str,
    /// Parameters with their meaning.
    pub params: &'static str,
    /// One line of description.
    pub description: &'static str,
    /// An example spec.
    pub example: &'static str,
}

/// Every model, for listings and help.
pub const MODELS: &[ModelInfo] = &[
    ModelInfo {
        name: "lambert",
        params: "kd: Value",
        description: "diffuse, f = k_d; albedo k_d·π (energy conserving for k_d ≤ 1/π)",
        example: r#"{"model": "lambert", "kd": 0.3}"#,
    },
    ModelInfo {
        name: "mirror",
        params: "fresnel: Fresnel = \"none\"",
        description: "ideal reflector (delta), direction 2(N·V)N − V, k_r = Fresnel",
        example: r#"{"model": "mirror", "fresnel": {"conductor": "Ag"}}"#,
    },
    ModelInfo {
        name: "refractor",
        params: "eta: Value",
        description: "ideal refraction (delta), Snell's law, weight 1 − F; total internal reflection → none",
        example: r#"{"model": "refractor", "eta": 1.5}"#,
    },
    ModelInfo {
        name: "phong",
        params: "ks: Value, n: number",
        description: "original Phong, k_s cos^n ψ / cos θ′ (not reciprocal)",
        example: r#"{"model": "phong", "ks": 0.5, "n": 20}"#,
    },
    ModelInfo {
        name: "reciprocal_phong",
        params: "ks: Value, n: number",
        description: "reciprocal Phong, k_s cos^n ψ; albedo 2π k_s/(n+2) at normal incidence",
        example: r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 50}"#,
    },
    ModelInfo {
        name: "max_phong",
        params: "ks: Value, n: number",
        description: "max Phong, k_s cos^n ψ / max(cos θ′, cos θ)",
        example: r#"{"model": "max_phong", "ks": 0.5, "n": 50}"#,
    },
    ModelInfo {
        name: "pumped_phong",
        params: "ks: Value, n: number, x: \"mean\" | \"product\" | \"sqrt\"",
        description: "pumped-up reciprocal Phong, k_s cos^n ψ / X with a symmetric X",
        example: r#"{"model": "pumped_phong", "ks": 0.5, "n": 50, "x": "mean"}"#,
    },
    ModelInfo {
        name: "cook_torrance",
        params: "m: number, ks: Value = 1, fresnel: Fresnel = \"none\"",
        description: "Cook-Torrance, D·G·F/(4 (N·V)(N·L)), normalized Beckmann D, V-cavity G, F at L·H",
        example: r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#,
    },
    ModelInfo {
        name: "blinn_phong",
        params: "ks: Value, n: number",
        description: "normalized Blinn-Phong, k_s (n+8)/(8π) cos^n θh",
        example: r#"{"model": "blinn_phong", "ks": 0.5, "n": 100}"#,
    },
    ModelInfo {
        name: "ggx",
        params: "alpha | alpha_x + alpha_y: number, ks: Value = 1, fresnel: Fresnel = \"none\"",
        description: "GGX / Trowbridge-Reitz microfacet model, k_s D G2 F(wi·h) / (4 cos θi cos θo), Smith height-correlated G2, isotropic or anisotropic; visible-normal sampling",
        example: r#"{"model": "ggx", "alpha": 0.1, "fresnel": {"conductor": "Cu"}}"#,
    },
    ModelInfo {
        name: "ward",
        params: "ks: Value, alpha_x: number, alpha_y: number",
        description: "Ward (1992) anisotropic Gaussian lobe, k_s exp(−tan²θh (cos²φh/α_x² + sin²φh/α_y²)) / (4π α_x α_y √(cos θi cos θo)); not energy conserving at grazing angles",
        example: r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
    },
    ModelInfo {
        name: "oren_nayar",
        params: "kd: Value, sigma: radians",
        description: "Oren-Nayar rough diffuse (qualitative model), k_d (A + B max(0, cos Δφ) sin α tan β); sigma = 0 is Lambert",
        example: r#"{"model": "oren_nayar", "kd": 0.25, "sigma": 0.3}"#,
    },
    ModelInfo {
        name: "sum",
        params: "terms: [spec, ...], weights: [number, ...] = all 1",
        description: "weighted sum of models, e.g. diffuse + specular; sampling picks a term with probability ∝ weight × albedo",
        example: r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2}, {"model": "cook_torrance", "m": 0.2}]}"#,
    },
];

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
        let text = std::fs::read_to_string(path.as_ref()).map_err(|e| Error::io(&path, e))?;
        Self::parse(&text).map_err(|e| match e {
            Error::Json { source, .. } => Error::Json {
                context: path.as_ref().display().to_string(),
                source,
            },
            other => other,
        })
    }

    /// The `"model"` tag of this spec.
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

    /// The spec as compact JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("specs always serialize")
    }

    /// Checks every parameter (finite, in range), naming the field on error.
    pub fn validate(&self) -> Result<()> {
        self.validate_at("")
    }

    fn validate_at(&self, prefix: &str) -> Result<()> {
        let f = |name: &str| format!("{prefix}{name}");
        let nonneg = |name: &str, x: f64| -> Result<()> {
            if !x.is_finite() || x < 0.0 {
                return Err(Error::spec(
                    f(name),
                    format!("{x} must be a finite number ≥ 0"),
                ));
            }
            Ok(())
        };
        let positive = |name: &str, x: f64| -> Result<()> {
            if !x.is_finite() || x <= 0.0 {
                return Err(Error::spec(
                    f(name),
                    format!("{x} must be a finite number > 0"),
                ));
            }
            Ok(())
        };
        match self {
            ModelSpec::Lambert { kd } => kd.validate(&f("kd"), 0.0),
            ModelSpec::Mirror { .. } => Ok(()), // Fresnel validated when resolved.
            ModelSpec::Refractor { eta } => {
                eta.validate(&f("eta"), 0.0)?;
                if eta.numbers().iter().any(|&x| x <= 0.0) {
                    return Err(Error::spec(f("eta"), "must be > 0"));
                }
                Ok(())
            }
            ModelSpec::Phong { ks, n }
            | ModelSpec::ReciprocalPhong { ks, n }
            | ModelSpec::MaxPhong { ks, n }
            | ModelSpec::PumpedPhong { ks, n, .. }
            | ModelSpec::BlinnPhong { ks, n } => {
                ks.validate(&f("ks"), 0.0)?;
                nonneg("n", *n)
            }
            ModelSpec::CookTorrance { m, ks, .. } => {
                ks.validate(&f("ks"), 0.0)?;
                positive("m", *m)
            }
            ModelSpec::Ggx {
                alpha,
                alpha_x,
                alpha_y,
                ks,
                ..
            } => {
                ks.validate(&f("ks"), 0.0)?;
                match (alpha, alpha_x, alpha_y) {
                    (Some(a), None, None) => positive("alpha", *a),
                    (None, Some(ax), Some(ay)) => {
                        positive("alpha_x", *ax)?;
                        positive("alpha_y", *ay)
                    }
                    _ => Err(Error::spec(
                        f("alpha"),
                        "give either `alpha` or both `alpha_x` and `alpha_y`",
                    )),
                }
            }
            ModelSpec::Ward {
                ks,
                alpha_x,
                alpha_y,
            } => {
                ks.validate(&f("ks"), 0.0)?;
                positive("alpha_x", *alpha_x)?;
                positive("alpha_y", *alpha_y)
            }
            ModelSpec::OrenNayar { kd, sigma } => {
                kd.validate(&f("kd"), 0.0)?;
                nonneg("sigma", *sigma)
            }
            ModelSpec::Sum { terms, weights } => {
                if terms.is_empty() {
                    return Err(Error::spec(f("terms"), "a sum needs at least one term"));
                }
                if let Some(w) = weights {
                    if w.len() != terms.len() {
                        return Err(Error::spec(
                            f("weights"),
                            format!("{} weights for {} terms", w.len(), terms.len()),
                        ));
                    }
                    for (i, &x) in w.iter().enumerate() {
                        nonneg(&format!("weights[{i}]"), x)?;
                    }
                }
                for (i, t) in terms.iter().enumerate() {
                    t.validate_at(&format!("{prefix}terms[{i}]."))?;
                }
                Ok(())
            }
        }
    }

    /// Builds the model for `channels` (validating first).
    pub fn build(&self, channels: &Channels) -> Result<Box<dyn Brdf + Send + Sync>> {
        self.validate()?;
        crate::models::build(self, channels)
    }
}

// The JSON form is internally tagged (`{"model": "lambert", "kd": ..}`), but serde's internally
// tagged enums buffer their content and lose the field path of errors. So the derive above makes
// the externally tagged form (`{"lambert": {"kd": ..}}`) available as inherent functions
// (`remote = "Self"`), and these impls convert at the top level. Errors carry the field path as
// "at `terms[1].ks`: message", merged across nested sums.
impl Serialize for ModelSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::Error as _;
        let ext =
            ModelSpec::serialize(self, serde_json::value::Serializer).map_err(S::Error::custom)?;
        let mut out = serde_json::Map::new();
        out.insert(
            "model".into(),
            serde_json::Value::String(self.name().into()),
        );
        if let serde_json::Value::Object(o) = ext
            && let Some((_, serde_json::Value::Object(fields))) = o.into_iter().next()
        {
            out.extend(fields);
        }
        serde_json::Value::Object(out).serialize(s)
    }
}

impl<'de> Deserialize<'de> for ModelSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let v = serde_json::Value::deserialize(d)?;
        let serde_json::Value::Object(mut o) = v else {
            return Err(D::Error::custom("at `model`: a spec must be a JSON object"));
        };
        let name = match o.remove("model") {
            Some(serde_json::Value::String(s)) => s,
            Some(other) => {
                return Err(D::Error::custom(format!(
                    "at `model`: expected a model name, got {other}"
                )));
            }
            None => return Err(D::Error::custom("at `model`: missing field `model`")),
        };
        let mut ext = serde_json::Map::new();
        ext.insert(name, serde_json::Value::Object(o));
        let mut track = serde_path_to_error::Track::new();
        let de = serde_path_to_error::Deserializer::new(serde_json::Value::Object(ext), &mut track);
        ModelSpec::deserialize(de).map_err(|e: serde_json::Error| {
            // The tracked path starts with the variant name (`lambert.kd`): drop it.
            let path = track.path().to_string();
            let path = path.split_once('.').map(|(_, p)| p).unwrap_or("");
            let msg = e.to_string();
            // A nested spec (a term of a sum) reports "at `inner`: msg": join the paths.
            let (inner, msg) = match msg.strip_prefix("at `").and_then(|r| r.split_once("`: ")) {
                Some((p, m)) => (p.to_string(), m.to_string()),
                None => (String::new(), msg),
            };
            let full = match (path.is_empty(), inner.is_empty()) {
                (true, true) => "model".to_string(),
                (false, true) => path.to_string(),
                (true, false) => inner,
                (false, false) => format!("{path}.{inner}"),
            };
            D::Error::custom(format!("at `{full}`: {msg}"))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_example_parses_and_round_trips() {
        for m in MODELS {
            let s = ModelSpec::parse(m.example).unwrap_or_else(|e| panic!("{}: {e}", m.name));
            assert_eq!(s.name(), m.name);
            let back = ModelSpec::parse(&s.to_json()).unwrap();
            assert_eq!(back, s);
        }
    }

    #[test]
    fn unknown_field_is_named() {
        let e = ModelSpec::parse(r#"{"model": "lambert", "kd": 0.3, "kx": 1}"#).unwrap_err();
        assert!(e.to_string().contains("kx"), "{e}");
    }

    #[test]
    fn unknown_model_is_an_error() {
        let e = ModelSpec::parse(r#"{"model": "bogus"}"#).unwrap_err();
        assert!(e.to_string().contains("bogus"), "{e}");
    }

    #[test]
    fn negative_parameter_is_named_with_path() {
        let e = ModelSpec::parse(
            r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.1}, {"model": "reciprocal_phong", "ks": -1, "n": 3}]}"#,
        )
        .unwrap_err();
        assert!(e.to_string().contains("terms[1].ks"), "{e}");
        let e = ModelSpec::parse(r#"{"model": "phong", "ks": 1, "n": -3}"#).unwrap_err();
        assert!(e.to_string().contains("`n`"), "{e}");
    }

    #[test]
    fn wrong_type_names_the_field() {
        let e = ModelSpec::parse(r#"{"model": "lambert", "kd": "red"}"#).unwrap_err();
        assert!(e.to_string().contains("kd"), "{e}");
        let e =
            ModelSpec::parse(r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"eta": [1, 2]}}"#)
                .unwrap_err();
        assert!(e.to_string().contains("fresnel"), "{e}");
    }

    #[test]
    fn missing_field_and_bad_json() {
        assert!(ModelSpec::parse(r#"{"model": "lambert"}"#).is_err());
        assert!(matches!(ModelSpec::parse("{"), Err(Error::Json { .. })));
    }
}
