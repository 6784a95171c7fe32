//! From a request to a response: the security checks first, then the fixed table of routes
//! (the embedded page and the JSON API). Only `GET` and `HEAD` exist; anything else is 405.

use super::api::{self, Query};
use super::http::{Request, Response};
use super::registry::Registry;
use super::security;

/// The content type of the scripts.
const JS: &str = "text/javascript; charset=utf-8";

/// The page, its scripts and its style, embedded in the binary: the viewer works offline.
const ASSETS: &[(&str, &str, &str)] = &[
    (
        "/",
        "text/html; charset=utf-8",
        include_str!("assets/index.html"),
    ),
    ("/app.js", JS, include_str!("assets/app.js")),
    ("/list.js", JS, include_str!("assets/list.js")),
    ("/spec.js", JS, include_str!("assets/spec.js")),
    ("/plots.js", JS, include_str!("assets/plots.js")),
    ("/report.js", JS, include_str!("assets/report.js")),
    (
        "/style.css",
        "text/css; charset=utf-8",
        include_str!("assets/style.css"),
    ),
];

/// The response to `req` for a server that answers to the `Host` values `hosts`.
pub fn handle(reg: &Registry, hosts: &[String], req: &Request) -> Response {
    let (host, target) = match security::effective(&req.target, req.host.as_deref()) {
        Ok(x) => x,
        Err(e) => return Response::error(400, e),
    };
    if !security::host_allowed(host, hosts) {
        return Response::error(403, "unexpected Host header");
    }
    if req.method != "GET" && req.method != "HEAD" {
        return Response::error(405, "only GET and HEAD are served");
    }
    let (path, params) = match security::split_target(target) {
        Ok(x) => x,
        Err(e) => return Response::error(400, &e),
    };
    if let Some((_, ty, body)) = ASSETS.iter().find(|(p, _, _)| *p == path) {
        return Response {
            status: 200,
            content_type: ty,
            body: body.as_bytes().to_vec(),
        };
    }
    let q = Query(params);
    let result = match path {
        "/api/materials" => Ok(api::materials(reg)),
        "/api/models" => Ok(api::models()),
        "/api/polar" => api::polar(reg, &q),
        "/api/lobe" => api::lobe(reg, &q),
        "/api/slice" => api::slice(reg, &q),
        "/api/sphere" => api::sphere(reg, &q),
        "/api/albedo" => api::albedo(reg, &q),
        "/api/plausibility" => api::plausibility(reg, &q),
        "/api/compare" => api::compare(reg, &q),
        _ => Err(Response::error(404, "no such route")),
    };
    result.unwrap_or_else(|e| e)
}
