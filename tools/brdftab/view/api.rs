//! The JSON API: one handler per view, each taking its material by index (`m=ID`, with
//! `of=source` for a table's source) or as an inline analytic spec (`spec={...}`).
//!
//! Handlers validate every number against a range before use, so no request can ask for an
//! unbounded amount of work; the slow figures of a material (error figures, plausibility,
//! albedo) are computed once and cached.

use std::sync::Arc;

use brdftab::analysis::plausibility;
use brdftab::spectrum::Channels;
use serde_json::json;

use super::eval::{self, Channel};
use super::http::Response;
use super::registry::{Registry, Shared};
use super::security::inline_spec;
use crate::report::suite::{self, MetricOptions};

/// A request's decoded query parameters.
pub struct Query(pub super::security::Params);

impl Query {
    /// The value of parameter `k`, if given.
    pub fn get(&self, k: &str) -> Option<&str> {
        self.0.iter().find(|(n, _)| n == k).map(|(_, v)| v.as_str())
    }

    /// Number `k` in [lo, hi] (`default` when absent).
    fn num(&self, k: &str, default: f64, lo: f64, hi: f64) -> Result<f64, Response> {
        let Some(v) = self.get(k) else {
            return Ok(default);
        };
        match v.parse::<f64>() {
            Ok(x) if (lo..=hi).contains(&x) => Ok(x),
            _ => Err(Response::error(
                400,
                &format!("{k}: expected a number in [{lo}, {hi}]"),
            )),
        }
    }

    /// The channel a view shows (`ch=y|r|g|b`, the luminance when absent).
    fn channel(&self) -> Result<Channel, Response> {
        match self.get("ch") {
            None => Ok(Channel::Y),
            Some(v) => {
                Channel::parse(v).ok_or_else(|| Response::error(400, "ch: expected y, r, g or b"))
            }
        }
    }

    /// Count `k`, an integer in [lo, hi] (`default` when absent). `n=10.5` is refused, not
    /// rounded: a count the client did not ask for would be answered silently.
    fn count(&self, k: &str, default: usize, lo: usize, hi: usize) -> Result<usize, Response> {
        let Some(v) = self.get(k) else {
            return Ok(default);
        };
        match v.parse::<usize>() {
            Ok(n) if (lo..=hi).contains(&n) => Ok(n),
            _ => Err(Response::error(
                400,
                &format!("{k}: expected an integer in [{lo}, {hi}]"),
            )),
        }
    }
}

/// What a view request evaluates: the BRDF, and the cache key of a registered material (`None`
/// for an inline spec, which is never cached).
struct Target {
    brdf: Shared,
    key: Option<String>,
}

/// The BRDF a request names: `spec=` (inline specs only), else `m=ID` with optional `of=source`.
fn target(reg: &Registry, q: &Query) -> Result<Target, Response> {
    if let Some(s) = q.get("spec") {
        let spec = inline_spec(s).map_err(|e| Response::error(400, &e))?;
        let brdf = spec
            .build(&Channels::Rgb)
            .map_err(|e| Response::error(400, &e.to_string()))?;
        return Ok(Target {
            brdf: Arc::from(brdf),
            key: None,
        });
    }
    let id: usize = q
        .get("m")
        .ok_or_else(|| Response::error(400, "m=ID or spec=JSON is required"))?
        .parse()
        .map_err(|_| Response::error(400, "m: expected a material index"))?;
    let m = reg
        .get(id)
        .ok_or_else(|| Response::error(404, "no such material"))?;
    match q.get("of") {
        None | Some("table") => Ok(Target {
            brdf: m.brdf.clone(),
            key: Some(id.to_string()),
        }),
        Some("source") => match &m.source {
            Some(s) => Ok(Target {
                brdf: s.clone(),
                key: Some(format!("{id}:source")),
            }),
            None => Err(Response::error(
                404,
                "this material has no source that opens",
            )),
        },
        Some(_) => Err(Response::error(400, "of: expected table or source")),
    }
}

/// `/api/materials`: every material's description.
pub fn materials(reg: &Registry) -> Response {
    let list: Vec<&serde_json::Value> = reg.materials.iter().map(|m| &m.info).collect();
    Response::json(json!(list).to_string())
}

/// `/api/models`: the model catalogue (parameters, bounds, defaults) the spec sliders use.
pub fn models() -> Response {
    Response::json(serde_json::to_string(brdftab::spec::MODELS).unwrap_or_default())
}

/// `body` as JSON, or a 500 error when `brdf` failed while it was read (a corrupt table chunk):
/// the zeros it gave are no answer.
fn answer(brdf: &dyn brdftab::Brdf, body: String) -> Result<Response, Response> {
    brdf.health()
        .map_err(|e| Response::error(500, &e.to_string()))?;
    Ok(Response::json(body))
}

