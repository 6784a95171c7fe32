//! Where does a table's error come from? Compares θd mappings / premultiplication for one model
//! and bins the cosine-weighted squared error by θh (rows) and θd (columns), 10° bins.
//!
//! `cargo run --release --example table_diag -- SPEC [u|c] [n_theta_d]` (θd uniform or uniform in cos)
use brdftab::analysis::accuracy;
use brdftab::table::{BakeOptions, Grid, Mapping, Param, TabulatedBrdf, bake, symmetry};
use brdftab::{Brdf, Channels, ModelSpec, geometry, testkit::Pcg32};

fn main() -> brdftab::Result<()> {
    let Some(spec) = std::env::args().nth(1) else {
        return Err(brdftab::Error::arg(
            "SPEC",
            "usage: table_diag SPEC [u|c] [n_theta_d]",
        ));
    };
    let mode = std::env::args().nth(2).unwrap_or("u".into());
    let ntd: usize = std::env::args()
        .nth(3)
        .and_then(|s| s.parse().ok())
        .unwrap_or(90);
    let model = ModelSpec::parse(&spec)?.build(&Channels::Rgb)?;
    let sym = symmetry::detect(model.as_ref(), 1e-3);
    let m = match mode.as_str() {
        "c" => Mapping::Cos,
        _ => Mapping::Uniform,
    };
    let grid = Grid::with_sizes(
        Param::HalfDiff,
        [90, 360, ntd, 360],
        [Mapping::Sqrt, m],
        Channels::Rgb,
        sym,
    )?;
    let (t, _) = bake(model.as_ref(), &grid, &BakeOptions::default())?;
    let tb = TabulatedBrdf::from_table(t);
    let nb = 9;
    let mut e = vec![0.0f64; nb * nb];
    let mut tot = 0.0;
    let mut rng = Pcg32::new(1);
    let (mut a, mut b) = ([0f32; 3], [0f32; 3]);
    for _ in 0..200_000 {
        let wi = geometry::uniform_hemisphere(rng.next_dvec2());
        let wo = geometry::uniform_hemisphere(rng.next_dvec2());
        tb.eval(wi, wo, &mut a);
        model.eval(wi, wo, &mut b);
        let Some(hd) = geometry::to_half_diff(wi, wo) else {
            continue;
        };
        let i = ((hd.theta_h / std::f64::consts::FRAC_PI_2 * nb as f64) as usize).min(nb - 1);
        let o = ((hd.theta_d / std::f64::consts::FRAC_PI_2 * nb as f64) as usize).min(nb - 1);
        for k in 0..3 {
            e[i * nb + o] += ((a[k] - b[k]) as f64 * wi.z).powi(2);
            tot += (b[k] as f64 * wi.z).powi(2);
        }
    }
    println!(
        "{}\nshare of squared error (%), rows θh, columns θd (10° bins)",
        grid.summary()
    );
    for i in 0..nb {
        let row: Vec<String> = (0..nb)
            .map(|o| format!("{:6.2}", 100.0 * e[i * nb + o] / e.iter().sum::<f64>()))
            .collect();
        println!("{}", row.join(" "));
    }
    let mut r: Vec<f64> = (0..7)
        .map(|s| {
            accuracy::compare(&tb, model.as_ref(), 100_000, 12345 + s).map(|a| a.rel_rmse * 100.0)
        })
        .collect::<brdftab::Result<_>>()?;
    r.sort_by(f64::total_cmp);
    println!(
        "rel rmse {:.4}% (200k, seed 1); 7 seeds x 1e5: {:?}",
        100.0 * (e.iter().sum::<f64>() / tot).sqrt(),
        r.iter().map(|x| format!("{x:.3}")).collect::<Vec<_>>()
    );
    Ok(())
}
