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

use serde::Serialize;
use serde_json::Value as Json;

use crate::error::{Error, Result};
use crate::spectrum::Channels;

/// How a bounded parameter is mapped to the optimizer's unconstrained variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scale {
    /// Logistic between `lo` and `hi`.
    Linear,
    /// Logistic between `ln lo` and `ln hi` (needs `lo > 0`).
    Log,
}

/// Closed bounds of one parameter and the scale in which it is fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bounds {
    /// Lower bound.
    pub lo: f64,
    /// Upper bound (> `lo`).
    pub hi: f64,
    /// Linear or log space.
    pub scale: Scale,
}

impl Bounds {
    /// Linear bounds `[lo, hi]`.
    pub const fn linear(lo: f64, hi: f64) -> Self {
        Bounds {
            lo,
            hi,
            scale: Scale::Linear,
        }
    }

    /// Bounds `[lo, hi]` fit in log space.
    pub const fn log(lo: f64, hi: f64) -> Self {
        Bounds {
            lo,
            hi,
            scale: Scale::Log,
        }
    }

    /// Checks `lo < hi`, finiteness, and `lo > 0` for log scale.
    pub fn validate(&self, path: &str) -> Result<()> {
        if !(self.lo.is_finite() && self.hi.is_finite() && self.lo < self.hi) {
            return Err(Error::arg(
                path,
                format!(
                    "bounds [{}, {}] must be finite with lo < hi",
                    self.lo, self.hi
                ),
            ));
        }
        if self.scale == Scale::Log && self.lo <= 0.0 {
            return Err(Error::arg(
                path,
                format!("log-space bounds need lo > 0, got {}", self.lo),
            ));
        }
        Ok(())
    }

    fn ends(&self) -> (f64, f64) {
        match self.scale {
            Scale::Linear => (self.lo, self.hi),
            Scale::Log => (self.lo.ln(), self.hi.ln()),
        }
    }

    /// The position `u ∈ [0, 1]` of `x` between the bounds (in the bound's scale), clamped.
    pub fn to_unit(&self, x: f64) -> f64 {
        let (a, b) = self.ends();
        let y = match self.scale {
            Scale::Linear => x,
            Scale::Log => x.max(self.lo).ln(),
        };
        ((y - a) / (b - a)).clamp(0.0, 1.0)
    }

    /// The value at unit position `u ∈ [0, 1]`. A value nearer 0 than a spec may hold
    /// ([`crate::spectrum::NUMBER_RANGE`]: 0 or a magnitude of at least 1e-12) is 0 where the
    /// bounds hold 0: a start heading for a lower bound of 0 (a Lambert term the source does not
    /// have) passed through such values, failed the spec's check and was dropped.
    pub fn from_unit(&self, u: f64) -> f64 {
        let (a, b) = self.ends();
        let y = a + (b - a) * u;
        let x = match self.scale {
            Scale::Linear => y,
            Scale::Log => y.exp(),
        };
        let x = x.clamp(self.lo, self.hi);
        let tiny = x != 0.0 && x.abs() < *crate::spectrum::NUMBER_RANGE.start();
        if tiny && (self.lo..=self.hi).contains(&0.0) {
            0.0
        } else {
            x
        }
    }

    /// Unconstrained variable → parameter value (always within the bounds).
    pub fn from_free(&self, t: f64) -> f64 {
        self.from_unit(logistic(t))
    }

    /// Parameter value → unconstrained variable; values at or beyond a bound are pulled inside
    /// by 1e-4 of the range so the start is not on a flat part of the logistic.
    pub fn to_free(&self, x: f64) -> f64 {
        let u = self.to_unit(x).clamp(1e-4, 1.0 - 1e-4);
        (u / (1.0 - u)).ln()
    }
}

fn logistic(t: f64) -> f64 {
    if t >= 0.0 {
        1.0 / (1.0 + (-t).exp())
    } else {
        let e = t.exp();
        e / (1.0 + e)
    }
}

/// True when the field `key` of model `model` holds a [`Value`](crate::Value) (grey, RGB or
/// spectral) rather than a plain number.
pub fn is_value_field(key: &str) -> bool {
    matches!(key, "kd" | "ks" | "eta" | "schlick")
}

