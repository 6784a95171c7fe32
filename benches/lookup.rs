//! Table lookup throughput: linear and nearest RGB lookups on a MERL-size halfdiff table
//! (90 × 1 × 90 × 180 × 3, isotropic + reciprocal), random pairs uniform on the hemisphere.
//!
//! - `lookup/{linear,nearest}_single`: one thread, 4096 pairs per iteration (time / 4096 = ns per
//!   lookup);
//! - `lookup/linear_batch`: `eval_batch` on 2^20 pairs, rayon on all cores;
//! - `lookup/measured_{single,block}`: the default table of the shipped `cc_ibiza_sunset`
//!   (an adaptive kernel table, cache resident) on one thread, one `eval` per pair against
//!   `eval_batch` on the same 4096 pairs (below the parallel threshold, so one thread: the
//!   eight-lane AVX2 path against the one-pair path, in the same run);
//! - `lookup/measured_{single,block}_f32`: the same pairs rounded to f32 and normalized there,
//!   as pbrt-v4, Mitsuba 3 and float32 arrays hand them over (before session 35 these took the
//!   normalizing path: 1.8× one `eval`, 5–6× a batch).
//!
//! Run: `cargo bench --bench lookup`. The machine may be shared: compare with CPU time
//! (`brdftab bench FILE` prints both).

use std::hint::black_box;

use brdftab::geometry::uniform_hemisphere;
use brdftab::table::{Grid, Interp, Table, TabulatedBrdf};
use brdftab::testkit::Pcg32;
use brdftab::{Brdf, Channels};
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

fn table() -> TabulatedBrdf {
    let t = Table::from_fn(Grid::merl(Channels::Rgb), "synthetic", |idx, ang, out| {
        let v = (0.1 + (-ang[0] * 20.0).exp() + 0.01 * idx[3] as f64) as f32;
        out.copy_from_slice(&[v, 0.5 * v, 0.25 * v]);
    });
    TabulatedBrdf::from_table(t)
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("lookup");
    g.sample_size(20)
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(3));
    let (wi, wo) = pairs(4096);
    for interp in [Interp::Linear, Interp::Nearest] {
        let t = table().with_interp(interp);
        g.throughput(Throughput::Elements(wi.len() as u64));
        g.bench_function(format!("{interp:?}_single").to_lowercase(), |b| {
            let mut f = [0.0f32; 3];
            b.iter(|| {
                for k in 0..wi.len() {
                    t.eval(wi[k], wo[k], &mut f);
                    black_box(&f);
                }
            })
        });
    }
    let path = brdftab::measured::data::rgl_file("cc_ibiza_sunset_rgb.bsdf")
        .unwrap_or_else(|e| panic!("{e}"));
    let (measured, _) = brdftab::bake::BakeRequest::new(path.display().to_string().as_str())
        .table(&brdftab::progress::Silent)
        .unwrap_or_else(|e| panic!("{e}"));
    let measured = TabulatedBrdf::from_table(measured);
    g.throughput(Throughput::Elements(wi.len() as u64));
    g.bench_function("measured_single", |b| {
        let mut f = [0.0f32; 3];
        b.iter(|| {
            for k in 0..wi.len() {
                measured.eval(wi[k], wo[k], &mut f);
                black_box(&f);
            }
        })
    });
    let mut block = vec![0.0f32; wi.len() * 3];
    g.bench_function("measured_block", |b| {
        b.iter(|| {
            measured.eval_batch(&wi, &wo, &mut block);
            black_box(&block);
        })
    });
    // The same pairs as renderers hand them over: rounded to f32 and normalized there.
    let f32_dirs = |w: &[DVec3]| -> Vec<DVec3> {
        w.iter()
            .map(|d| d.as_vec3().normalize().as_dvec3())
            .collect()
    };
    let (fi, fo) = (f32_dirs(&wi), f32_dirs(&wo));
    g.bench_function("measured_single_f32", |b| {
        let mut f = [0.0f32; 3];
        b.iter(|| {
            for k in 0..fi.len() {
                measured.eval(fi[k], fo[k], &mut f);
                black_box(&f);
            }
        })
    });
    g.bench_function("measured_block_f32", |b| {
        b.iter(|| {
            measured.eval_batch(&fi, &fo, &mut block);
            black_box(&block);
        })
    });
    let (bi, bo) = pairs(1 << 20);
    let t = table();
    let mut out = vec![0.0f32; bi.len() * 3];
    g.throughput(Throughput::Elements(bi.len() as u64));
    g.bench_function("linear_batch", |b| {
        b.iter(|| {
            t.eval_batch(&bi, &bo, &mut out);
            black_box(&out);
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
