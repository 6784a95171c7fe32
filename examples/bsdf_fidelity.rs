//! Whole-domain fidelity of written `.bsdf` files: each SOURCE is written as `brdftab convert
//! SOURCE out.bsdf` writes it (the default options; a `.bsdf` source is re-encoded into its own
//! parameterization), read back with brdftab's RGL reader (which equals the reference C++ reader
//! to 1e-6) and compared with the source: within 80°, whole hemisphere, grazing band (either
//! direction past 80°; cos θi cos θo-weighted relative RMSE over random pairs and the
//! mirror-centred rule) and the worst directional albedo over θ′ = 1–89° — the figures of the
//! measured tables' bars (issue 22), applied to the file a renderer loads.
//!
//! `cargo run --release --example bsdf_fidelity -- [--pairs N] [--keep DIR] SOURCE...`
//! (`--keep DIR` leaves the written files there; otherwise they go to a temporary directory).
//! Environment: `THETA_I=n` and `RES=n` write n elevations or an n × n table instead of the
//! defaults (`PHI_I=n`: n incident azimuths, `NDF_RES=n`: n × n warps); `AGAINST=SOURCE` judges every written file against that source instead of its own
//! (a table of an RGL file, written as `.bsdf`, against the file); `BINS=1` also prints the
//! relative RMSE of f_r cos θi cos θo per (θi, θo) band (`BINS=phi`: per 30° of φi, of φo − φi
//! and of the half vector's φm, within 80° and in the grazing band), `GRID=1` the incident directions written, `TURN=deg` measures
//! both turned by deg about the normal (the albedo with the light at azimuth deg, the rule's
//! pairs turned with it).

use brdftab::analysis::fidelity::{self, FidelityOptions};
use brdftab::measured::rgl_write;

fn main() -> brdftab::Result<()> {
    let mut pairs = 100_000;
    let mut keep: Option<std::path::PathBuf> = None;
    let mut sources = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--pairs" => {
                pairs = args.next().and_then(|s| s.parse().ok()).unwrap_or_else(|| {
                    eprintln!("error: --pairs takes a whole number");
                    std::process::exit(1)
                })
            }
            "--keep" => keep = args.next().map(Into::into),
            _ => sources.push(a),
        }
    }
    let tmp = std::env::temp_dir().join(format!("bsdf-fidelity-{}", std::process::id()));
    let dir = keep.clone().unwrap_or(tmp.clone());
    std::fs::create_dir_all(&dir).map_err(|e| brdftab::Error::io(&dir, e))?;
    let opts = FidelityOptions {
        pairs,
        ..Default::default()
    };
    println!(
        "| source | bytes | write s | within 80° | whole | grazing | rule 80° / whole / grazing | worst albedo |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for (k, s) in sources.iter().enumerate() {
        let src = brdftab::open(s)?;
        let path = dir.join(format!("{k}.bsdf"));
        let t0 = std::time::Instant::now();
        let mut wopts = rgl_write::Options::default().reuse_source_file(s)?;
        if let Some(n) = std::env::var("THETA_I").ok().and_then(|v| v.parse().ok()) {
            wopts.theta_i = Some(n);
        }
        if let Some(n) = std::env::var("RES").ok().and_then(|v| v.parse().ok()) {
            wopts.resolution = Some(n);
        }
        if let Some(n) = std::env::var("PHI_I").ok().and_then(|v| v.parse().ok()) {
            wopts.phi_i = Some(n);
        }
        if let Some(n) = std::env::var("NDF_RES").ok().and_then(|v| v.parse().ok()) {
            wopts.ndf_resolution = Some(n);
        }
        let w = rgl_write::write(src.as_ref(), &path, &wopts, &brdftab::progress::Silent)?;
        let secs = t0.elapsed().as_secs_f64();
        if std::env::var("GRID").is_ok() {
            let deg = |v: &[f32]| -> Vec<String> {
                v.iter().map(|x| format!("{:.1}", x.to_degrees())).collect()
            };
            eprintln!(
                "{s}: {} φi {:?}, {} θi {:?}, N = {}",
                w.fields.phi_i.len(),
                deg(&w.fields.phi_i),
                w.fields.theta_i.len(),
                deg(&w.fields.theta_i),
                w.fields.n
            );
        }
        let back = brdftab::measured::RglBrdf::open(&path)?;
        match std::env::var("BINS").as_deref() {
            Ok("phi") => phi_bins(&back, src.as_ref()),
            Ok(_) => bins(&back, src.as_ref()),
            Err(_) => {}
        }
        let against = match std::env::var("AGAINST") {
            Ok(a) => brdftab::open(&a)?,
            Err(_) => brdftab::open(s)?,
        };
        let turn = std::env::var("TURN")
            .ok()
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
            .to_radians();
        let f = fidelity::measure(&Turned(&back, turn), &Turned(against.as_ref(), turn), &opts)?;
        let p = f.percents();
        println!(
            "| {s} | {} | {secs:.1} | {:.2} % | {:.2} % | {:.2} % | {:.2} / {:.2} / {:.2} % | {:.2} % at {}° (ch {}, {:.4} vs {:.4}) |",
            w.bytes,
            p[0],
            p[1],
            p[2],
            p[3],
            p[4],
            p[5],
            p[6],
            f.albedo.theta_deg,
            f.albedo.channel,
            f.albedo.approx,
            f.albedo.reference
        );
    }
    if keep.is_none() {
        let _ = std::fs::remove_dir_all(&tmp);
    }
    Ok(())
}