/// The default bounds of field `key` in model `model`, or `None` when the field has no default
/// (it can still be fit with explicit bounds).
///
/// | field | models | bounds | scale |
/// |---|---|---|---|
/// | `kd` | lambert, oren_nayar | [0, 1.2/π] | linear |
/// | `ks` | cook_torrance, ggx, blinn_phong, ward | [0, 1.5] | linear |
/// | `ks` | phong, reciprocal_phong, max_phong, pumped_phong | [1e-3, 1e4] | log |
/// | `m`, `alpha`, `alpha_x`, `alpha_y` | microfacet, ward | [0.01, 1.5] | log |
/// | `n` | Phong family, blinn_phong | [1, 10000] | log |
/// | `sigma` | oren_nayar | [0, 1.5] rad | linear |
/// | `fresnel.schlick` (F0) | microfacet | [0, 1] | linear |
/// | `fresnel.eta` (dielectric) | microfacet | [1.01, 3] | linear |
///
/// `k_d ≤ 1.2/π` allows a little more than energy conservation (albedo 1.2) so that measured data
/// with calibration error is not clipped; `k_s` of the Phong family is the lobe's peak value, which
/// grows with n, hence log space.
pub fn default_bounds(model: &str, key: &str) -> Option<Bounds> {
    use std::f64::consts::PI;
    Some(match key {
        "kd" => Bounds::linear(0.0, 1.2 / PI),
        "ks" => match model {
            "phong" | "reciprocal_phong" | "max_phong" | "pumped_phong" => Bounds::log(1e-3, 1e4),
            _ => Bounds::linear(0.0, 1.5),
        },
        "m" | "alpha" | "alpha_x" | "alpha_y" => Bounds::log(0.01, 1.5),
        "n" => Bounds::log(1.0, 10000.0),
        "sigma" => Bounds::linear(0.0, 1.5),
        "schlick" => Bounds::linear(0.0, 1.0),
        "eta" if model != "refractor" => Bounds::linear(1.01, 3.0),
        _ => return None,
    })
}

/// One segment of a parameter path: a field name with an optional array index (`terms[1]`).
#[derive(Debug, Clone, PartialEq, Eq)]
struct Segment {
    key: String,
    index: Option<usize>,
}

/// Parses `terms[1].m` into segments.
fn parse_path(path: &str) -> Result<Vec<Segment>> {
    let bad = |msg: &str| Error::arg("params", format!("`{path}`: {msg}"));
    if path.trim().is_empty() {
        return Err(bad("empty parameter path"));
    }
    path.split('.')
        .map(|seg| {
            let (key, index) = match seg.split_once('[') {
                None => (seg, None),
                Some((k, rest)) => {
                    let i = rest
                        .strip_suffix(']')
                        .and_then(|i| i.parse::<usize>().ok())
                        .ok_or_else(|| bad("expected `name[index]`"))?;
                    (k, Some(i))
                }
            };
            if key.is_empty() || !key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                return Err(bad("expected field names like `kd` or `terms[1].m`"));
            }
            Ok(Segment {
                key: key.to_string(),
                index,
            })
        })
        .collect()
}

/// The JSON value at `path` and the name of the model that owns its last field.
fn lookup<'a>(root: &'a mut Json, path: &str) -> Result<(&'a mut Json, String, String)> {
    let segs = parse_path(path)?;
    let missing = |what: String| Error::arg("params", format!("`{path}`: {what}"));
    let mut cur = root;
    let mut model = String::new();
    let mut last = String::new();
    for s in &segs {
        let obj = cur
            .as_object_mut()
            .ok_or_else(|| missing(format!("`{}` is not inside an object", s.key)))?;
        if let Some(Json::String(m)) = obj.get("model") {
            model = m.clone();
        }
        cur = obj
            .get_mut(&s.key)
            .ok_or_else(|| missing(format!("no field `{}` in model `{model}`", s.key)))?;
        if let Some(i) = s.index {
            let arr = cur
                .as_array_mut()
                .ok_or_else(|| missing(format!("`{}` is not a list", s.key)))?;
            let n = arr.len();
            cur = arr
                .get_mut(i)
                .ok_or_else(|| missing(format!("index {i} out of range (`{}` has {n})", s.key)))?;
        }
        last = s.key.clone();
    }
    Ok((cur, model, last))
}

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
mod tests {
    use super::*;

