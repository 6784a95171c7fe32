//! Fit parameters: paths into a spec, their default bounds, and the smooth reparameterization
//! that keeps Levenberg-Marquardt unconstrained.
//!
//! A parameter is addressed by a path into the spec's JSON form: `kd`, `m`, `terms[1].m`,
//! `terms[0].kd`. Paths are resolved on the JSON object (`serde_json::Value`) so that every model
//! of [`ModelSpec`](crate::spec::ModelSpec) — present and future — is addressable without a per-model table of setters;
//! the only per-parameter knowledge is the table of default bounds in [`default_bounds`].
//!
//! Bounds are enforced by a reparameterization: the optimizer sees an unconstrained `t ∈ ℝ` and
//! the model gets `x = lo + (hi − lo)·σ(t)` (σ the logistic function) for linear parameters, or
//! `ln x = ln lo + (ln hi − ln lo)·σ(t)` for parameters fit in log space (Phong exponents,
//! roughness, Phong-family k_s). Either way `x` never leaves `[lo, hi]`.

mod bounds;
mod path;

pub use bounds::{Bounds, Scale, default_bounds, is_value_field};
use path::{lookup, parse_path};

use serde::Serialize;
use serde_json::Value as Json;

use crate::error::{Error, Result};
use crate::spectrum::Channels;

/// A request to fit the parameter at `path`, with optional bounds overriding the defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamRequest {
    /// Path into the spec (`kd`, `terms[1].m`).
    pub path: String,
    /// Bounds; `None` uses [`default_bounds`].
    pub bounds: Option<Bounds>,
}

impl ParamRequest {
    /// A parameter with default bounds.
    pub fn new(path: impl Into<String>) -> Self {
        ParamRequest {
            path: path.into(),
            bounds: None,
        }
    }
}

impl std::str::FromStr for ParamRequest {
    type Err = crate::Error;

    /// Parses `path` or `path=lo:hi` (linear) or `path=lo:hi:log`.
    fn from_str(s: &str) -> std::result::Result<Self, crate::Error> {
        let s = s.trim();
        let Some((path, b)) = s.split_once('=') else {
            parse_path(s)?;
            return Ok(ParamRequest::new(s));
        };
        parse_path(path)?;
        let bad = || {
            Error::arg(
                "params",
                format!("`{s}`: bounds are written `path=lo:hi` or `path=lo:hi:log`"),
            )
        };
        let parts: Vec<&str> = b.split(':').collect();
        if !(2..=3).contains(&parts.len()) {
            return Err(bad());
        }
        let lo: f64 = parts[0].trim().parse().map_err(|_| bad())?;
        let hi: f64 = parts[1].trim().parse().map_err(|_| bad())?;
        let scale = match parts.get(2).map(|x| x.trim()) {
            None | Some("lin") | Some("linear") => Scale::Linear,
            Some("log") => Scale::Log,
            Some(_) => return Err(bad()),
        };
        let bounds = Bounds { lo, hi, scale };
        bounds.validate(path)?;
        Ok(ParamRequest {
            path: path.to_string(),
            bounds: Some(bounds),
        })
    }
}

/// How [`Value`](crate::Value) parameters (`kd`, `ks`) are fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ColorMode {
    /// One free value per channel of the source (RGB triples, or spectra on the source's
    /// wavelengths); shape parameters (m, n, α, σ) stay shared by all channels.
    #[default]
    PerChannel,
    /// One grey value for all channels.
    Grey,
}

/// One resolved parameter: a field in the spec, its bounds, and the number of scalars it takes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Param {
    /// Path into the spec.
    pub path: String,
    /// Bounds and scale.
    pub bounds: Bounds,
    /// Number of free scalars: the channel count for per-channel values, else 1.
    pub width: usize,
}

