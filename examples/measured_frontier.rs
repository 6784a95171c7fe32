//! Size × error frontier of adaptive halfdiff tables of the RGL measurements (scratch).
use brdftab::analysis::accuracy;
use brdftab::table::adaptive::{AdaptiveOptions, adaptive_grid};
use brdftab::table::symmetry::Symmetry;
use brdftab::table::{BakeOptions, TabulatedBrdf, bake};
use brdftab::{Brdf, measured};

fn main() -> brdftab::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let only = std::env::var("ONLY").unwrap_or_default();
    let sizes: Vec<[usize; 3]> = args
        .iter()
        .map(|a| {
            let v: Vec<usize> = a.split('x').map(|s| s.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let dir = measured::data::rgl_dir().expect("no RGL dir");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "bsdf"))
        .filter(|p| p.to_string_lossy().contains(&only))
        .collect();
    files.sort();
    let sym = Symmetry {
        isotropic: true,
        reciprocal: false,
        bilateral: true,
    };
    for f in &files {
        let src = brdftab::open(f.to_str().unwrap())?;
        for s in &sizes {
            let opts = AdaptiveOptions {
                nodes: *s,
                ..Default::default()
            };
            let grid = adaptive_grid(src.as_ref(), sym, &opts)?;
            let bo = BakeOptions {
                force: true,
                ..Default::default()
            };
            let (t, _) = bake(src.as_ref(), &grid, &bo)?;
            let n = t.values().len();
            let tb = TabulatedBrdf::from_table(t);
            let a = accuracy::compare_weighted(&tb, src.as_ref(), 20000, 1, 80f64.to_radians(), accuracy::Weight::CosInCosOut)?;
            let a2 = accuracy::compare_weighted(&tb, src.as_ref(), std::env::var("PAIRS2").ok().and_then(|s| s.parse().ok()).unwrap_or(20000), 2, 80f64.to_radians(), accuracy::Weight::CosInCosOut)?;
            let tt = brdftab::analysis::timing::lookups(&tb, 300_000, 3)?;
            {
                let wi = glam::DVec3::new(0.3, 0.2, (1.0f64 - 0.13).sqrt());
                let wo = glam::DVec3::new(-0.1, -0.4, (1.0f64 - 0.17).sqrt());
                let mut o = [0f32; 3];
                let t0 = std::time::Instant::now();
                for i in 0..3_000_000 {
                    let w = if i & 1 == 0 { wi } else { wo };
                    tb.eval(std::hint::black_box(w), std::hint::black_box(wo), &mut o);
                    std::hint::black_box(&o);
                }
                println!(
                    "  fixed pair {:.1} ns",
                    t0.elapsed().as_secs_f64() * 1e9 / 3e6
                );
            }
            let ts = if std::env::var("TIME_SRC").is_ok() {
                brdftab::analysis::timing::lookups(src.as_ref(), 300_000, 3)?
                    .cpu_ns_per_lookup_single_thread
            } else {
                f64::NAN
            };
            println!(
                "  table {:.1} ns, batch {:.2} M/s/core; native {:.1} ns",
                tt.cpu_ns_per_lookup_single_thread,
                tt.lookups_per_s_batch_per_core_cpu_time / 1e6,
                ts
            );
            println!(
                "{:28} {:>10} values {:>8} ({:.0} KB f16) err80 {:.3}% / {:.3}%  max {:.1}%",
                f.file_stem().unwrap().to_string_lossy(),
                format!("{}x{}x{}", s[0], s[1], s[2]),
                n,
                n as f64 * 2.0 / 1024.0,
                a.rel_rmse * 100.0,
                a2.rel_rmse * 100.0,
                a.max_rel * 100.0
            );
        }
    }
    Ok(())
}