    #[test]
    fn reparameterization_stays_in_bounds_and_round_trips() {
        for b in [Bounds::linear(0.0, 0.4), Bounds::log(1.0, 1e4)] {
            for t in [-1e3, -30.0, -1.0, 0.0, 2.0, 40.0, 1e3] {
                let x = b.from_free(t);
                assert!(x >= b.lo && x <= b.hi, "{x}");
            }
            let x = b.from_unit(0.3);
            assert!((b.from_free(b.to_free(x)) - x).abs() < 1e-9 * x.max(1.0));
        }
    }

    #[test]
    fn default_paths_walk_sums_and_skip_fresnel() {
        let j = serde_json::json!({"model": "sum", "terms": [
            {"model": "lambert", "kd": 0.1},
            {"model": "cook_torrance", "m": 0.3, "ks": 1.0, "fresnel": {"conductor": "Au"}}
        ]});
        assert_eq!(
            default_paths(&j),
            ["terms[0].kd", "terms[1].ks", "terms[1].m"]
        );
    }

    #[test]
    fn fresnel_f0_and_eta_are_found() {
        let j = serde_json::json!({"model": "sum", "terms": [
            {"model": "ggx", "alpha": 0.3, "ks": 1.0, "fresnel": {"schlick": 0.04}},
            {"model": "cook_torrance", "m": 0.3, "ks": 1.0, "fresnel": {"eta": 1.5}}
        ]});
        assert_eq!(
            default_paths(&j),
            [
                "terms[0].alpha",
                "terms[0].fresnel.schlick",
                "terms[0].ks",
                "terms[1].fresnel.eta",
                "terms[1].ks",
                "terms[1].m"
            ]
        );
    }

    #[test]
    fn paths_and_bounds_parse() {
        let r = "terms[1].m=0.05:0.5".parse::<ParamRequest>().unwrap();
        assert_eq!(r.path, "terms[1].m");
        assert_eq!(r.bounds, Some(Bounds::linear(0.05, 0.5)));
        let r = "n=2:100:log".parse::<ParamRequest>().unwrap();
        assert_eq!(r.bounds.unwrap().scale, Scale::Log);
        assert!("n=100:2".parse::<ParamRequest>().is_err());
        assert!("n=0:2:log".parse::<ParamRequest>().is_err());
        assert!("terms[x].m".parse::<ParamRequest>().is_err());
        assert!("".parse::<ParamRequest>().is_err());
    }

    #[test]
    fn unknown_path_is_an_error_naming_it() {
        let mut j = serde_json::json!({"model": "lambert", "kd": 0.1});
        let e = resolve(
            &mut j,
            &[ParamRequest::new("ks")],
            &Channels::Rgb,
            ColorMode::Grey,
        )
        .unwrap_err();
        assert!(e.to_string().contains("ks"), "{e}");
        let e = resolve(
            &mut j,
            &[ParamRequest::new("terms[0].kd")],
            &Channels::Rgb,
            ColorMode::Grey,
        )
        .unwrap_err();
        assert!(e.to_string().contains("terms"), "{e}");
    }

    #[test]
    fn per_channel_values_write_rgb_and_spectra() {
        let mut j = serde_json::json!({"model": "lambert", "kd": 0.1});
        let p = resolve(&mut j, &[], &Channels::Rgb, ColorMode::PerChannel).unwrap();
        assert_eq!(p[0].width, 3);
        write(&mut j, &p[0], &[0.1, 0.2, 0.3], &Channels::Rgb).unwrap();
        assert_eq!(j["kd"], serde_json::json!([0.1, 0.2, 0.3]));
        let ch = Channels::wavelengths(vec![450.0, 550.0]).unwrap();
        let p = resolve(&mut j, &[], &ch, ColorMode::PerChannel).unwrap();
        write(&mut j, &p[0], &[0.1, 0.2], &ch).unwrap();
        assert_eq!(read(&mut j, &p[0], &ch).unwrap(), vec![0.1, 0.2]);
    }
}
