//! The MERL-size analytic table against a MERL-style nearest lookup in C, in the same run
//! (issue: measured data in dense tables, "the MERL-size analytic table").
//!
//! Bakes Cook-Torrance (m 0.3, Fresnel n 0.2 k 3) on `--param halfdiff --grid 90x1x90x180`
//! as `brdftab bake` does, writes the same model as a MERL `.binary` file, compiles
//! `benches/c/merl_nearest.c` with `gcc -O2` (or `$CC`), and then in each round times the C
//! lookup (its own process, 10^6 random pairs) and the table (10^6 random pairs, one thread,
//! linear and nearest, and the same model on the adaptive grid `--target-error 0.5%` picks)
//! back to back. Prints per round and the medians of the paired ratios.
//!
//! `cargo run --release --example merl_c_compare [ROUNDS]`

use std::process::Command;
use std::time::Instant;

use brdftab::bake::{BakeRequest, GridChoice};
use brdftab::measured::MerlBrdf;
use brdftab::table::{Interp, Param, TabulatedBrdf};
use brdftab::{Brdf, Error, Result};
use glam::DVec3;

const SPEC: &str = r#"{"model":"cook_torrance","m":0.3,"fresnel":{"n":0.2,"k":3}}"#;

fn io(e: std::io::Error) -> Error {
    Error::Unsupported(e.to_string())
}

fn main() -> Result<()> {
    let rounds: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let dir = brdftab::testkit::TempDir::new("merl-c");
    let (table, _) = BakeRequest::new(SPEC)
        .grid(GridChoice::Sizes([90, 1, 90, 180]))
        .param(Param::HalfDiff)
        .table(&brdftab::progress::Silent)?;
    println!("table: {}", table.grid().summary());
    let linear = TabulatedBrdf::from_table(table);
    // The same model on the adaptive grid an error target of 0.5 % picks (for comparison).
    let (adaptive, r) = BakeRequest::new(SPEC)
        .target_error(0.005)
        .table(&brdftab::progress::Silent)?;
    println!(
        "adaptive: {} ({})",
        adaptive.grid().summary(),
        r.target.map(|t| t.summary()).unwrap_or_default()
    );
    let adaptive = TabulatedBrdf::from_table(adaptive);
    let nearest = TabulatedBrdf::from_table(linear.to_table()?).with_interp(Interp::Nearest);
    let merl = dir.join("ct.binary");
    MerlBrdf::from_brdf(brdftab::open(SPEC)?.as_ref()).write(&merl)?;
    let exe = dir.join("merl_nearest");
    let src = concat!(env!("CARGO_MANIFEST_DIR"), "/benches/c/merl_nearest.c");
    let cc = std::env::var("CC").unwrap_or_else(|_| "gcc".into());
    let st = Command::new(&cc)
        .args(["-O2", "-o"])
        .arg(&exe)
        .arg(src)
        .arg("-lm")
        .status()
        .map_err(io)?;
    if !st.success() {
        return Err(Error::Unsupported(format!("{cc} could not build {src}")));
    }
    let pairs = 1_000_000;
    let mut rng = brdftab::testkit::Pcg32::new(2024);
    let p: Vec<(DVec3, DVec3)> = (0..pairs)
        .map(|_| {
            (
                brdftab::geometry::uniform_hemisphere(rng.next_dvec2()),
                brdftab::geometry::uniform_hemisphere(rng.next_dvec2()),
            )
        })
        .collect();
    let mut out = vec![0f32; 3 * pairs];
    let mut time = |t: &TabulatedBrdf| {
        let s = Instant::now();
        for ((wi, wo), o) in p.iter().zip(out.chunks_exact_mut(3)) {
            t.eval(*wi, *wo, o);
        }
        std::hint::black_box(&out);
        s.elapsed().as_secs_f64() * 1e9 / pairs as f64
    };
    let c_lookup = || -> Result<f64> {
        let o = Command::new(&exe)
            .arg(&merl)
            .arg(pairs.to_string())
            .output()
            .map_err(io)?;
        let s = String::from_utf8_lossy(&o.stdout).into_owned();
        s.split_whitespace()
            .next()
            .and_then(|x| x.parse().ok())
            .ok_or_else(|| Error::Unsupported(format!("merl_nearest printed `{s}`")))
    };
    time(&linear);
    let (mut rl, mut rn, mut ra) = (Vec::new(), Vec::new(), Vec::new());
    for r in 0..rounds {
        let c = c_lookup()?;
        let l = time(&linear);
        let n = time(&nearest);
        let a = time(&adaptive);
        println!(
            "round {r}: C nearest {c:.1} ns, table linear {l:.1} ns ({:.2}x), nearest {n:.1} ns \
             ({:.2}x), adaptive {a:.1} ns ({:.2}x)",
            c / l,
            c / n,
            c / a
        );
        rl.push(c / l);
        rn.push(c / n);
        ra.push(c / a);
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(|a, b| a.total_cmp(b));
        v[v.len() / 2]
    };
    println!(
        "median ratio C / table: linear {:.2}x, nearest {:.2}x, adaptive {:.2}x",
        med(&mut rl),
        med(&mut rn),
        med(&mut ra)
    );
    Ok(())
}
