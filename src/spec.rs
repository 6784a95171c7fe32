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
use crate::models::{
    blinn_phong, cook_torrance, ggx, lambert, mirror, oren_nayar, phong, sum, ward,
};
use crate::spectrum::{Channels, Value};

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

/// How a parameter's numbers are bounded (checked by [`ModelSpec::validate`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Bound {
    /// No check beyond being a well-formed value (enums, Fresnel specs, nested specs).
    None,
    /// Every number finite and ≥ 0.
    NonNegative,
    /// Every number finite and > 0.
    Positive,
}

/// What a parameter holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// A [`Value`]: grey number, RGB triple or sampled spectrum.
    Value,
    /// One number.
    Number,
    /// One angle in radians.
    Radians,
    /// A [`FresnelSpec`].
    Fresnel,
    /// One of the listed names.
    Choice(&'static [&'static str]),
    /// A list of specs (the terms of a sum).
    Specs,
    /// A list of numbers, one per term.
    Numbers,
}

/// One parameter of a model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ParamInfo {
    /// Its JSON field name.
    pub name: &'static str,
    /// What it holds.
    pub kind: Kind,
    /// Its bound.
    pub bound: Bound,
    /// Its default when omitted, as written in JSON (`None`: required, or exclusive with
    /// another parameter as [`ModelInfo::rule`] says).
    pub default: Option<&'static str>,
}

/// One entry of [`MODELS`]: a model's name, parameters with their bounds, description and
/// example. [`ModelSpec::validate`] checks a spec against its entry, `brdftab models` lists them.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ModelInfo {
    /// The `"model"` tag.
    pub name: &'static str,
    /// The parameters.
    pub params: &'static [ParamInfo],
    /// A rule between parameters that their bounds cannot say, if any.
    pub rule: Option<&'static str>,
    /// One line of description.
    pub description: &'static str,
    /// An example spec.
    pub example: &'static str,
}

impl ModelInfo {
    /// The parameters as one line, e.g. `ks: Value ≥ 0, n: number ≥ 0`, then the model's rule
    /// after a semicolon.
    pub fn params_line(&self) -> String {
        let v: Vec<String> = self
            .params
            .iter()
            .map(|p| {
                let kind = match p.kind {
                    Kind::Value => "Value".to_owned(),
                    Kind::Number => "number".to_owned(),
                    Kind::Radians => "radians".to_owned(),
                    Kind::Fresnel => "Fresnel".to_owned(),
                    Kind::Choice(c) => c
                        .iter()
                        .map(|x| format!("\"{x}\""))
                        .collect::<Vec<_>>()
                        .join(" | "),
                    Kind::Specs => "[spec, ...]".to_owned(),
                    Kind::Numbers => "[number, ...]".to_owned(),
                };
                let bound = match p.bound {
                    Bound::None => "",
                    Bound::NonNegative => " ≥ 0",
                    Bound::Positive => " > 0",
                };
                let default = p.default.map(|d| format!(" = {d}")).unwrap_or_default();
                format!("{}: {kind}{bound}{default}", p.name)
            })
            .collect();
        let mut line = v.join(", ");
        if let Some(r) = self.rule {
            line += &format!("; {r}");
        }
        line
    }
}

const fn param(name: &'static str, kind: Kind, bound: Bound) -> ParamInfo {
    ParamInfo {
        name,
        kind,
        bound,
        default: None,
    }
}

const fn defaulted(name: &'static str, kind: Kind, bound: Bound, d: &'static str) -> ParamInfo {
    ParamInfo {
        name,
        kind,
        bound,
        default: Some(d),
    }
}

const KS: ParamInfo = param("ks", Kind::Value, Bound::NonNegative);
const KS_1: ParamInfo = defaulted("ks", Kind::Value, Bound::NonNegative, "1");
const KD: ParamInfo = param("kd", Kind::Value, Bound::NonNegative);
const N: ParamInfo = param("n", Kind::Number, Bound::NonNegative);
const FRESNEL: ParamInfo = defaulted("fresnel", Kind::Fresnel, Bound::None, "\"none\"");
const ALPHA_X: ParamInfo = param("alpha_x", Kind::Number, Bound::Positive);
const ALPHA_Y: ParamInfo = param("alpha_y", Kind::Number, Bound::Positive);

