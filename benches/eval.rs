//! Nanoseconds per `eval` for every model in `brdftab::spec::MODELS` (its example spec), RGB,
//! single thread. Models whose build fails (not implemented yet) are skipped, so new models show
//! up here as soon as they are wired into `models::build`.
//!
//! Each iteration evaluates one pair from a fixed pool of 1024 random pairs above the horizon
//! (cycled), so branch predictors and caches see realistic variety.
//!
//! Time is the benchmark thread's **CPU time** (`CLOCK_THREAD_CPUTIME_ID`), not wall time: the
//! machines this runs on are shared, and wall time there mostly measures the scheduler.
//!
//! Run: `cargo bench --bench eval -- --warm-up-time 1 --measurement-time 2`

use std::hint::black_box;

use brdftab::Channels;
use brdftab::geometry;
use brdftab::spec::{MODELS, ModelSpec};
use brdftab::testkit::Pcg32;
use criterion::measurement::WallTime;
use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;

mod common;
use common::ThreadCpuTime;

fn pairs() -> Vec<(DVec3, DVec3)> {
    let mut rng = Pcg32::new(2024);
    (0..1024)
        .map(|_| {
            let wi = geometry::uniform_hemisphere(rng.next_dvec2());
            // Half of the pairs near the mirror direction, where specular lobes are non-zero.
            let wo = if rng.next_f64() < 0.5 {
                geometry::uniform_hemisphere(rng.next_dvec2())
            } else {
                let r = geometry::reflect_z(wi) + 0.2 * (rng.next_dvec2().extend(0.0) - 0.5);
                geometry::normalize(DVec3::new(r.x, r.y, r.z.abs() + 1e-3)).unwrap_or(DVec3::Z)
            };
            (wi, wo)
        })
        .collect()
}

fn bench_eval(c: &mut Criterion<ThreadCpuTime>) {
    let pairs = pairs();
    let mut group = c.benchmark_group("eval_rgb");
    for info in MODELS {
        let Ok(spec) = ModelSpec::parse(info.example) else {
            continue;
        };
        let Ok(brdf) = spec.build(&Channels::Rgb) else {
            continue;
        };
        group.bench_function(info.name, |b| {
            let mut out = [0.0f32; 3];
            let mut i = 0usize;
            b.iter(|| {
                let (wi, wo) = pairs[i & 1023];
                i = i.wrapping_add(1);
                brdf.eval(black_box(wi), black_box(wo), &mut out);
                black_box(out[0])
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().with_measurement(ThreadCpuTime(WallTime));
    targets = bench_eval
}
criterion_main!(benches);