/// The incident azimuth φi of a view (`phi_i=DEG` in [−180°, 180°], 0 when absent): the
/// plane of incidence's azimuth, the light at φi + 180° ([`eval::polar`]).
fn phi_i(q: &Query) -> Result<f64, Response> {
    q.num("phi_i", 0.0, -180.0, 180.0)
}

/// `/api/polar?theta_i=DEG&phi_i=DEG&n=N&ch=C`.
pub fn polar(reg: &Registry, q: &Query) -> Result<Response, Response> {
    let t = target(reg, q)?;
    let ti = q.num("theta_i", 30.0, 0.0, 89.9)?;
    let pi = phi_i(q)?;
    let n = q.count("n", 181, 2, 2001)?;
    let body = eval::polar(t.brdf.as_ref(), ti, pi, n, q.channel()?).to_string();
    answer(t.brdf.as_ref(), body)
}

/// `/api/lobe?theta_i=DEG&phi_i=DEG&nt=N&np=N&ch=C`.
pub fn lobe(reg: &Registry, q: &Query) -> Result<Response, Response> {
    let t = target(reg, q)?;
    let ti = q.num("theta_i", 30.0, 0.0, 89.9)?;
    let pi = phi_i(q)?;
    let nt = q.count("nt", 24, 2, 96)?;
    let np = q.count("np", 48, 3, 192)?;
    let body = eval::lobe(t.brdf.as_ref(), ti, pi, nt, np, q.channel()?).to_string();
    answer(t.brdf.as_ref(), body)
}

/// `/api/slice?n=N&ch=C`.
pub fn slice(reg: &Registry, q: &Query) -> Result<Response, Response> {
    let t = target(reg, q)?;
    let n = q.count("n", 64, 2, 256)?;
    let body = eval::slice(t.brdf.as_ref(), n, q.channel()?).to_string();
    answer(t.brdf.as_ref(), body)
}

/// `/api/sphere?lt=DEG&lp=DEG&size=N&exposure=X`.
pub fn sphere(reg: &Registry, q: &Query) -> Result<Response, Response> {
    let t = target(reg, q)?;
    let lt = q.num("lt", 40.0, 0.0, 90.0)?;
    let lp = q.num("lp", 135.0, -360.0, 360.0)?;
    let size = q.count("size", 128, 8, 256)?;
    let exposure = q.num("exposure", 1.0, 1e-3, 1e3)?;
    let v = eval::sphere(t.brdf.as_ref(), lt, lp, size, exposure);
    answer(t.brdf.as_ref(), v.to_string())
}

/// The value of `f` on the target, cached under `what(target)` for registered materials.
fn cached_view(
    reg: &Registry,
    q: &Query,
    what: impl FnOnce(&dyn brdftab::Brdf) -> String,
    f: impl FnOnce(&(dyn brdftab::Brdf + Sync)) -> String,
) -> Result<Response, Response> {
    let t = target(reg, q)?;
    let body = match t.key {
        Some(k) => reg
            .cached(format!("{}:{k}", what(t.brdf.as_ref())), || {
                f(t.brdf.as_ref())
            })
            .to_string(),
        None => f(t.brdf.as_ref()),
    };
    answer(t.brdf.as_ref(), body)
}

/// `/api/albedo?phi_i=DEG&ch=C`: the albedo curve for light at azimuth φi + 180° (φi to 0.1°). An
/// isotropic material's is the same at every φi: it is computed (and cached) once, at φi = 0.
pub fn albedo(reg: &Registry, q: &Query) -> Result<Response, Response> {
    let ch = q.channel()?;
    let asked = phi_i(q)?;
    // To 0.1° (the slider's step is 1°), so a material's curves cached are at most 3601 per
    // channel however many azimuths a client asks for; `+ 0.0`: -0 and 0 are one key.
    let pi = |b: &dyn brdftab::Brdf| {
        if b.flags().isotropic {
            0.0
        } else {
            (asked * 10.0).round() / 10.0 + 0.0
        }
    };
    let what = |b: &dyn brdftab::Brdf| format!("albedo-{}-{}", ch.name(), pi(b));
    cached_view(reg, q, what, |b| eval::albedo(b, pi(b), ch).to_string())
}

/// `/api/plausibility`: positivity, reciprocity and energy conservation (the demo's quick
/// settings: 4000 pairs, albedo at 0°, 30°, 60°, 85°, each the BRDF's own [`Brdf::albedo`] as
/// `brdftab check` computes it, so delta lobes count).
///
/// [`Brdf::albedo`]: brdftab::Brdf::albedo
pub fn plausibility(reg: &Registry, q: &Query) -> Result<Response, Response> {
    cached_view(
        reg,
        q,
        |_| "plausibility".into(),
        |b| {
            let opts = plausibility::Options {
                pairs: 4000,
                thetas_deg: vec![0.0, 30.0, 60.0, 85.0],
                albedo: None,
                ..Default::default()
            };
            match plausibility::check(b, &opts) {
                Ok(r) => {
                    let mut v = serde_json::to_value(&r).unwrap_or_default();
                    v["plausible"] = json!(r.plausible());
                    v.to_string()
                }
                Err(e) => json!({ "error": e.to_string() }).to_string(),
            }
        },
    )
}

