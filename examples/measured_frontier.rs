//! Size × error frontier of adaptive tables of the RGL measurements: for each shipped `.bsdf`
//! file and each node count θh×θd×φd, bake an adaptive grid in memory (f32, no codec) and
//! report the stored values and the error against the native evaluation (relative RMSE of
//! f_r cos θi cos θo, both directions within 80°, 20 000 pairs, seeds 1 and 2).
//!
//! `cargo run --release --example measured_frontier -- 64x48x25 128x48x25`
//! (`ONLY=sunflower` restricts the files; `PAIRS2=400000` takes the second estimate on more
//! pairs).

use brdftab::analysis::accuracy::{Weight, compare_weighted};
use brdftab::table::adaptive::{AdaptiveOptions, adaptive_grid};
use brdftab::table::symmetry::Symmetry;
use brdftab::table::{BakeOptions, TabulatedBrdf, bake};

fn main() -> brdftab::Result<()> {
    let only = std::env::var("ONLY").unwrap_or_default();
    let pairs2: usize = std::env::var("PAIRS2")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_000);
    let mut sizes = Vec::new();
    for a in std::env::args().skip(1) {
        let v: Vec<usize> = a.split('x').filter_map(|s| s.parse().ok()).collect();
        let s: [usize; 3] = v
            .try_into()
            .map_err(|_| brdftab::Error::arg("SIZES", format!("`{a}`: expected NHxNDxNP")))?;
        sizes.push(s);
    }
    if sizes.is_empty() {
        sizes.push(brdftab::table::adaptive::DEFAULT_NODES);
    }
    let dir = brdftab::measured::data::rgl_dir()
        .ok_or_else(|| brdftab::Error::NotFound("no RGL directory".into()))?;
    let files = brdftab::measured::data::rgl_files(&dir)?;
    let sym = Symmetry {
        isotropic: true,
        reciprocal: false,
        bilateral: true,
    };
    let cap = 80f64.to_radians();
    for f in files.iter().filter(|f| f.to_string_lossy().contains(&only)) {
        let src = brdftab::open(f)?;
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
            let w = Weight::CosInCosOut;
            let a = compare_weighted(&tb, src.as_ref(), 20_000, 1, cap, w)?;
            let b = compare_weighted(&tb, src.as_ref(), pairs2, 2, cap, w)?;
            println!(
                "{:28} {:>10} values {n:>8} error {:.3}% / {:.3}% ({pairs2} pairs)",
                f.file_stem().unwrap_or_default().to_string_lossy(),
                format!("{}x{}x{}", s[0], s[1], s[2]),
                a.rel_rmse * 100.0,
                b.rel_rmse * 100.0,
            );
        }
    }
    Ok(())
}