/// Every model: the one declaration that validation, listings and help read (the serde enum
/// [`ModelSpec`] gives the same fields their Rust types; a test checks the two agree).
pub const MODELS: &[ModelInfo] = &[
    ModelInfo {
        name: "lambert",
        params: &[KD],
        rule: None,
        description: "diffuse, f = k_d; albedo k_d·π (energy conserving for k_d ≤ 1/π)",
        example: r#"{"model": "lambert", "kd": 0.3}"#,
    },
    ModelInfo {
        name: "mirror",
        params: &[FRESNEL],
        rule: None,
        description: "ideal reflector (delta), direction 2(N·V)N − V, k_r = Fresnel",
        example: r#"{"model": "mirror", "fresnel": {"conductor": "Ag"}}"#,
    },
    ModelInfo {
        name: "refractor",
        params: &[param("eta", Kind::Value, Bound::Positive)],
        rule: None,
        description: "ideal refraction (delta), Snell's law, weight 1 − F; total internal reflection → none",
        example: r#"{"model": "refractor", "eta": 1.5}"#,
    },
    ModelInfo {
        name: "phong",
        params: &[KS, N],
        rule: None,
        description: "original Phong, k_s cos^n ψ / cos θ′ (not reciprocal)",
        example: r#"{"model": "phong", "ks": 0.5, "n": 20}"#,
    },
    ModelInfo {
        name: "reciprocal_phong",
        params: &[KS, N],
        rule: None,
        description: "reciprocal Phong, k_s cos^n ψ; albedo 2π k_s/(n+2) at normal incidence",
        example: r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 50}"#,
    },
    ModelInfo {
        name: "max_phong",
        params: &[KS, N],
        rule: None,
        description: "max Phong, k_s cos^n ψ / max(cos θ′, cos θ)",
        example: r#"{"model": "max_phong", "ks": 0.5, "n": 50}"#,
    },
    ModelInfo {
        name: "pumped_phong",
        params: &[
            KS,
            N,
            param("x", Kind::Choice(&["mean", "product", "sqrt"]), Bound::None),
        ],
        rule: None,
        description: "pumped-up reciprocal Phong, k_s cos^n ψ / X with a symmetric X",
        example: r#"{"model": "pumped_phong", "ks": 0.5, "n": 50, "x": "mean"}"#,
    },
    ModelInfo {
        name: "cook_torrance",
        params: &[param("m", Kind::Number, Bound::Positive), KS_1, FRESNEL],
        rule: None,
        description: "Cook-Torrance, D·G·F/(4 (N·V)(N·L)), normalized Beckmann D, V-cavity G, F at L·H",
        example: r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#,
    },
    ModelInfo {
        name: "blinn_phong",
        params: &[KS, N],
        rule: None,
        description: "normalized Blinn-Phong, k_s (n+8)/(8π) cos^n θh",
        example: r#"{"model": "blinn_phong", "ks": 0.5, "n": 100}"#,
    },
    ModelInfo {
        name: "ggx",
        params: &[
            param("alpha", Kind::Number, Bound::Positive),
            ALPHA_X,
            ALPHA_Y,
            KS_1,
            FRESNEL,
        ],
        rule: Some(GGX_RULE),
        description: "GGX / Trowbridge-Reitz microfacet model, k_s D G2 F(wi·h) / (4 cos θi cos θo), Smith height-correlated G2, isotropic or anisotropic; visible-normal sampling",
        example: r#"{"model": "ggx", "alpha": 0.1, "fresnel": {"conductor": "Cu"}}"#,
    },
    ModelInfo {
        name: "ward",
        params: &[KS, ALPHA_X, ALPHA_Y],
        rule: None,
        description: "Ward (1992) anisotropic Gaussian lobe, k_s exp(−tan²θh (cos²φh/α_x² + sin²φh/α_y²)) / (4π α_x α_y √(cos θi cos θo)); not energy conserving at grazing angles",
        example: r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
    },
    ModelInfo {
        name: "oren_nayar",
        params: &[KD, param("sigma", Kind::Radians, Bound::NonNegative)],
        rule: None,
        description: "Oren-Nayar rough diffuse (qualitative model), k_d (A + B max(0, cos Δφ) sin α tan β); sigma = 0 is Lambert",
        example: r#"{"model": "oren_nayar", "kd": 0.25, "sigma": 0.3}"#,
    },
    ModelInfo {
        name: "sum",
        params: &[
            param("terms", Kind::Specs, Bound::None),
            defaulted("weights", Kind::Numbers, Bound::NonNegative, "all 1"),
        ],
        rule: Some(SUM_RULE),
        description: "weighted sum of models, e.g. diffuse + specular; sampling picks a term with probability ∝ weight × albedo",
        example: r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2}, {"model": "cook_torrance", "m": 0.2}]}"#,
    },
];

const GGX_RULE: &str = "give either `alpha` or both `alpha_x` and `alpha_y`";
const SUM_RULE: &str = "at least one term; one weight per term";

