//! The four fidelity figures of default bakes (issue #22): within 80°, whole hemisphere,
//! grazing band (cos θi cos θo-weighted relative RMSE on 100 000 pairs) and the worst
//! directional albedo error over θ′ = 1–89°, each table against the source it was baked from.
//!
//! `cargo run --release --example measured_fidelity -- data/rgl/*.bsdf` (set `GRID` to a
//! `--grid` value to bake another grid than the default). With `--merl` first, the same figures
//! for the MERL file each source converts to (`brdftab convert SOURCE out.binary`: cell means,
//! looked up by cell as the MERL reader does) instead of its default table.

use brdftab::analysis::fidelity::{FidelityOptions, measure};
use brdftab::bake::BakeRequest;
use brdftab::table::TabulatedBrdf;
fn main() -> brdftab::Result<()> {
    let mut files: Vec<String> = std::env::args().skip(1).collect();
    let merl = files.first().is_some_and(|a| a == "--merl");
    if merl {
        files.remove(0);
    }
    for f in files {
        if merl {
            let src = brdftab::source::open(&f)?;
            let t0 = std::time::Instant::now();
            let m = brdftab::measured::MerlBrdf::from_brdf(src.as_ref());
            let secs = t0.elapsed().as_secs_f64();
            let opts = FidelityOptions {
                pairs: 100_000,
                ..Default::default()
            };
            let fi = measure(&m, src.as_ref(), &opts)?;
            println!(
                "{f}: MERL file written in {secs:.1}s\n   {}  a={:.4} ref={:.4}",
                fi.summary(),
                fi.albedo.approx,
                fi.albedo.reference
            );
            continue;
        }
        let mut req = BakeRequest::new(f.as_str());
        if let Ok(g) = std::env::var("GRID") {
            req = req.grid(g.parse::<brdftab::bake::GridChoice>()?);
        }
        if std::env::var("COSCOS").is_ok() {
            req = req.quantity(brdftab::table::Quantity::FrCosCos);
        }
        let src = req.open_source()?;
        let t0 = std::time::Instant::now();
        let (t, rep) = req.table_of(src.as_ref(), &brdftab::progress::Silent)?;
        let bake_s = t0.elapsed().as_secs_f64();
        let vals = t.grid().stored_values();
        let tb = TabulatedBrdf::from_table(t);
        let fi = measure(
            &tb,
            src.as_ref(),
            &FidelityOptions {
                pairs: 100_000,
                ..Default::default()
            },
        )?;
        println!(
            "{f}: {} values {vals} bake {bake_s:.1}s\n   {}  a={:.4} ref={:.4}",
            rep.grid.summary(),
            fi.summary(),
            fi.albedo.approx,
            fi.albedo.reference
        );
    }
    Ok(())
}