/// Every numeric parameter of `spec` that has default bounds (sum `weights` excluded; a Fresnel
/// term's `schlick` F0 or dielectric `eta` included when the spec has one),
/// terms in order, fields of a term in alphabetical order (the JSON form keeps keys sorted).
pub fn default_paths(spec: &Json) -> Vec<String> {
    fn walk(v: &Json, prefix: &str, out: &mut Vec<String>) {
        let Some(obj) = v.as_object() else { return };
        let model = obj.get("model").and_then(Json::as_str).unwrap_or("");
        for (k, x) in obj {
            if k == "fresnel" {
                if let Some(f) = x.as_object() {
                    for (fk, fx) in f {
                        if default_bounds(model, fk).is_some() && !fx.is_null() {
                            out.push(format!("{prefix}fresnel.{fk}"));
                        }
                    }
                }
            } else if k == "terms" {
                if let Some(arr) = x.as_array() {
                    for (i, t) in arr.iter().enumerate() {
                        walk(t, &format!("{prefix}terms[{i}]."), out);
                    }
                }
            } else if default_bounds(model, k).is_some() && !x.is_null() {
                out.push(format!("{prefix}{k}"));
            }
        }
    }
    let mut out = Vec::new();
    walk(spec, "", &mut out);
    out
}

/// Resolves requests against the spec's JSON: checks that each path exists and is numeric,
/// fills in default bounds, and decides the width (channels) of each.
pub fn resolve(
    spec: &mut Json,
    requests: &[ParamRequest],
    channels: &Channels,
    color: ColorMode,
) -> Result<Vec<Param>> {
    let requests: Vec<ParamRequest> = if requests.is_empty() {
        default_paths(spec)
            .into_iter()
            .map(ParamRequest::new)
            .collect()
    } else {
        requests.to_vec()
    };
    if requests.is_empty() {
        return Err(Error::arg(
            "params",
            "the model has no parameter with default bounds to fit",
        ));
    }
    let mut out: Vec<Param> = Vec::new();
    for r in &requests {
        if out.iter().any(|p| p.path == r.path) {
            return Err(Error::arg("params", format!("`{}` given twice", r.path)));
        }
        let (v, model, key) = lookup(spec, &r.path)?;
        let numeric = match v {
            Json::Number(_) => true,
            Json::Array(a) => a.iter().all(Json::is_number),
            Json::Object(o) => o.contains_key("values"),
            _ => false,
        };
        if !numeric {
            return Err(Error::arg(
                "params",
                format!("`{}` is not a numeric parameter", r.path),
            ));
        }
        let bounds = match r.bounds.or_else(|| default_bounds(&model, &key)) {
            Some(b) => b,
            None => {
                return Err(Error::arg(
                    "params",
                    format!(
                        "`{}` has no default bounds; give them as `{}=lo:hi`",
                        r.path, r.path
                    ),
                ));
            }
        };
        bounds.validate(&r.path)?;
        let width = if is_value_field(&key) && color == ColorMode::PerChannel {
            channels.len()
        } else {
            1
        };
        out.push(Param {
            path: r.path.clone(),
            bounds,
            width,
        });
    }
    Ok(out)
}

/// The current value(s) of `p` in `spec`, one per scalar of its width (a grey value is repeated;
/// an RGB or spectral value is resolved to the channels, or averaged for width 1).
pub fn read(spec: &mut Json, p: &Param, channels: &Channels) -> Result<Vec<f64>> {
    let (v, _, _) = lookup(spec, &p.path)?;
    let value: crate::spectrum::Value = serde_json::from_value(v.clone())
        .map_err(|e| Error::arg("params", format!("`{}`: {e}", p.path)))?;
    let per = value.resolve(channels);
    Ok(if p.width == 1 {
        vec![per.iter().sum::<f64>() / per.len() as f64]
    } else {
        per
    })
}

/// Writes `x` (one scalar per channel, or one) into the spec at `p`.
pub fn write(spec: &mut Json, p: &Param, x: &[f64], channels: &Channels) -> Result<()> {
    let (v, _, _) = lookup(spec, &p.path)?;
    *v = if p.width == 1 {
        Json::from(x[0])
    } else {
        match channels {
            Channels::Rgb => Json::from(x.to_vec()),
            Channels::Wavelengths(w) => serde_json::json!({"wavelengths": w, "values": x}),
        }
    };
    Ok(())
}

#[cfg(test)]
mod tests;