/// The entry of [`MODELS`] named `name`.
pub fn model_info(name: &str) -> Option<&'static ModelInfo> {
    MODELS.iter().find(|m| m.name == name)
}

/// Checks one parameter's JSON value against its bound and
/// [`NUMBER_RANGE`](crate::spectrum::NUMBER_RANGE). `field` names
/// it in errors.
fn check_param(p: &ParamInfo, field: &str, v: &serde_json::Value) -> Result<()> {
    let number = |x: Option<f64>, field: &str| -> Result<()> {
        if let Some(x) = x.filter(|x| x.is_finite()) {
            crate::spectrum::check_range(x, field)?;
        }
        let ok = match (x, p.bound) {
            (Some(x), Bound::NonNegative) => x.is_finite() && x >= 0.0,
            (Some(x), Bound::Positive) => x.is_finite() && x > 0.0,
            (Some(_), Bound::None) => true,
            (None, _) => false,
        };
        if ok {
            return Ok(());
        }
        let what = x.map_or_else(|| "NaN".to_owned(), |x| x.to_string());
        let rel = if p.bound == Bound::Positive {
            ">"
        } else {
            "≥"
        };
        Err(Error::spec(
            field,
            format!("{what} must be a finite number {rel} 0"),
        ))
    };
    match p.kind {
        Kind::Number | Kind::Radians => number(v.as_f64(), field),
        Kind::Numbers => match v.as_array() {
            Some(a) => a
                .iter()
                .enumerate()
                .try_for_each(|(i, x)| number(x.as_f64(), &format!("{field}[{i}]"))),
            None => Err(Error::spec(field, "expected a list of numbers")),
        },
        Kind::Value => {
            let value: Value = serde_json::from_value(v.clone()).map_err(|_| {
                Error::spec(field, "must be a finite number, RGB triple or spectrum")
            })?;
            value.validate(field, 0.0)?;
            if p.bound == Bound::Positive && value.numbers().iter().any(|&x| x <= 0.0) {
                return Err(Error::spec(field, "must be > 0"));
            }
            Ok(())
        }
        // Checked by their own types (Fresnel when resolved, choices by serde, specs by
        // recursion in `validate_at`).
        Kind::Fresnel | Kind::Choice(_) | Kind::Specs => Ok(()),
    }
}

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

