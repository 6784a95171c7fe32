//! Samples per second per core of `Brdf::sample` (direction + pdf + weight f_r cos θi / pdf), RGB,
//! single thread: the analytic models' importance samplers (target ≥ 20 M samples/s per core)
//! and tables with tabulated importance sampling (target ≥ 5 M samples/s per core).
//!
//! Each iteration draws one sample for an outgoing direction from a pool of 1024 random `wo`
//! above the horizon (cycled) with uniforms from a pool of 4096 PCG32 pairs drawn before timing
//! (cycled, so each `wo` meets four uniform pairs and branch predictors and caches see realistic
//! variety). The RNG is not timed: a renderer's sampler supplies the uniforms. Tables are `halfdiff` `small` grids (32 × 32 × 64, folded)
//! baked from the same models; their sampler is built before timing.
//!
//! Time is the benchmark thread's **CPU time** (`CLOCK_THREAD_CPUTIME_ID`), as in `benches/eval.rs`:
//! the machines this runs on are shared. samples/s per core = 1e9 / (reported ns per iteration).
//!
//! Run: `cargo bench --bench sampling -- --warm-up-time 1 --measurement-time 2`

use std::hint::black_box;

use brdftab::geometry;
use brdftab::spec::ModelSpec;
use brdftab::table::{BakeOptions, Grid, Mapping, Param, Symmetry, TabulatedBrdf, bake};
use brdftab::testkit::Pcg32;
use brdftab::{Brdf, Channels};
use criterion::measurement::{Measurement, WallTime};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec2, DVec3};

mod common;
use common::ThreadCpuTime;

/// Tables are baked from these (the analytic models timed are every entry of
/// [`brdftab::spec::MODELS`], with its example spec).
const TABLE_SOURCES: &[&str] = &["lambert", "reciprocal_phong", "cook_torrance"];

fn wos() -> Vec<DVec3> {
    let mut rng = Pcg32::new(2024);
    (0..1024)
        .map(|_| geometry::uniform_hemisphere(rng.next_dvec2()))
        .collect()
}

fn table_of(src: &dyn Brdf) -> TabulatedBrdf {
    let grid = Grid::with_sizes(
        Param::HalfDiff,
        [32, 64, 32, 64],
        [Mapping::Sqrt, Mapping::Uniform],
        Channels::Rgb,
        Symmetry::ALL,
    )
    .expect("grid");
    let (t, _) = bake(src, &grid, &BakeOptions::default()).expect("bake");
    let t = TabulatedBrdf::from_table(t);
    t.sampler(); // build the distributions before timing
    t
}

fn run<M: Measurement>(
    g: &mut criterion::BenchmarkGroup<M>,
    name: &str,
    b: &dyn Brdf,
    wos: &[DVec3],
) {
    // The uniforms are drawn before timing (a renderer's sampler supplies them), so the figure
    // is the cost of `Brdf::sample` alone, not of the random number generator.
    let mut rng = Pcg32::new(7);
    let us: Vec<DVec2> = (0..4096).map(|_| rng.next_dvec2()).collect();
    g.bench_function(name, |bch| {
        let mut w = [0.0f32; 3];
        let mut i = 0usize;
        bch.iter(|| {
            let wo = wos[i & 1023];
            let u = us[i & 4095];
            i = i.wrapping_add(1);
            let s = b.sample(black_box(wo), black_box(u), &mut w);
            black_box((s.map(|s| s.pdf), w[0]))
        })
    });
}

fn bench_sampling(c: &mut Criterion<ThreadCpuTime>) {
    let wos = wos();
    let mut g = c.benchmark_group("sample_rgb");
    g.throughput(Throughput::Elements(1));
    let mut tables = Vec::new();
    for info in brdftab::spec::MODELS {
        let Ok(m) = ModelSpec::parse(info.example).and_then(|s| s.build(&Channels::Rgb)) else {
            continue;
        };
        run(&mut g, info.name, m.as_ref(), &wos);
        if TABLE_SOURCES.contains(&info.name) {
            tables.push((format!("table_{}", info.name), table_of(m.as_ref())));
        }
    }
    for (name, t) in &tables {
        run(&mut g, name, t, &wos);
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(ThreadCpuTime(WallTime));
    targets = bench_sampling
}
criterion_main!(benches);
