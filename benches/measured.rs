//! Measured-data benchmarks (plain timing harness, short runs for a shared machine):
//!
//! - native RGL evaluation, ns per `eval`;
//! - MERL: load time of a (synthetic) 35 MB `.binary` file, ns per nearest lookup;
//! - the RGL material resampled to the MERL grid: ns per lookup and its error against native.
//!
//! Run: `cargo bench --bench measured`.

use std::hint::black_box;
use std::time::Instant;

use brdftab::Brdf;
use brdftab::geometry::uniform_hemisphere;
use brdftab::measured::{MerlBrdf, RglBrdf, merl};
use brdftab::testkit::Pcg32;
use glam::DVec3;

/// The shipped RGL file `name` (`data/rgl`, see `brdftab::measured::data`); a missing file
/// fails loudly.
fn rgl(name: &str) -> String {
    brdftab::measured::data::rgl_file(name)
        .unwrap_or_else(|e| panic!("{e}"))
        .display()
        .to_string()
}

fn pairs(n: usize) -> Vec<(DVec3, DVec3)> {
    let mut rng = Pcg32::new(42);
    (0..n)
        .map(|_| {
            (
                uniform_hemisphere(rng.next_dvec2()),
                uniform_hemisphere(rng.next_dvec2()),
            )
        })
        .collect()
}

/// Best-of-3 ns per evaluation over `pairs`.
fn ns_per_eval(b: &dyn Brdf, pairs: &[(DVec3, DVec3)]) -> f64 {
    let mut f = [0f32; 64];
    let c = b.channels().len();
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let t = Instant::now();
        for &(wi, wo) in pairs {
            b.eval(black_box(wi), black_box(wo), &mut f[..c]);
            black_box(&f);
        }
        best = best.min(t.elapsed().as_nanos() as f64 / pairs.len() as f64);
    }
    best
}

/// Cosine-weighted relative RMSE of `b` against `reference` over `pairs` (all channels):
/// sqrt(Σ cos θi cos θo (b − r)²) / sqrt(Σ cos θi cos θo r²).
fn rel_rmse(b: &dyn Brdf, reference: &dyn Brdf, pairs: &[(DVec3, DVec3)]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    let (mut fa, mut fb) = ([0f32; 3], [0f32; 3]);
    for &(wi, wo) in pairs {
        b.eval(wi, wo, &mut fa);
        reference.eval(wi, wo, &mut fb);
        let w = wi.z * wo.z;
        for k in 0..3 {
            num += w * (fa[k] as f64 - fb[k] as f64).powi(2);
            den += w * (fb[k] as f64).powi(2);
        }
    }
    (num / den).sqrt()
}

/// Coherent pairs, as a renderer or a slice produces them: 200 incident directions, each with a
/// 32 × 32 sweep of outgoing directions in scan order.
fn coherent_pairs() -> Vec<(DVec3, DVec3)> {
    let mut rng = Pcg32::new(43);
    let mut v = Vec::with_capacity(200 * 1024);
    for _ in 0..200 {
        let wi = uniform_hemisphere(rng.next_dvec2());
        for a in 0..32 {
            for b in 0..32 {
                let u = glam::DVec2::new((a as f64 + 0.5) / 32.0, (b as f64 + 0.5) / 32.0);
                v.push((wi, uniform_hemisphere(u)));
            }
        }
    }
    v
}

fn main() {
    let p = pairs(200_000);
    let coherent = coherent_pairs();
    println!(
        "measured benchmarks ({} random direction pairs, best of 3)",
        p.len()
    );

    for file in [
        "paper_white_rgb.bsdf",
        "cc_ibiza_sunset_rgb.bsdf",
        "cg_sunflower_rgb.bsdf",
    ] {
        let t = Instant::now();
        let b = RglBrdf::open(rgl(file)).unwrap();
        let load = t.elapsed().as_secs_f64() * 1e3;
        println!(
            "rgl native eval   {file:<28} {:7.1} ns/eval   (open {load:.1} ms)",
            ns_per_eval(&b, &p)
        );
    }

    // MERL: a synthetic file of random values.
    let dir = brdftab::testkit::TempDir::new("bench-measured");
    let path = dir.join("synthetic.binary");
    let mut rng = Pcg32::new(7);
    let data: Vec<f64> = (0..3 * merl::SAMPLES)
        .map(|_| rng.next_f64() * 2000.0)
        .collect();
    MerlBrdf::from_raw("synthetic", data)
        .unwrap()
        .write(&path)
        .unwrap();
    let mut best = f64::INFINITY;
    let mut m = None;
    for _ in 0..3 {
        let t = Instant::now();
        m = Some(MerlBrdf::open(&path).unwrap());
        best = best.min(t.elapsed().as_secs_f64());
    }
    let m = m.unwrap();
    println!(
        "merl load         synthetic 34,992,012 bytes    {:7.3} s (target ≤ 0.3 s)",
        best
    );
    let t = Instant::now();
    let sha = merl::sha256_file(&path).unwrap();
    println!(
        "merl sha256       (info only, not on load)      {:7.3} s  {}…",
        t.elapsed().as_secs_f64(),
        &sha[..12]
    );
    println!(
        "merl nearest eval                               {:7.1} ns/eval",
        ns_per_eval(&m, &p)
    );
    drop(dir);

    // The RGL material baked into tables (halfdiff, sqrt θh, isotropic) and the MERL grid.
    use brdftab::table::presets::Preset;
    use brdftab::table::{BakeOptions, Interp, Symmetry, TabulatedBrdf, bake};
    let b = RglBrdf::open(rgl("cc_ibiza_sunset_rgb.bsdf")).unwrap();
    let native = ns_per_eval(&b, &p);
    let native_coh = ns_per_eval(&b, &coherent);
    println!("rgl native eval   cc_ibiza_sunset, coherent pairs {native_coh:7.1} ns/eval");
    let q = &p[..100_000];
    let iso = Symmetry {
        isotropic: true,
        reciprocal: false,
        bilateral: false,
    };
    for preset in [Preset::Small, Preset::Medium, Preset::Large] {
        let grid = preset.grid(None, iso, brdftab::Channels::Rgb).unwrap();
        let t = Instant::now();
        let (table, _) = bake(&b, &grid, &BakeOptions::default()).unwrap();
        let secs = t.elapsed().as_secs_f64();
        for interp in [Interp::Linear, Interp::Nearest] {
            let tab = TabulatedBrdf::from_table(table.clone()).with_interp(interp);
            let ns = ns_per_eval(&tab, &p);
            let ns_coh = ns_per_eval(&tab, &coherent);
            let acc = brdftab::analysis::accuracy::compare(&tab, &b, 100_000, 1).unwrap();
            println!(
                "rgl → table {preset:?} {interp:?} ({}; bake {secs:.1} s):\n    random {ns:6.1} ns/lookup ({:.1}× native), \
                 coherent {ns_coh:6.1} ns/lookup ({:.1}× native); \
                 error of f_r·cos θo (cos θi cos θo weights) {:.4}, accuracy::compare (cos θi weights) {:.4}",
                grid.summary(),
                native / ns,
                native_coh / ns_coh,
                rel_rmse(&tab, &b, q),
                acc.rel_rmse
            );
        }
    }
    let t = Instant::now();
    let resampled = MerlBrdf::from_brdf(&b);
    let secs = t.elapsed().as_secs_f64();
    println!(
        "rgl → merl grid   cc_ibiza_sunset (resample {secs:.2} s) {:7.1} ns/lookup, error of f_r·cos θo {:.4}",
        ns_per_eval(&resampled, &p),
        rel_rmse(&resampled, &b, q)
    );
}
