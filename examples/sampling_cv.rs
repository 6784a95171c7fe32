//! The coefficient of variation of sample weights w = f_r cos θi / pdf (issue #24): for each
//! SOURCE, natively (RGL files: the native reader) and as the default table that
//! `brdftab bake SOURCE` makes, at views θo = 3, 15, 30, 45, 60, 75, 85°. Each figure is the
//! largest CV over four view azimuths (0.3, 1.9, 3.4, 5.0 rad), 40 000 samples each; a draw
//! without a direction counts as weight 0. The last column is the cost of one `sample`
//! (direction, pdf and weight) against one `eval`, single thread, on random views.
//!
//! `cargo run --release --example sampling_cv -- data/rgl/*.bsdf`
//! (`--samples N` per view; `--native-only`, `--table-only`; `--wrap` samples a native source with
//! the table sampler built from it; `--res NH,NP,NT[,FLOOR]` sets the
//! table sampler's θh, φh and θo nodes (and floor); SOURCE may be a model spec, e.g.
//! `'{"model": "ggx", "alpha": 0.1, "fresnel": {"conductor": "Cu"}}'`; `--grid G` bakes on grid
//! G instead of the default, e.g. `medium`; `--quantity fr|fr_cos_cos|fr_cos_out` bakes that
//! stored quantity instead of the default; `--midway` prints instead, per source, the sampler's
//! resolution (`TableSampler::for_source`, or `--res`) and the worst CV predicted from its
//! density (`TableSampler::predicted_cv`) at the views midway between its conditioning views,
//! over 3–75° and 75–85° (and 85° itself), where a drawn figure at fixed views may miss it.)

use std::time::Instant;

use brdftab::Brdf;
use brdftab::analysis::weights::weight_stats;
use brdftab::bake::{BakeRequest, BakeTarget, GridChoice};
use brdftab::geometry;
use brdftab::source;
use brdftab::table::{Quantity, SamplingResolution, TableSampler};

/// A source sampled by a [`TableSampler`] built from it (`--wrap`): the sampler's quality
/// separated from a table's.
struct Wrapped {
    inner: Box<dyn Brdf + Send + Sync>,
    sampler: TableSampler,
}

impl Brdf for Wrapped {
    fn channels(&self) -> &brdftab::Channels {
        self.inner.channels()
    }
    fn eval(&self, wi: glam::DVec3, wo: glam::DVec3, out: &mut [f32]) {
        self.inner.eval(wi, wo, out)
    }
    fn flags(&self) -> brdftab::brdf::Flags {
        self.inner.flags()
    }
    fn describe(&self) -> String {
        self.inner.describe()
    }
    fn sample(
        &self,
        wo: glam::DVec3,
        u: glam::DVec2,
        w: &mut [f32],
    ) -> Option<brdftab::brdf::BrdfSample> {
        self.sampler.sample(self, wo, u, w)
    }
    fn pdf(&self, wi: glam::DVec3, wo: glam::DVec3) -> f64 {
        self.sampler.pdf(wi, wo)
    }
}

const VIEWS: [f64; 7] = [3.0, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0];
const PHIS: [f64; 4] = [0.3, 1.9, 3.4, 5.0];

fn row(label: &str, b: &dyn Brdf, samples: usize) {
    let t = Instant::now();
    // Build any lazy structure before timing the rows.
    let _ = b.pdf(glam::DVec3::Z, glam::DVec3::Z);
    let build = t.elapsed().as_secs_f64();
    let mut cells = Vec::new();
    let mut worst_max = 0.0f64;
    let mut worst_refused = 0.0f64;
    for &v in &VIEWS {
        let mut cv = 0.0f64;
        for (k, &phi) in PHIS.iter().enumerate() {
            let wo = geometry::spherical(v.to_radians(), phi);
            let s = weight_stats(b, wo, samples, 1000 + k as u64);
            cv = if s.cv.is_nan() {
                f64::NAN
            } else {
                cv.max(s.cv)
            };
            worst_max = worst_max.max(s.max_over_mean);
            worst_refused = worst_refused.max(s.refused);
        }
        cells.push(format!("{cv:6.3}"));
    }
    // Cost: one sample (direction, pdf, weight) against one evaluation, on the same views and
    // uniforms, single thread, wall time (best of three runs of 200 000 each).
    // A splitmix64 stream (the crate's generator is private).
    let mut state = 5u64;
    let mut next = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut pair = move || glam::DVec2::new(next(), next());
    let n = 200_000;
    let pairs: Vec<(glam::DVec3, glam::DVec2, glam::DVec3)> = (0..n)
        .map(|_| {
            let wo = geometry::uniform_hemisphere(pair());
            let u = pair();
            let wi = geometry::uniform_hemisphere(pair());
            (wo, u, wi)
        })
        .collect();
    let mut w = [0.0f32; 64];
    let c = b.channels().len();
    let mut best = [f64::INFINITY; 2];
    for _ in 0..3 {
        let t = Instant::now();
        for &(wo, u, _) in &pairs {
            std::hint::black_box(b.sample(wo, u, &mut w[..c]));
        }
        best[0] = best[0].min(t.elapsed().as_secs_f64());
        let t = Instant::now();
        for &(wo, _, wi) in &pairs {
            b.eval(wi, wo, &mut w[..c]);
            std::hint::black_box(w[0]);
        }
        best[1] = best[1].min(t.elapsed().as_secs_f64());
    }
    let ns = |s: f64| s / n as f64 * 1e9;
    println!(
        "| {label:<34} | {} | {worst_max:7.1} | {:5.1} % | {build:5.2} | {:.0} / {:.0} ns = {:.2} |",
        cells.join(" | "),
        100.0 * worst_refused,
        ns(best[0]),
        ns(best[1]),
        best[0] / best[1]
    );
}

