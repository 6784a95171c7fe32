//! Bake throughput: Cook-Torrance (m = 0.3, conductor n = 0.2, k = 3) with 10 wavelengths on the
//! medium halfdiff grid (90 × 1 × 90 × 91 × 10 = 7.4 M stored values), rayon on all cores.
//! Throughput is in stored values per second.
//!
//! Run: `cargo bench --bench bake`.

use std::hint::black_box;

use brdftab::table::presets::Preset;
use brdftab::table::{BakeOptions, Symmetry, bake_chunks};
use brdftab::{Channels, ModelSpec};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};

fn bench(c: &mut Criterion) {
    let ch = Channels::linspace(400.0, 700.0, 10).expect("valid wavelengths");
    let model =
        ModelSpec::parse(r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"n": 0.2, "k": 3}}"#)
            .and_then(|s| s.build(&ch))
            .expect("cook_torrance builds");
    let grid = Preset::Medium
        .grid(None, Symmetry::ALL, ch)
        .expect("medium grid");
    let mut g = c.benchmark_group("bake");
    g.sample_size(10)
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(5));
    g.throughput(Throughput::Elements(grid.stored_values() as u64));
    // Includes the symmetry verification (3 × 20 000 pairs) a real bake runs first.
    g.bench_function("cook_torrance_10wl_medium", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            bake_chunks(model.as_ref(), &grid, &BakeOptions::default(), |_, v| {
                sum += v[0];
                Ok(())
            })
            .expect("bake");
            black_box(sum)
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
