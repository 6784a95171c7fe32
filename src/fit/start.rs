//! A fit's starting specs: the default [`preset`] of a model name or sum, and [`with_fresnel`],
//! which gives a spec's microfacet lobes a Fresnel term to fit; and the points its starts begin
//! from ([`StartPoints`]: the spec's own values, then a Latin hypercube over the bounds).

use serde_json::Value as Json;

use super::params::Param;
use super::problem::{from_free, spec_from_json, to_free};
use crate::error::{Error, Result};
use crate::rng::Pcg32;
use crate::spec::ModelSpec;

/// Default starting spec for a model name, or a sum of them joined with `+`
/// (`lambert+cook_torrance`, `lambert+ggx`, `lambert+blinn_phong`, `lambert+ward`, `ggx`, ...).
/// An inline JSON spec (starting with `{`) is parsed and used as given. Fresnel terms are
/// `"none"`: a fitted `ks` then absorbs the average reflectance.
pub fn preset(name: &str) -> Result<ModelSpec> {
    let name = name.trim();
    if name.starts_with('{') {
        return ModelSpec::parse(name);
    }
    let one = |n: &str| -> Result<Json> {
        Ok(match n.trim() {
            "lambert" => serde_json::json!({"model": "lambert", "kd": 0.1}),
            "oren_nayar" => serde_json::json!({"model": "oren_nayar", "kd": 0.1, "sigma": 0.3}),
            m @ ("phong" | "reciprocal_phong" | "max_phong") => {
                serde_json::json!({"model": m, "ks": 1.0, "n": 20.0})
            }
            "pumped_phong" => {
                serde_json::json!({"model": "pumped_phong", "ks": 1.0, "n": 20.0, "x": "mean"})
            }
            "blinn_phong" => serde_json::json!({"model": "blinn_phong", "ks": 0.5, "n": 50.0}),
            "cook_torrance" => serde_json::json!({"model": "cook_torrance", "m": 0.3, "ks": 0.5}),
            "ggx" => serde_json::json!({"model": "ggx", "alpha": 0.3, "ks": 0.5}),
            "ward" => {
                serde_json::json!({"model": "ward", "ks": 0.2, "alpha_x": 0.2, "alpha_y": 0.2})
            }
            other => {
                return Err(Error::arg(
                    "model",
                    format!(
                        "`{other}` cannot be fit; use lambert, oren_nayar, phong, reciprocal_phong, \
                         max_phong, pumped_phong, blinn_phong, cook_torrance, ggx, ward, sums of \
                         them with `+`, or a JSON spec"
                    ),
                ));
            }
        })
    };
    let terms = name.split('+').map(one).collect::<Result<Vec<_>>>()?;
    let json = if terms.len() == 1 {
        terms.into_iter().next().unwrap_or_default()
    } else {
        serde_json::json!({"model": "sum", "terms": terms})
    };
    spec_from_json(json)
}

/// `spec` with the Fresnel term of every microfacet lobe (`cook_torrance`, `ggx`) replaced by
/// `fresnel` — e.g. `{"schlick": 0.04}` so that a fit also finds F0, or `{"eta": 1.5}` for a
/// dielectric index. Presets use `"none"` (k_s absorbs the reflectance).
pub fn with_fresnel(spec: &ModelSpec, fresnel: &crate::fresnel::FresnelSpec) -> Result<ModelSpec> {
    fn walk(v: &mut Json, f: &Json) {
        let Some(obj) = v.as_object_mut() else { return };
        if matches!(
            obj.get("model").and_then(Json::as_str),
            Some("cook_torrance" | "ggx")
        ) {
            obj.insert("fresnel".into(), f.clone());
        }
        if let Some(Json::Array(terms)) = obj.get_mut("terms") {
            for t in terms {
                walk(t, f);
            }
        }
    }
    let to_json = |x: serde_json::Result<Json>| {
        x.map_err(|e| Error::Json {
            context: "spec".into(),
            source: e,
        })
    };
    let mut json = to_json(serde_json::to_value(spec))?;
    walk(&mut json, &to_json(serde_json::to_value(fresnel))?);
    spec_from_json(json)
}

/// Where a fit's starts begin: start 0 at the spec's own values (pulled inside the bounds),
/// starts 1.. on a Latin hypercube over the bounds (positions 5 %–95 %, one stratum per start
/// along every parameter; the channels of one field share a position).
pub(super) struct StartPoints {
    /// The spec's own values, flattened in parameter order.
    first: Vec<f64>,
    /// Per parameter, the stratum of starts 1.. (a permutation of 0..starts − 1).
    strata: Vec<Vec<usize>>,
    starts: usize,
}

impl StartPoints {
    /// The points of `starts` starts for `params` whose spec holds `first`, permuted by `seed`.
    pub(super) fn new(params: &[Param], first: Vec<f64>, starts: usize, seed: u64) -> Self {
        let mut rng = Pcg32::with_stream(seed, 0x5354_4152);
        let strata = params
            .iter()
            .map(|_| {
                let k = starts.saturating_sub(1);
                let mut perm: Vec<usize> = (0..k).collect();
                for i in (1..k).rev() {
                    perm.swap(i, rng.below(i as u32 + 1) as usize);
                }
                perm
            })
            .collect();
        StartPoints {
            first,
            strata,
            starts,
        }
    }

    /// The parameter values start `s` begins from (flattened in parameter order).
    pub(super) fn values(&self, params: &[Param], s: usize) -> Vec<f64> {
        if s == 0 {
            return from_free(params, &to_free(params, &self.first));
        }
        let k = (self.starts - 1) as f64;
        let mut v = Vec::with_capacity(self.first.len());
        for (pi, p) in params.iter().enumerate() {
            let u = 0.05 + 0.9 * (self.strata[pi][s - 1] as f64 + 0.5) / k;
            v.extend(std::iter::repeat_n(p.bounds.from_unit(u), p.width));
        }
        v
    }
}