/// `/api/compare?m=ID`: a table against its source, as the demo measures it (cos-weighted
/// relative RMSE over 20 000 random pairs, and the largest relative albedo error).
pub fn compare(reg: &Registry, q: &Query) -> Result<Response, Response> {
    let id: usize = q
        .get("m")
        .and_then(|m| m.parse().ok())
        .ok_or_else(|| Response::error(400, "m: expected a material index"))?;
    let m = reg
        .get(id)
        .ok_or_else(|| Response::error(404, "no such material"))?;
    let Some(source) = m.source.clone() else {
        return Err(Response::error(
            404,
            "this material has no source that opens",
        ));
    };
    let (table, measured) = (m.brdf.clone(), m.measured_source);
    let (table_health, source_health) = (table.clone(), source.clone());
    let body = reg.cached(format!("compare:{id}"), move || {
        let thetas: &[f64] = if measured {
            &[2.0, 30.0, 60.0, 80.0]
        } else {
            &[0.0, 30.0, 60.0, 80.0]
        };
        // As the demo's and the suite's rows (`suite::rmse_weighting`).
        let (cap, weight) = suite::rmse_weighting(measured);
        let opts = MetricOptions {
            pairs: 20_000,
            seed: 1,
            albedo_thetas: thetas.iter().map(|t| t.to_radians()).collect(),
            cap,
            weight,
        };
        let src_albedo = suite::albedos(source.as_ref(), &opts.albedo_thetas);
        match suite::metrics(table.as_ref(), source.as_ref(), &src_albedo, &opts) {
            Ok(r) => json!({
                "rel_rmse": r.rel_rmse,
                "max_rel": r.max_rel,
                "albedo_err": r.albedo_err,
                "pairs": opts.pairs,
                "weight": if measured { "cos θi cos θo, within 80°" } else { "cos θi cos θo" },
            })
            .to_string(),
            Err(e) => json!({ "error": e.to_string() }).to_string(),
        }
    });
    source_health
        .health()
        .map_err(|e| Response::error(500, &e.to_string()))?;
    answer(table_health.as_ref(), body.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdftab::{Brdf, Channels, Flags};
    use glam::DVec3;

    /// A black BRDF that reports a read failure, as a table with a corrupt chunk does.
    struct Failed(Channels);

    impl Brdf for Failed {
        fn channels(&self) -> &Channels {
            &self.0
        }
        fn eval(&self, _: DVec3, _: DVec3, out: &mut [f32]) {
            out.fill(0.0);
        }
        fn flags(&self) -> Flags {
            Flags::default()
        }
        fn describe(&self) -> String {
            "failed".into()
        }
        fn health(&self) -> brdftab::Result<()> {
            Err(brdftab::Error::Unsupported(
                "chunk 0: checksum mismatch".into(),
            ))
        }
    }

    #[test]
    fn a_source_that_failed_answers_its_error_not_its_zeros() {
        let failed = Failed(Channels::Rgb);
        let body = eval::polar(&failed, 30.0, 0.0, 5, Channel::Y).to_string();
        let r = answer(&failed, body).unwrap_err();
        assert_eq!(r.status, 500);
        assert!(String::from_utf8_lossy(&r.body).contains("checksum"));
        let lambert = brdftab::ModelSpec::parse(r#"{"model": "lambert", "kd": 0.5}"#)
            .unwrap()
            .build(&Channels::Rgb)
            .unwrap();
        let body = eval::polar(lambert.as_ref(), 30.0, 0.0, 5, Channel::Y).to_string();
        assert_eq!(answer(lambert.as_ref(), body).unwrap().status, 200);
    }

    #[test]
    fn a_delta_lobe_is_announced_since_no_plot_of_f_r_shows_it() {
        let open = |s: &str| {
            brdftab::ModelSpec::parse(s)
                .unwrap()
                .build(&Channels::Rgb)
                .unwrap()
        };
        let smooth = open(r#"{"model": "lambert", "kd": 0.3}"#);
        let mirror = open(r#"{"model": "mirror", "fresnel": {"conductor": "Ag"}}"#);
        let sum = open(
            r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.3},
                {"model": "mirror", "fresnel": {"conductor": "Ag"}}]}"#,
        );
        for (b, want) in [(&smooth, false), (&mirror, true), (&sum, true)] {
            assert_eq!(
                eval::polar(b.as_ref(), 30.0, 0.0, 5, Channel::Y)["delta"],
                want,
                "{}",
                b.describe()
            );
        }
    }
}
