//! What a request may ask of the viewer, checked before any handler runs.
//!
//! The server holds only the materials named on its command line (by index) and evaluates inline
//! analytic specs; nothing a page sends can name a file. Three checks keep it so:
//!
//! - [`host_allowed`]: the `Host` header must name the bound address (or `localhost` on a
//!   loopback bind). A page on another site that rebinds its DNS name to 127.0.0.1 sends its own
//!   name as `Host` and is refused: that is the defence against DNS rebinding.
//!   An absolute-form target (`http://HOST/path`) names its host itself ([`effective`]): its
//!   authority is checked in the header's place.
//! - [`split_target`]: the path must be plain (no `%`, no `..`, no backslash); only the query is
//!   percent-decoded, and it only ever carries numbers, ids and inline specs.
//! - [`inline_spec`]: a page-supplied SOURCE is accepted only if the library's own
//!   classification ([`brdftab::source::classify`]) calls it a spec *and* it is inline JSON: a
//!   `.json` path, a table, `DB#NAME`, a MERL or RGL file are refused without being touched.

use std::net::SocketAddr;

use brdftab::source::{SourceKind, classify};
use brdftab::spec::ModelSpec;

/// The most query parameters a request may carry.
const MAX_PARAMS: usize = 32;

/// The `Host` values the server answers to when bound at `addr`: the address itself, and
/// `localhost` when the address is a loopback one.
pub fn allowed_hosts(addr: SocketAddr) -> Vec<String> {
    let port = addr.port();
    let mut hosts = vec![addr.to_string()];
    if addr.ip().is_loopback() {
        hosts.push(format!("localhost:{port}"));
        hosts.push(format!("127.0.0.1:{port}"));
    }
    hosts
}

/// True if `host` (the request's `Host` header) is one of `allowed`.
pub fn host_allowed(host: Option<&str>, allowed: &[String]) -> bool {
    host.is_some_and(|h| allowed.iter().any(|a| a.eq_ignore_ascii_case(h)))
}

/// The host and the origin-form target of a request: an absolute-form target
/// (`http://127.0.0.1:8127/api/models`, what a client talking to a proxy sends) names the host
/// itself, and RFC 9112 (3.2.2, 3.3) has the server accept it and ignore the `Host` header. Its
/// authority then goes through [`host_allowed`] as a `Host` header would; userinfo is refused.
pub fn effective<'a>(
    target: &'a str,
    host: Option<&'a str>,
) -> Result<(Option<&'a str>, &'a str), &'static str> {
    let scheme = "http://";
    match target.get(..scheme.len()) {
        Some(s) if s.eq_ignore_ascii_case(scheme) => {
            let rest = &target[scheme.len()..];
            let end = rest.find(['/', '?']).unwrap_or(rest.len());
            let (authority, path) = rest.split_at(end);
            if authority.contains('@') {
                return Err("userinfo in the request target");
            }
            // An empty path is `/` (RFC 9112 3.2.1); `http://host?x` is not served.
            match path {
                "" => Ok((Some(authority), "/")),
                p if p.starts_with('/') => Ok((Some(authority), p)),
                _ => Err("bad path"),
            }
        }
        _ => Ok((host, target)),
    }
}

/// Decoded query parameters, in request order.
pub type Params = Vec<(String, String)>;

/// A request target split into its path and decoded query parameters, or why it is refused.
/// A parameter given twice is refused: `theta_i=30&theta_i=60` (a URL edited by appending) has
/// no one meaning, and answering for either value would be a silent guess.
pub fn split_target(target: &str) -> Result<(&str, Params), String> {
    let (path, query) = target.split_once('?').unwrap_or((target, ""));
    if !path.starts_with('/')
        || path.contains('%')
        || path.contains('\\')
        || path.split('/').any(|seg| seg == ".." || seg == ".")
    {
        return Err("bad path".into());
    }
    let mut params: Params = Vec::new();
    for pair in query.split('&').filter(|p| !p.is_empty()) {
        if params.len() == MAX_PARAMS {
            return Err("too many query parameters".into());
        }
        let (k, v) = pair.split_once('=').unwrap_or((pair, ""));
        let k = decode(k)?;
        if params.iter().any(|(n, _)| *n == k) {
            return Err(format!("{k}: given more than once"));
        }
        params.push((k, decode(v)?));
    }
    Ok((path, params))
}

