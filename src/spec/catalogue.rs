//! The model catalogue: every model's parameters with their kinds, bounds and defaults
//! ([`MODELS`]), the one declaration that validation, `brdftab models` and help read, and the
//! check of one parameter's JSON value against it.

use serde::Serialize;

use crate::error::{Error, Result};
use crate::spectrum::Value;

/// How a parameter's numbers are bounded (checked by
/// [`ModelSpec::validate`](super::ModelSpec::validate)).
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
    /// A [`FresnelSpec`](crate::fresnel::FresnelSpec).
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
/// example. [`ModelSpec::validate`](super::ModelSpec::validate) checks a spec against its entry,
/// `brdftab models` lists them.
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
/// [`ModelSpec`](super::ModelSpec) gives the same fields their Rust types; a test checks the two
/// agree).
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

pub(super) const GGX_RULE: &str = "give either `alpha` or both `alpha_x` and `alpha_y`";
const SUM_RULE: &str = "at least one term; one weight per term";

/// The entry of [`MODELS`] named `name`.
pub fn model_info(name: &str) -> Option<&'static ModelInfo> {
    MODELS.iter().find(|m| m.name == name)
}

/// Checks one parameter's JSON value against its bound and
/// [`NUMBER_RANGE`](crate::spectrum::NUMBER_RANGE). `field` names
/// it in errors.
pub(super) fn check_param(p: &ParamInfo, field: &str, v: &serde_json::Value) -> Result<()> {
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
