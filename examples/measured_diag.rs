//! Scratch: the pairs that dominate a measured table's error.
use brdftab::Brdf;
use brdftab::geometry;
use brdftab::rng::Pcg32;

fn main() -> brdftab::Result<()> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let native = brdftab::open(&a[0])?;
    let table = brdftab::open(&a[1])?;
    let seed: u64 = a.get(2).map(|s| s.parse().unwrap()).unwrap_or(1);
    let span = 1.0 - 80f64.to_radians().cos();
    let cap = |u: glam::DVec2| geometry::uniform_hemisphere(glam::DVec2::new((1.0 - span) + span * u.x, u.y));
    let mut rows = vec![];
    let (mut e2, mut r2) = (0.0, 0.0);
    for b in 0..(20000usize).div_ceil(1024) {
        let mut rng = Pcg32::with_stream(seed, b as u64);
        for _ in 0..1024.min(20000 - b * 1024) {
            let wi = cap(rng.next_dvec2());
            let wo = cap(rng.next_dvec2());
            let (mut fa, mut fr) = ([0f32; 3], [0f32; 3]);
            table.eval(wi, wo, &mut fa);
            native.eval(wi, wo, &mut fr);
            let w = wi.z * wo.z;
            let mut e = 0.0;
            for k in 0..3 {
                e += ((fa[k] - fr[k]) as f64 * w).powi(2);
                r2 += (fr[k] as f64 * w).powi(2);
            }
            e2 += e;
            let hd = geometry::to_half_diff(wi, wo).unwrap();
            rows.push((e, hd.theta_h.to_degrees(), hd.theta_d.to_degrees(), hd.phi_d.to_degrees(), fa[0], fr[0]));
        }
    }
    rows.sort_by(|x, y| y.0.total_cmp(&x.0));
    let t = brdftab::source::open_table(&a[1], &Default::default())?;
    let ax = &t.grid().stored_axes()[0];
    let n: Vec<String> = (0..ax.size.min(40)).map(|i| format!("{:.3}", ax.node(i).to_degrees())).collect();
    println!("θh nodes: {}", n.join(" "));
    let ax = &t.grid().stored_axes()[2];
    let n: Vec<String> = (0..ax.size).map(|i| format!("{:.1}", ax.node(i).to_degrees())).collect();
    println!("θd nodes: {}", n.join(" "));
    println!("rel rmse {:.3}%", (e2 / r2).sqrt() * 100.0);
    for r in rows.iter().take(8) {
        println!("share {:.3} θh {:.3} θd {:.2} φd {:.1}: table {:.4} native {:.4}", r.0 / e2, r.1, r.2, r.3, r.4, r.5);
    }
    Ok(())
}
#[allow(dead_code)]
fn nodes() {}
