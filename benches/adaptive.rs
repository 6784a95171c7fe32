//! Measured materials: the native RGL evaluation against the default (adaptive) table of the
//! same file, one thread, 4096 random pairs per iteration (time / 4096 = ns per lookup), in the
//! same run. `brdftab bench --measured` prints the whole comparison (error, bytes, memory,
//! paired timings, batch rates) for every shipped file.
//!
//! Run: `cargo bench --bench adaptive`.

use std::hint::black_box;

use brdftab::Brdf;
use brdftab::bake::BakeRequest;
use brdftab::geometry::uniform_hemisphere;
use brdftab::progress::Silent;
use brdftab::table::TabulatedBrdf;
use brdftab::testkit::Pcg32;
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;

fn pairs(n: usize) -> (Vec<DVec3>, Vec<DVec3>) {
    let mut rng = Pcg32::new(42);
    (0..n)
        .map(|_| {
            (
                uniform_hemisphere(rng.next_dvec2()),
                uniform_hemisphere(rng.next_dvec2()),
            )
        })
        .unzip()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("adaptive");
    g.sample_size(20)
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(3));
    let (wi, wo) = pairs(4096);
    g.throughput(Throughput::Elements(wi.len() as u64));
    for name in ["paper_white_rgb.bsdf", "cg_sunflower_rgb.bsdf"] {
        let file = brdftab::measured::data::rgl_file(name).unwrap_or_else(|e| panic!("{e}"));
        let file = file.to_string_lossy().into_owned();
        let native = brdftab::open(&file).unwrap();
        let (table, _) = BakeRequest::new(file.as_str()).table(&Silent).unwrap();
        let table = TabulatedBrdf::from_table(table);
        let stem = name.trim_end_matches("_rgb.bsdf");
        for (what, b) in [("native", native.as_ref() as &dyn Brdf), ("table", &table)] {
            g.bench_function(format!("{stem}/{what}"), |bn| {
                let mut f = [0.0f32; 3];
                bn.iter(|| {
                    for k in 0..wi.len() {
                        b.eval(wi[k], wo[k], &mut f);
                        black_box(&f);
                    }
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
