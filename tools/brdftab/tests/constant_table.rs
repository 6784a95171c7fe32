//! A table of a constant BRDF is constant: `brdftab bake` with every default (medium preset,
//! log16 at 1e-3) of a Lambert BRDF evaluates to kd — the codec stores constant chunks exactly
//! (chunk version 3 anchors each channel's log16 grid at its most common value).

mod common;

use brdftab::geometry::uniform_hemisphere;
use brdftab::testkit::{Pcg32, TempDir};

#[test]
fn default_lambert_table_evaluates_to_kd() {
    let dir = TempDir::new("constant");
    let table = dir.join("lam.btdb");
    let kd = [0.1f64, 0.2, 0.3];
    let spec = r#"{"model":"lambert","kd":[0.1,0.2,0.3]}"#;
    let o = common::brdftab(&["bake", spec, "-o", table.to_str().unwrap()]);
    assert!(o.ok, "{}", o.stderr);
    assert!(
        o.stderr.contains("log16"),
        "the default codec is log16: {}",
        o.stderr
    );

    // Random pairs over both hemispheres' interiors, plus near-normal and near-grazing ones.
    let mut rng = Pcg32::new(12);
    let mut pairs = String::new();
    for _ in 0..5000 {
        let (wi, wo) = (
            uniform_hemisphere(rng.next_dvec2()),
            uniform_hemisphere(rng.next_dvec2()),
        );
        if wi.z > 1e-6 && wo.z > 1e-6 {
            pairs += &format!("{} {} {} {} {} {}\n", wi.x, wi.y, wi.z, wo.x, wo.y, wo.z);
        }
    }
    pairs += "0 0 1 0 0 1\n0.9999 0 0.0141 -0.9999 0 0.0141\n";
    // (The runner feeds stdin from a thread: the output would fill its pipe before the input
    // is written.)
    let o = common::brdftab_with_stdin(&["eval", table.to_str().unwrap()], &pairs);
    assert!(o.ok, "{}", o.stderr);
    let out = o.stdout;
    let mut n = 0;
    for line in out.lines() {
        let v: Vec<f64> = line
            .split_whitespace()
            .map(|t| t.parse().unwrap())
            .collect();
        assert_eq!(v.len(), 3, "{line}");
        for c in 0..3 {
            // kd is stored as f32 (relative rounding ≤ 2^-24) and interpolated with weights
            // that sum to 1 in f32 (a few more roundings): 1e-6 is ten times that.
            let rel = (v[c] - kd[c]).abs() / kd[c];
            assert!(rel <= 1e-6, "channel {c}: {} vs {} ({rel:e})", v[c], kd[c]);
        }
        n += 1;
    }
    assert_eq!(n, pairs.lines().count());
}