/// Percent-decodes a query component (`+` is a space); the result must be UTF-8 without NUL.
fn decode(s: &str) -> Result<String, &'static str> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'%' => {
                let hex = b.get(i + 1..i + 3).ok_or("bad percent escape")?;
                let hex = std::str::from_utf8(hex).map_err(|_| "bad percent escape")?;
                out.push(u8::from_str_radix(hex, 16).map_err(|_| "bad percent escape")?);
                i += 3;
            }
            b'+' => {
                out.push(b' ');
                i += 1;
            }
            c => {
                out.push(c);
                i += 1;
            }
        }
    }
    let text = String::from_utf8(out).map_err(|_| "query is not UTF-8")?;
    if text.contains('\0') {
        return Err("NUL in query");
    }
    Ok(text)
}

/// Parses a page-supplied SOURCE that must be an inline analytic spec; anything else — a path to
/// a `.json` file, a table, `DB#NAME`, a measured file — is refused without opening it.
///
/// The `{` comes first: [`classify`] looks for a file named like a `FILE#NAME` string, so a
/// string that is not inline JSON must be refused before anything classifies it.
pub fn inline_spec(source: &str) -> Result<ModelSpec, String> {
    let refused = || "only inline model specs ({\"model\": ...}) are evaluated here".to_owned();
    if !source.trim_start().starts_with('{') {
        return Err(refused());
    }
    if classify(source) != SourceKind::Spec {
        return Err(refused());
    }
    ModelSpec::parse(source).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hosts_are_the_bound_address_and_localhost() {
        let a: SocketAddr = "127.0.0.1:8127".parse().unwrap();
        let ok = allowed_hosts(a);
        assert!(host_allowed(Some("127.0.0.1:8127"), &ok));
        assert!(host_allowed(Some("LOCALHOST:8127"), &ok));
        for bad in ["evil.example:8127", "127.0.0.1:80", "127.0.0.1", ""] {
            assert!(!host_allowed(Some(bad), &ok), "{bad}");
        }
        assert!(!host_allowed(None, &ok));
    }

    #[test]
    fn paths_with_escapes_or_dot_segments_are_refused() {
        for bad in [
            "/../etc/passwd",
            "/a/%2e%2e/b",
            "/a\\b",
            "x",
            "/./x",
            "/a/..",
        ] {
            assert!(split_target(bad).is_err(), "{bad}");
        }
        let (path, q) = split_target("/api/polar?m=1&spec=%7B%22a%22+1%7D").unwrap();
        assert_eq!(path, "/api/polar");
        assert_eq!(q[1], ("spec".to_owned(), "{\"a\" 1}".to_owned()));
        assert!(split_target("/x?a=%zz").is_err());
        assert!(split_target("/x?a=%00").is_err());
    }

    #[test]
    fn absolute_form_targets_name_their_host() {
        let ok = vec!["127.0.0.1:8127".to_owned()];
        let (h, t) =
            effective("http://127.0.0.1:8127/api/models?x=1", Some("evil.example")).unwrap();
        assert_eq!((h, t), (Some("127.0.0.1:8127"), "/api/models?x=1"));
        assert!(host_allowed(h, &ok));
        assert_eq!(
            effective("HTTP://127.0.0.1:8127", None).unwrap(),
            (Some("127.0.0.1:8127"), "/")
        );
        // The authority is checked as a Host header would be, whatever the header says.
        let (h, _) = effective("http://evil.example/api/models", Some("127.0.0.1:8127")).unwrap();
        assert!(!host_allowed(h, &ok));
        assert!(effective("http://u@127.0.0.1:8127/", None).is_err());
        assert!(effective("http://127.0.0.1:8127?x", None).is_err());
        assert_eq!(effective("/a", Some("h")).unwrap(), (Some("h"), "/a"));
    }

    #[test]
    fn only_inline_specs_pass() {
        assert!(inline_spec(r#"{"model": "lambert", "kd": 0.5}"#).is_ok());
        for bad in [
            "paint.json",
            "lib.btdb#gold",
            "a.binary",
            "b.bsdf",
            "/etc/passwd",
            "",
        ] {
            assert!(inline_spec(bad).is_err(), "{bad}");
        }
    }
}
