//! Lookups on directions as renderers hold them: pbrt-v4, Mitsuba 3 and any C or numpy float32
//! caller keep directions in f32, unit only to the rounding of their normalization, and hand
//! them over as f64. For each SOURCE this times `eval`, `eval_batch` (blocks of 4096) and
//! `sample` on random pairs, exact in f64 and the same pairs rounded to f32 and normalized
//! there, in the same rounds (median of 5, one thread), and prints the ratios. Uses only the
//! public API, so the same file runs against any commit (the session-35 before/after in
//! BENCHMARKS.md "Directions as renderers pass them").
//!
//! `cargo run --release --example f32_directions -- SOURCE...`

use std::time::Instant;

use brdftab::Brdf;
use brdftab::geometry::uniform_hemisphere;
use glam::{DVec2, DVec3};

/// Pairs (wi, wo) and the numbers a sample draws from.
type Pairs = Vec<(DVec3, DVec3, DVec2)>;

fn main() -> brdftab::Result<()> {
    const N: usize = 400_000;
    const BLOCK: usize = 4096;
    for source in std::env::args().skip(1) {
        let b = brdftab::open(&source)?;
        let mut rng = brdftab::testkit::Pcg32::new(35);
        let mut pair = move || rng.next_dvec2();
        let exact: Pairs = (0..N)
            .map(|_| {
                (
                    uniform_hemisphere(pair()),
                    uniform_hemisphere(pair()),
                    pair(),
                )
            })
            .collect();
        let round = |v: DVec3| v.as_vec3().normalize().as_dvec3();
        let rounded: Pairs = exact
            .iter()
            .map(|&(a, b, u)| (round(a), round(b), u))
            .collect();
        let c = b.channels().len();
        let mut w = vec![0.0f32; c];
        let mut block = vec![0.0f32; c * BLOCK];
        // eval, eval_batch, sample; exact then rounded.
        let mut ns = vec![Vec::new(); 6];
        for _ in 0..5 {
            for (s, set) in [&exact, &rounded].into_iter().enumerate() {
                let t = Instant::now();
                for &(wi, wo, _) in set {
                    b.eval(wi, wo, &mut w);
                    std::hint::black_box(w[0]);
                }
                ns[3 * s].push(t.elapsed().as_secs_f64() / N as f64 * 1e9);
                let (wi, wo): (Vec<DVec3>, Vec<DVec3>) = set.iter().map(|p| (p.0, p.1)).unzip();
                let t = Instant::now();
                for (i, o) in wi.chunks(BLOCK).zip(wo.chunks(BLOCK)) {
                    b.eval_batch(i, o, &mut block[..c * i.len()]);
                    std::hint::black_box(block[0]);
                }
                ns[3 * s + 1].push(t.elapsed().as_secs_f64() / N as f64 * 1e9);
                let t = Instant::now();
                for &(_, wo, u) in set {
                    std::hint::black_box(b.sample(wo, u, &mut w));
                }
                ns[3 * s + 2].push(t.elapsed().as_secs_f64() / N as f64 * 1e9);
            }
        }
        let m: Vec<f64> = ns
            .into_iter()
            .map(|mut v| {
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            })
            .collect();
        println!(
            "{source}: exact eval {:.1} batch {:.1} sample {:.1} ns | f32 eval {:.1} ({:.2}×) batch {:.1} ({:.2}×) sample {:.1} ns ({:.2}×)",
            m[0],
            m[1],
            m[2],
            m[3],
            m[3] / m[0],
            m[4],
            m[4] / m[1],
            m[5],
            m[5] / m[2]
        );
    }
    Ok(())
}