/// The `--midway` row of `b`: its sampler's resolution and worst predicted CV between views.
fn midway(label: &str, b: &dyn Brdf, res: Option<&SamplingResolution>) {
    let iso = b.flags().isotropic;
    let s = match res {
        Some(r) => TableSampler::build(b, iso, r),
        None => TableSampler::for_source(b, iso, false),
    };
    let r = s.resolution();
    let nt = r.theta_o.max(2);
    let mut views: Vec<f64> = (0..nt - 1)
        .map(|k| {
            let t = (k as f64 + 0.5) / (nt - 1) as f64;
            (1.0 - t * t).acos().to_degrees()
        })
        .filter(|t| (3.0..=85.0).contains(t))
        .collect();
    views.push(85.0);
    let (mut near, mut grazing) = ((0.0f64, 0.0f64), (0.0f64, 0.0f64));
    for v in views {
        let cv = s.predicted_cv(b, geometry::spherical(v.to_radians(), 0.3));
        let w = if v <= 75.0 { &mut near } else { &mut grazing };
        if cv > w.1 {
            *w = (v, cv);
        }
    }
    println!(
        "| {label:<34} | {}×{}×{} | {:.3} ({:.1}°) | {:.3} ({:.1}°) | {:.2} MB |",
        r.theta_h,
        r.phi_h,
        r.theta_o,
        near.1,
        near.0,
        grazing.1,
        grazing.0,
        s.memory_bytes() as f64 / 1e6
    );
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut samples = 40_000;
    let (mut native, mut table) = (true, true);
    let mut grid: Option<GridChoice> = None;
    let mut quantity: Option<Quantity> = None;
    let mut res = SamplingResolution::default();
    let mut res_set = false;
    let mut wrap = false;
    let mut mid = false;
    let mut sources = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--samples" => samples = args.next().unwrap_or_default().parse()?,
            "--native-only" => table = false,
            "--wrap" => wrap = true,
            "--midway" => mid = true,
            "--table-only" => native = false,
            "--grid" => grid = args.next().map(|g| g.parse()).transpose()?,
            "--quantity" => {
                let q = args.next().unwrap_or_default();
                quantity = Some(Quantity::from_name(&q).ok_or(format!("unknown quantity {q}"))?);
            }
            "--res" => {
                // θh,φh,θo[,floor] nodes of the table sampler (isotropic tables)
                let v: Vec<f64> = args
                    .next()
                    .unwrap_or_default()
                    .split(',')
                    .filter_map(|x| x.parse().ok())
                    .collect();
                res.theta_h = v[0] as usize;
                res.phi_h = v[1] as usize;
                res.theta_o = v[2] as usize;
                if let Some(&f) = v.get(3) {
                    res.floor = f;
                }
                res_set = true;
            }
            _ => sources.push(a),
        }
    }
    if mid {
        println!("| source | θh × φh × θo | worst midway 3–75° | 75–85° | bytes |");
        println!("|---|---|---|---|---|");
    } else {
        println!(
            "| source | {} | max w/mean | refused | build s | sample / eval |",
            VIEWS.map(|v| format!("{v}°")).join(" | ")
        );
        println!("|---|{}---|---|---|---|", "---|".repeat(VIEWS.len()));
    }
    let fixed = res_set.then_some(&res);
    let dir = brdftab::testkit::TempDir::new("sampling-cv");
    for (i, s) in sources.iter().enumerate() {
        let name = std::path::Path::new(s)
            .file_stem()
            .map(|f| f.to_string_lossy().replace("_rgb", ""))
            .filter(|n| !s.trim_start().starts_with('{') && !n.is_empty())
            .unwrap_or_else(|| format!("source {i}"));
        if native {
            let b = source::open(s)?;
            if mid {
                midway(&format!("{name} native"), b.as_ref(), fixed);
            } else if wrap {
                let iso = b.flags().isotropic;
                let r = if res_set || iso {
                    res
                } else {
                    SamplingResolution::anisotropic()
                };
                let sampler = TableSampler::build(b.as_ref(), iso, &r);
                let w = Wrapped { inner: b, sampler };
                row(&format!("{name} native, table sampler"), &w, samples);
            } else {
                row(&format!("{name} native"), b.as_ref(), samples);
            }
        }
        if table {
            let out = dir.join(format!("{i}.btdb"));
            let mut req = BakeRequest::new(s.as_str());
            if let Some(g) = grid {
                req = req.grid(g);
            }
            if let Some(q) = quantity {
                req = req.quantity(q);
            }
            req.run(&BakeTarget::file(&out))?;
            let mut b = source::open_table(&out, &Default::default())?;
            if mid {
                midway(&format!("{name} table"), &b, fixed);
                continue;
            }
            if res_set {
                b.set_sampling_resolution(&res);
            }
            row(&format!("{name} table"), &b, samples);
        }
    }
    Ok(())
}
