//! Whole-domain figures of model specs' default tables (the analytic side of issue 22's
//! metrics): within 80°, whole hemisphere, grazing band (random pairs and the product rule) and
//! the worst directional albedo over θ′ = 1–89°, each table against its source, with the stored
//! quantity and the table's bytes.
//!
//! `cargo run --release --example model_fidelity -- [--quantity fr|fr_cos_cos] [--target E] SPEC...`
//! (`--quantity` bakes that quantity instead of the default; `--target E` the smallest adaptive
//! table within error E, calibrated, instead of the default preset; `--pairs N` random pairs.)

use brdftab::analysis::fidelity::{self, FidelityOptions};
use brdftab::bake::BakeRequest;
use brdftab::table::Quantity;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut quantity = None;
    let mut pairs = 100_000;
    let mut target: Option<f64> = None;
    let mut specs = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--quantity" => {
                let q = args.next().unwrap_or_default();
                quantity = Some(Quantity::from_name(&q).ok_or(format!("unknown quantity {q}"))?);
            }
            "--pairs" => pairs = args.next().and_then(|s| s.parse().ok()).unwrap_or(pairs),
            "--target" => target = args.next().and_then(|s| s.parse().ok()),
            _ => specs.push(a),
        }
    }
    let opts = FidelityOptions {
        pairs,
        ..Default::default()
    };
    println!(
        "| source | stores | grid | MB | within 80° | whole | grazing | rule 80° / whole / grazing | worst albedo |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for s in &specs {
        let mut req = BakeRequest::new(s.as_str());
        if let Some(q) = quantity {
            req = req.quantity(q);
        }
        if let Some(e) = target {
            req = req.target_error(e);
        }
        let src = req.open_source()?;
        let (table, _) = req.table(&brdftab::progress::Silent)?;
        let mb = table.values().len() as f64 * 4e-6;
        let grid = table.grid().summary();
        let stores = table.grid().quantity().name();
        let tab = brdftab::table::TabulatedBrdf::from_table(table);
        let f = fidelity::measure(&tab, src.as_ref(), &opts)?;
        let p = f.percents();
        println!(
            "| {} | {stores} | {} | {mb:.1} | {:.2} % | {:.2} % | {:.2} % | {:.2} / {:.2} / {:.2} % | {:.2} % at {}° |",
            src.describe(),
            grid.split(',').next().unwrap_or(&grid),
            p[0],
            p[1],
            p[2],
            p[3],
            p[4],
            p[5],
            p[6],
            f.albedo.theta_deg
        );
    }
    Ok(())
}