/// A BRDF with both directions turned by an angle about the normal (`TURN`).
struct Turned<'a>(&'a dyn brdftab::Brdf, f64);

impl brdftab::Brdf for Turned<'_> {
    fn channels(&self) -> &brdftab::spectrum::Channels {
        self.0.channels()
    }
    fn eval(&self, wi: glam::DVec3, wo: glam::DVec3, out: &mut [f32]) {
        let (s, c) = self.1.sin_cos();
        let turn = |v: glam::DVec3| glam::DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z);
        self.0.eval(turn(wi), turn(wo), out)
    }
    fn flags(&self) -> brdftab::brdf::Flags {
        self.0.flags()
    }
    fn describe(&self) -> String {
        self.0.describe()
    }
}

fn bins(a: &dyn brdftab::Brdf, r: &dyn brdftab::Brdf) {
    let edges = [0.0, 20.0, 40.0, 60.0, 70.0, 80.0, 85.0, 88.0, 90.0];
    let nb = edges.len() - 1;
    let bin = |t: f64| {
        edges
            .windows(2)
            .position(|w| t >= w[0] && t < w[1])
            .unwrap_or(nb - 1)
    };
    let mut num = vec![0.0f64; nb * nb];
    let mut den = vec![0.0f64; nb * nb];
    let mut st = 0x9E3779B97F4A7C15u64;
    let mut next = move || {
        st ^= st << 13;
        st ^= st >> 7;
        st ^= st << 17;
        (st >> 11) as f64 / (1u64 << 53) as f64
    };
    let c = r.channels().len();
    let (mut fa, mut fr) = (vec![0.0f32; c], vec![0.0f32; c]);
    for _ in 0..400_000 {
        let wi = brdftab::geometry::uniform_hemisphere(glam::DVec2::new(next(), next()));
        let wo = brdftab::geometry::uniform_hemisphere(glam::DVec2::new(next(), next()));
        a.eval(wi, wo, &mut fa);
        r.eval(wi, wo, &mut fr);
        let w = wi.z * wo.z;
        let (bi, bo) = (bin(wi.z.acos().to_degrees()), bin(wo.z.acos().to_degrees()));
        for ch in 0..c {
            num[bi * nb + bo] += ((fa[ch] - fr[ch]) as f64 * w).powi(2);
            den[bi * nb + bo] += (fr[ch] as f64 * w).powi(2);
        }
    }
    print!("θi\\θo");
    for w in edges.windows(2) {
        print!(" {:>7}", format!("{}-{}", w[0], w[1]));
    }
    println!();
    for i in 0..nb {
        print!("{:>5}", format!("{}-{}", edges[i], edges[i + 1]));
        for o in 0..nb {
            print!(
                " {:>6.2}%",
                100.0 * (num[i * nb + o] / den[i * nb + o]).sqrt()
            );
        }
        println!();
    }
}

/// Relative RMSE of f_r cos θi cos θo over random pairs binned by φi, by φo − φi and by the half
/// vector's φm (12 bins of 30° centred on 0°, ±30°, …, 180°), within 80° and in the grazing band.
fn phi_bins(a: &dyn brdftab::Brdf, r: &dyn brdftab::Brdf) {
    const NB: usize = 12;
    let cap = 80f64.to_radians().cos();
    // [which angle][band][bin]
    let mut num = [[[0.0f64; NB]; 2]; 3];
    let mut den = [[[0.0f64; NB]; 2]; 3];
    let mut st = 0x9E3779B97F4A7C15u64;
    let mut next = move || {
        st ^= st << 13;
        st ^= st >> 7;
        st ^= st << 17;
        (st >> 11) as f64 / (1u64 << 53) as f64
    };
    let bin = |phi: f64| {
        let d = phi.to_degrees().rem_euclid(360.0);
        (((d + 15.0) / 30.0).floor() as usize) % NB
    };
    let c = r.channels().len();
    let (mut fa, mut fr) = (vec![0.0f32; c], vec![0.0f32; c]);
    for _ in 0..1_000_000 {
        let wi = brdftab::geometry::uniform_hemisphere(glam::DVec2::new(next(), next()));
        let wo = brdftab::geometry::uniform_hemisphere(glam::DVec2::new(next(), next()));
        a.eval(wi, wo, &mut fa);
        r.eval(wi, wo, &mut fr);
        let w = wi.z * wo.z;
        let band = usize::from(wi.z < cap || wo.z < cap);
        let pi = wi.y.atan2(wi.x);
        let h = wi + wo;
        let bins = [bin(pi), bin(wo.y.atan2(wo.x) - pi), bin(h.y.atan2(h.x))];
        for ch in 0..c {
            let (e, f) = (
                ((fa[ch] - fr[ch]) as f64 * w).powi(2),
                (fr[ch] as f64 * w).powi(2),
            );
            for (k, &b) in bins.iter().enumerate() {
                num[k][band][b] += e;
                den[k][band][b] += f;
            }
        }
    }
    print!("{:>17}", "bin centre (deg)");
    for b in 0..NB {
        print!(" {:>6}", (b as i64 * 30 + 180).rem_euclid(360) - 180);
    }
    println!();
    for (k, name) in ["φi", "φo − φi", "φm"].iter().enumerate() {
        for (band, bname) in ["within 80°", "grazing"].iter().enumerate() {
            print!("{:>17}", format!("{name} {bname}"));
            for b in 0..NB {
                print!(
                    " {:>5.2}%",
                    100.0 * (num[k][band][b] / den[k][band][b]).sqrt()
                );
            }
            println!();
        }
    }
}