// The JSON form is internally tagged (`{"model": "lambert", "kd": ..}`), but serde's internally
// tagged enums buffer their content and lose the field path of errors. So the derive above makes
// the externally tagged form (`{"lambert": {"kd": ..}}`) available as inherent functions
// (`remote = "Self"`), and these impls convert at the top level. Errors carry the field path as
// "at `terms[1].ks`: message", merged across nested sums.
#[cfg(test)]
thread_local! {
    /// How many times this thread serialized a spec (the work-bound test of nested sums).
    static SERIALIZED: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

impl Serialize for ModelSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::Error as _;
        #[cfg(test)]
        SERIALIZED.with(|n| n.set(n.get() + 1));
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
            assert_eq!(
                s.tagged().0.as_deref(),
                Some(m.name),
                "name() and serde disagree"
            );
            let back = ModelSpec::parse(&s.to_json()).unwrap();
            assert_eq!(back, s);
        }
    }

    #[test]
    fn nested_sums_parse_in_polynomial_work() {
        // Issue #23: `name()` serialized the whole spec and the serializer asks every nested
        // spec its name, so each level of nested sums doubled the work (a 1 KB spec nesting 20
        // sums took 29 s to parse). Now parsing and validating a chain of depth d serializes
        // each spec once per validation of each enclosing level: about d² in all (depth 12:
        // 312, before 73,614).
        let leaf = r#"{"model": "ggx", "alpha": 0.2}"#;
        let mut chain = leaf.to_string();
        let depth = 12;
        for _ in 0..depth {
            chain = format!(r#"{{"model": "sum", "terms": [{leaf}, {chain}]}}"#);
        }
        SERIALIZED.with(|n| n.set(0));
        let spec = ModelSpec::parse(&chain).unwrap();
        assert_eq!(spec.name(), "sum");
        spec.validate().unwrap();
        let n = SERIALIZED.with(|n| n.get());
        let bound = 2 * (2 * depth + 1) * (2 * depth + 1);
        assert!(
            n <= bound,
            "{n} serializations for depth {depth} (bound {bound})"
        );
    }

    #[test]
    fn the_declaration_and_the_enum_agree() {
        for m in MODELS {
            let s = ModelSpec::parse(m.example).unwrap();
            // Every field the enum writes is declared ...
            for (k, _) in s.tagged().1 {
                assert!(m.params.iter().any(|p| p.name == k), "{}.{k}", m.name);
            }
            // ... and a declared parameter that is not in the enum is rejected by serde.
            for p in m.params {
                let mut j: serde_json::Value = serde_json::from_str(m.example).unwrap();
                if j.get(p.name).is_none() {
                    continue;
                }
                j[p.name] = serde_json::json!(-1);
                let e = ModelSpec::parse(&j.to_string());
                if p.bound != Bound::None {
                    let e = e.unwrap_err().to_string();
                    assert!(e.contains(p.name), "{}.{}: {e}", m.name, p.name);
                }
            }
        }
        assert_eq!(MODELS.len(), 13, "one entry per ModelSpec variant");
    }

    #[test]
    fn bounds_come_from_the_declaration() {
        let e = ModelSpec::parse(r#"{"model": "cook_torrance", "m": 0}"#).unwrap_err();
        assert!(e.to_string().contains("> 0"), "{e}");
        let e = ModelSpec::parse(r#"{"model": "refractor", "eta": 0}"#).unwrap_err();
        assert!(e.to_string().contains("eta"), "{e}");
        let e = ModelSpec::parse(
            r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.1}], "weights": [-1]}"#,
        )
        .unwrap_err();
        assert!(e.to_string().contains("weights[0]"), "{e}");
        let e = ModelSpec::parse(r#"{"model": "ggx", "alpha": 0.1, "alpha_x": 0.2}"#).unwrap_err();
        assert!(e.to_string().contains("alpha"), "{e}");
        assert!(MODELS[9].params_line().contains("alpha_x: number > 0"));
        // The rule follows the parameters after a semicolon (it was ", (rule)").
        let sum = MODELS
            .iter()
            .find(|m| m.name == "sum")
            .unwrap()
            .params_line();
        assert!(
            sum.ends_with("= all 1; at least one term; one weight per term"),
            "{sum}"
        );
    }

    /// Every number at either end of [`crate::spectrum::NUMBER_RANGE`] evaluates to finite
    /// values (the range is safe), and just beyond it is an error naming the field.
    #[test]
    fn numbers_at_the_range_ends_evaluate_finite_and_beyond_are_errors() {
        use crate::geometry::spherical;
        use std::f64::consts::{FRAC_PI_2, PI};
        let (lo, hi) = (
            *crate::spectrum::NUMBER_RANGE.start(),
            *crate::spectrum::NUMBER_RANGE.end(),
        );
        // Normal, oblique, mirror, retro and grazing pairs.
        let pairs = [
            (glam::DVec3::Z, glam::DVec3::Z),
            (spherical(0.4, 0.0), spherical(0.4, PI)),
            (spherical(0.7, 1.0), spherical(0.2, 2.0)),
            (spherical(1.2, 0.3), spherical(1.2, 0.3)),
            (
                spherical(FRAC_PI_2 - 1e-4, 0.0),
                spherical(FRAC_PI_2 - 1e-4, PI),
            ),
            (spherical(FRAC_PI_2 - 1e-4, 0.0), spherical(0.01, 1.0)),
        ];
        let mut checked = 0;
        for m in MODELS {
            for p in m.params {
                let numeric = matches!(p.kind, Kind::Number | Kind::Radians | Kind::Value);
                if !numeric {
                    continue;
                }
                for (x, ok) in [
                    (lo, true),
                    (hi, true),
                    (lo / 10.0, false),
                    (hi * 10.0, false),
                ] {
                    let mut j: serde_json::Value = serde_json::from_str(m.example).unwrap();
                    if p.name == "alpha" || p.name == "alpha_x" || p.name == "alpha_y" {
                        // Keep the example's own choice of isotropic or anisotropic α.
                        if j.get(p.name).is_none() {
                            continue;
                        }
                    }
                    j[p.name] = serde_json::json!(x);
                    let parsed = ModelSpec::parse(&j.to_string());
                    if !ok {
                        let e = parsed.expect_err(&j.to_string()).to_string();
                        assert!(e.contains(p.name) && e.contains("out of range"), "{e}");
                        continue;
                    }
                    // Rules between parameters (Schlick F0 ≤ 1, ...) may refuse an end.
                    let Ok(spec) = parsed else { continue };
                    let b = build(&spec, &Channels::Rgb).unwrap();
                    let mut f = [0.0f32; 3];
                    for (wi, wo) in pairs {
                        b.eval(wi, wo, &mut f);
                        assert!(f.iter().all(|v| v.is_finite()), "{j}: {f:?} at {wi} {wo}");
                    }
                    checked += 1;
                }
            }
        }
        assert!(checked >= 20, "{checked} specs evaluated");
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
