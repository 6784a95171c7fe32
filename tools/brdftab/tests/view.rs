//! `brdftab view` end to end: the binary serving a database baked in a temporary directory,
//! asked over plain TCP. The materials list, every view, the security checks (Host header,
//! path traversal, ids out of range, page-supplied SOURCE strings that are not inline specs,
//! oversized requests) and the time of a slider's requests.

mod common;

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

use brdftab::testkit::TempDir;
use common::brdftab;
use common::viewer::{database, enc, get, get_json, send, send_raw, start};

#[test]
fn materials_and_views_of_a_database() {
    let d = TempDir::new("view-api");
    let db = database(&d);
    let v = start(&[&db, r#"{"model": "ggx", "alpha": 0.2}"#]);
    let list = get_json(&v, "/api/materials");
    let list = list.as_array().unwrap();
    assert_eq!(list.len(), 3);
    assert_eq!(
        (list[0]["name"].as_str(), list[1]["name"].as_str()),
        (Some("gold"), Some("matte"))
    );
    for m in &list[..2] {
        assert_eq!(m["kind"], "table");
        assert_eq!(m["has_source"], true);
        assert!(m["bytes"].as_u64().unwrap() > 0 && m["ratio"].as_f64().unwrap() > 1.0);
        assert_eq!(m["codec"]["quant"], "log16");
        assert!(m["grid"].as_str().unwrap().starts_with("halfdiff"));
    }
    assert_eq!(
        (list[2]["kind"].as_str(), list[2]["spec"]["model"].as_str()),
        (Some("spec"), Some("ggx"))
    );

    // The matte table is 0.2 everywhere in the plane of incidence, and so is its source.
    for of in ["table", "source"] {
        let p = get_json(&v, &format!("/api/polar?m=1&of={of}&theta_i=30&n=9"));
        let y = p["y"].as_array().unwrap();
        assert_eq!(y.len(), 9);
        for f in &y[1..8] {
            assert!((f.as_f64().unwrap() - 0.2).abs() < 2e-3, "{of}: {p}");
        }
    }
    // Gold's peak (of f_r cos θo) moves with θi, towards the mirror direction: the plot
    // changes with the slider.
    let a = get_json(&v, "/api/polar?m=0&theta_i=10&n=181");
    let b = get_json(&v, "/api/polar?m=0&theta_i=50&n=181");
    assert_ne!(a["y"], b["y"]);
    let peak = |p: &serde_json::Value| {
        let t = |k: usize| p["theta_o"][k].as_f64().unwrap();
        let y = |k: usize| p["y"][k].as_f64().unwrap() * t(k).to_radians().cos();
        t((0..181).max_by(|&i, &j| y(i).total_cmp(&y(j))).unwrap())
    };
    let (pa, pb) = (peak(&a), peak(&b));
    assert!(
        (0.0..=25.0).contains(&pa) && pb > pa + 25.0,
        "peaks at {pa}° and {pb}°"
    );

    let lobe = get_json(&v, "/api/lobe?m=0&theta_i=30&nt=10&np=20");
    assert_eq!(lobe["y"].as_array().unwrap().len(), 200);
    let slice = get_json(&v, "/api/slice?m=0&n=16");
    assert_eq!(slice["y"].as_array().unwrap().len(), 256);
    let sphere = get_json(&v, "/api/sphere?m=0&size=32");
    let rgb = sphere["rgb"].as_array().unwrap();
    assert_eq!(rgb.len(), 32 * 32 * 3);
    assert!(
        rgb.iter().any(|x| x.as_u64().unwrap() > 100),
        "a lit sphere has bright pixels"
    );
    let albedo = get_json(&v, "/api/albedo?m=1");
    let a0 = albedo["y"][0].as_f64().unwrap();
    assert!((a0 - 0.2 * std::f64::consts::PI).abs() < 5e-3, "{albedo}");

    // Error figures against the source: the matte table is exact up to its codec; gold's small
    // grid blurs Cook-Torrance's lobe and misses its grazing growth.
    let err = |m: usize| {
        let c = get_json(&v, &format!("/api/compare?m={m}"));
        (
            c["rel_rmse"].as_f64().unwrap(),
            c["albedo_err"].as_f64().unwrap(),
        )
    };
    let (matte, gold) = (err(1), err(0));
    assert!(matte.0 < 2e-3 && matte.1 < 2e-3, "{matte:?}");
    assert!(gold.0 > 10.0 * matte.0 && gold.1 < 0.05, "{gold:?}");
    let pl = get_json(&v, "/api/plausibility?m=1");
    assert_eq!(
        (pl["positive"].as_bool(), pl["energy_conserving"].as_bool()),
        (Some(true), Some(true))
    );

    // Inline specs are re-evaluated as given (the sliders' requests).
    let spec = enc(r#"{"model": "lambert", "kd": 0.1}"#);
    let p = get_json(&v, &format!("/api/polar?spec={spec}&n=3"));
    assert!((p["y"][1].as_f64().unwrap() - 0.1).abs() < 1e-6, "{p}");
    let pl = get_json(&v, &format!("/api/plausibility?spec={spec}"));
    assert_eq!(pl["plausible"], true);
    let (status, body) = get(
        &v,
        &format!(
            "/api/polar?spec={}",
            enc(r#"{"model": "lambert", "kd": -1}"#)
        ),
    );
    assert!(status == 400 && body.contains("kd"), "{status} {body}");

    // The page and its assets are served from the binary.
    let (status, page) = get(&v, "/");
    assert!(status == 200 && page.contains("/app.js"), "{status}");
    for asset in ["/app.js", "/list.js", "/spec.js", "/plots.js", "/style.css"] {
        assert_eq!(get(&v, asset).0, 200, "{asset}");
    }
}

#[test]
fn requests_cannot_reach_beyond_the_materials_named_at_start() {
    let d = TempDir::new("view-security");
    let db = database(&d);
    let secret = d.file("secret.json");
    std::fs::write(&secret, r#"{"model": "lambert", "kd": 0.3}"#).unwrap();
    let v = start(&[&format!("{db}#matte")]);
    assert_eq!(get_json(&v, "/api/materials").as_array().unwrap().len(), 1);

    // DNS rebinding: another name for this address, or no Host at all, is refused.
    let p = v.port;
    for host in [
        format!("Host: evil.example:{p}\r\n"),
        format!("Host: 127.0.0.1:{}\r\n", p + 1),
        String::new(),
    ] {
        let (status, _) = send(
            p,
            format!("GET /api/materials HTTP/1.1\r\n{host}\r\n").as_bytes(),
        );
        assert_eq!(status, 403, "{host:?}");
    }
    assert_eq!(
        send(
            p,
            format!("GET / HTTP/1.1\r\nHost: localhost:{p}\r\n\r\n").as_bytes()
        )
        .0,
        200
    );

    // An absolute-form target (RFC 9112 3.2.2: a server must accept it) is served, and its
    // authority, not the Host header, is what the rebinding check reads.
    let abs = |authority: &str, host: &str| {
        let r = format!("GET http://{authority}/api/materials HTTP/1.1\r\nHost: {host}\r\n\r\n");
        send(p, r.as_bytes()).0
    };
    assert_eq!(
        abs(&format!("127.0.0.1:{p}"), &format!("127.0.0.1:{p}")),
        200
    );
    assert_eq!(abs(&format!("localhost:{p}"), "evil.example"), 200);
    assert_eq!(
        abs(&format!("evil.example:{p}"), &format!("127.0.0.1:{p}")),
        403
    );
    assert_eq!(
        abs(&format!("x@127.0.0.1:{p}"), &format!("127.0.0.1:{p}")),
        400
    );

    // Path traversal, plain or encoded, and unknown routes.
    for target in [
        "/../../etc/passwd",
        "/%2e%2e/%2e%2e/etc/passwd",
        "/api/%2e%2e/materials",
        "/..%2f..%2fetc",
    ] {
        assert_eq!(get(&v, target).0, 400, "{target}");
    }
    for target in ["/etc/passwd", "/api/unknown", "/api", "/index.html/.."] {
        assert!(matches!(get(&v, target).0, 400 | 404), "{target}");
    }
    // Ids out of range or not ids, a source that does not exist.
    for target in [
        "/api/polar?m=1",
        "/api/polar?m=99999999999999999999",
        "/api/polar?m=-1",
        "/api/polar?m=..%2Fsecret",
        "/api/compare?m=7",
    ] {
        assert!(matches!(get(&v, target).0, 400 | 404), "{target}");
    }
    // Page-supplied SOURCE strings other than inline specs: never opened.
    for source in [
        secret.as_str(),
        &format!("{db}#gold"),
        &db,
        "/etc/passwd",
        "x.binary",
        "y.bsdf",
        "../lib.btdb",
    ] {
        let (status, body) = get(&v, &format!("/api/polar?spec={}", enc(source)));
        assert!(
            status == 400 && body.contains("only inline model specs"),
            "{source}: {status} {body}"
        );
    }
    // Numbers outside their ranges (unbounded work) are refused.
    for target in [
        "/api/polar?m=0&n=100000",
        "/api/sphere?m=0&size=5000",
        "/api/polar?m=0&theta_i=NaN",
        "/api/polar?m=0&n=10.5",
        "/api/sphere?m=0&size=1e2",
        "/api/slice?m=0&n=+64",
    ] {
        assert_eq!(get(&v, target).0, 400, "{target}");
    }
    // Only GET; bounded heads and bodies.
    let post = format!(
        "POST /api/materials HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nContent-Length: 2\r\n\r\n{{}}"
    );
    let refused = send_raw(p, post.as_bytes());
    assert!(refused.starts_with("HTTP/1.1 405"), "{refused}");
    // A 405 names the methods that are served (RFC 9110 §15.5.6); it named none.
    let head = refused.split("\r\n\r\n").next().unwrap();
    assert!(head.contains("\r\nAllow: GET, HEAD\r\n"), "{head}");
    // A parameter given twice has no one meaning: it was answered for the first, silently.
    for target in [
        "/api/polar?m=0&theta_i=30&theta_i=60",
        "/api/polar?m=0&m=1",
        "/api/polar?m=0&of=source&of=table",
    ] {
        let (status, body) = get(&v, target);
        assert!(
            status == 400 && body.contains("more than once"),
            "{target}: {status} {body}"
        );
    }
    let long = format!(
        "GET /api/polar?m=0&x={} HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\n\r\n",
        "a".repeat(64 * 1024)
    );
    assert_eq!(send(p, long.as_bytes()).0, 431);
    let big = format!(
        "POST /api/polar HTTP/1.1\r\nHost: 127.0.0.1:{p}\r\nContent-Length: 10000000\r\n\r\n"
    );
    assert_eq!(send(p, big.as_bytes()).0, 413);
    // A client that stalls mid-request is cut off (the read timeout), and the server lives on.
    let mut stalled = TcpStream::connect(("127.0.0.1", p)).unwrap();
    stalled.write_all(b"GET / HTTP/1.1\r\n").unwrap();
    stalled
        .set_read_timeout(Some(Duration::from_secs(30)))
        .unwrap();
    let mut out = String::new();
    let _ = stalled.read_to_string(&mut out);
    assert!(out.starts_with("HTTP/1.1 408"), "{out:?}");
    assert_eq!(get(&v, "/api/materials").0, 200);
}

#[test]
fn a_slider_step_is_answered_within_the_redraw_budget() {
    let d = TempDir::new("view-timing");
    let db = database(&d);
    let v = start(&[&format!("{db}#gold")]);
    // What the page asks on one θi step (polar and lobe), and a small sphere while dragging the
    // light: the median over 20 steps, against the 100 ms redraw budget (in a release build).
    let mut times = Vec::new();
    for k in 0..20 {
        let t0 = Instant::now();
        get_json(&v, &format!("/api/polar?m=0&theta_i={}&n=181", 2 * k));
        get_json(&v, &format!("/api/lobe?m=0&theta_i={}&nt=19&np=36", 2 * k));
        get_json(&v, &format!("/api/sphere?m=0&size=48&lp={}", 5 * k));
        times.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    let median = times[times.len() / 2];
    eprintln!(
        "slider step (polar + lobe + 48² sphere): median {median:.1} ms, max {:.1} ms",
        times[times.len() - 1]
    );
    let budget = if cfg!(debug_assertions) {
        2000.0
    } else {
        100.0
    };
    assert!(median < budget, "median {median:.1} ms");
}

#[test]
fn it_binds_loopback_by_default_and_refuses_an_unnameable_bind_address() {
    let d = TempDir::new("view-bind");
    let db = database(&d);
    // `start` reads the URL: the default bind is 127.0.0.1.
    let v = start(&[&db]);
    assert_eq!(get_json(&v, "/api/materials").as_array().unwrap().len(), 2);
    let r = brdftab(&["view", &db, "--bind", "0.0.0.0", "--port", "0"]);
    assert!(
        !r.ok && r.stderr.starts_with("error: ") && r.stderr.contains("--bind"),
        "{}",
        r.stderr
    );
}

#[test]
fn a_database_entry_is_read_from_the_database_not_a_file_named_like_it() {
    // A SOURCE string `lib.btdb#matte` is looked up as a whole file first; the viewer lists a
    // database's entries and must open each from the database even when a file of that name
    // lies beside it (here a table of another material).
    let d = TempDir::new("view-decoy");
    let db = database(&d);
    let decoy = d.file("decoy.btdb");
    let r = brdftab(&[
        "bake",
        r#"{"model": "lambert", "kd": 0.02}"#,
        "-o",
        &decoy,
        "--preset",
        "small",
    ]);
    assert!(r.ok, "{}", r.stderr);
    std::fs::copy(&decoy, format!("{db}#matte")).unwrap();
    use brdftab::Brdf;
    let reg = brdftab_tools::view::Registry::open(std::slice::from_ref(&db)).unwrap();
    let matte = reg
        .materials
        .iter()
        .find(|m| m.info["name"] == "matte")
        .expect("the database's entry");
    let (wi, wo) = (glam::DVec3::Z, glam::DVec3::new(0.6, 0.0, 0.8));
    let mut f = [0.0f32; 3];
    matte.brdf.eval(wi, wo, &mut f);
    // Lambert kd = 0.2 (the entry), not 0.02 (the decoy): f_r = kd to the codec's 1e-3.
    assert!((f[0] - 0.2).abs() < 1e-3, "{f:?}");
}
