//! Scratch: where a kernel lookup's time goes.
use brdftab::Brdf;
use brdftab::table::kernel::Kernel;
use glam::DVec3;
use std::hint::black_box;
use std::time::Instant;

fn main() -> brdftab::Result<()> {
    let path = std::env::args().nth(1).unwrap();
    let t = brdftab::open(&path)?;
    let table = brdftab::source::open_table(&path, &Default::default())?.to_table()?;
    let k = Kernel::new(table.grid()).unwrap();
    let values = table.values();
    let n: usize = std::env::var("N")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1 << 20);
    let mut rng = brdftab::rng::Pcg32::new(5);
    let pairs: Vec<(DVec3, DVec3)> = (0..n)
        .map(|_| {
            (
                brdftab::geometry::uniform_hemisphere(rng.next_dvec2()),
                brdftab::geometry::uniform_hemisphere(rng.next_dvec2()),
            )
        })
        .collect();
    let mut out = vec![0f32; 3 * n];
    for round in 0..3 {
        let t0 = Instant::now();
        let mut acc = 0f32;
        for (wi, wo) in &pairs {
            let v = k.vars(*wi, *wo).unwrap_or([0.0; 3]);
            acc += v[0] + v[1] + v[2];
        }
        black_box(acc);
        let a = t0.elapsed().as_secs_f64() * 1e9 / n as f64;
        let t0 = Instant::now();
        for (i, (wi, wo)) in pairs.iter().enumerate() {
            k.eval(*wi, *wo, &mut out[3 * i..3 * i + 3], values);
        }
        black_box(&out);
        let b = t0.elapsed().as_secs_f64() * 1e9 / n as f64;
        let t0 = Instant::now();
        for (i, (wi, wo)) in pairs.iter().enumerate() {
            t.eval(*wi, *wo, &mut out[3 * i..3 * i + 3]);
        }
        black_box(&out);
        let c = t0.elapsed().as_secs_f64() * 1e9 / n as f64;
        let (wi, wo) = pairs[7];
        let t0 = Instant::now();
        for _ in 0..n {
            k.eval(black_box(wi), black_box(wo), &mut out[0..3], values);
            black_box(&out[0]);
        }
        let d = t0.elapsed().as_secs_f64() * 1e9 / n as f64;
        let native = brdftab::open(&std::env::args().nth(2).unwrap())?;
        let t0 = Instant::now();
        for (i, (wi, wo)) in pairs.iter().enumerate().take(n / 4) {
            native.eval(*wi, *wo, &mut out[3 * i..3 * i + 3]);
        }
        black_box(&out);
        let e = t0.elapsed().as_secs_f64() * 1e9 / (n / 4) as f64;
        println!("round {round}: native {e:.1} ns ratio {:.2}", e / c);
        println!(
            "round {round}: vars {a:.1} ns, kernel {b:.1} ns, dyn Brdf {c:.1} ns, fixed pair {d:.1} ns"
        );
    }
    Ok(())
}
