//! The path tracer and the lit-sphere mode.
//!
//! A unidirectional path tracer with next-event estimation: at every non-delta surface
//! interaction it samples the environment (by luminance) and the spherical light (by solid
//! angle), and it continues the path with [`Brdf::sample`]. The two ways of reaching an emitter —
//! a light sample and a BRDF sample that happens to hit it — are combined with multiple
//! importance sampling (Veach's power heuristic, β = 2), so both `Brdf::sample` and `Brdf::pdf`
//! are exercised and must agree; a wrong pdf shows up as a biased image (see the MIS-consistency
//! test). Point lights are reached only by light samples. Delta lobes skip light sampling and
//! take the emitter they hit with weight 1. Russian roulette starts after three bounces.
//!
//! [`Mode::Lit`] is the lecture's "lit sphere": direct lighting only (one bounce, no
//! interreflection), which is fast and nearly noise-free under the smooth default sky.
//!
//! Transmission is not traced: a path whose sampled direction enters the sphere ends there.
//!
//! Spectral BRDFs are rendered in RGB as a spectral renderer's pixel shows them: the channels'
//! spectrum (linear between the channels' wavelengths, held at the ends) projected to linear
//! sRGB under D65 ([`brdftab::colour::srgb_weights`]; a flat spectrum gives grey exactly), and
//! negative sRGB (a spectrum outside the gamut) clipped at 0 — for evaluation and for sample
//! weights alike, so MIS stays consistent.

use std::f64::consts::{FRAC_1_PI, PI};

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use super::image::Image;
use super::options::{Mode, RenderOptions, Sampling};
use super::sampler::PixelSampler;
use super::scene::{Hit, Light, Scene};
use brdftab::brdf::Brdf;
use brdftab::error::{Error, Result};
use brdftab::geometry::{self, Frame};
use brdftab::progress::{Progress, Stage};
use brdftab::spectrum::{Channels, MAX_CHANNELS};

/// A material seen in RGB: the BRDF's channels mapped to R, G, B (see the module docs).
struct RgbMaterial<'a> {
    brdf: &'a dyn Brdf,
    n: usize,
    /// Spectral channels: each channel's weight in R, G, B.
    map: Option<Vec<[f64; 3]>>,
    delta: bool,
}

impl<'a> RgbMaterial<'a> {
    fn new(brdf: &'a dyn Brdf) -> Result<Self> {
        let ch = brdf.channels();
        let n = ch.len();
        if n == 0 || n > MAX_CHANNELS {
            return Err(Error::Unsupported(format!(
                "rendering a BRDF with {n} channels (1..={MAX_CHANNELS} supported)"
            )));
        }
        let map = match ch {
            Channels::Rgb => None,
            Channels::Wavelengths(w) => Some(brdftab::colour::srgb_weights(w)),
        };
        Ok(RgbMaterial {
            brdf,
            n,
            map,
            delta: brdf.flags().delta,
        })
    }

    #[inline]
    fn to_rgb(&self, v: &[f32]) -> DVec3 {
        match &self.map {
            None => DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64),
            Some(m) => {
                let mut c = DVec3::ZERO;
                for (w, &x) in m.iter().zip(v) {
                    c += DVec3::from(*w) * x as f64;
                }
                c
            }
        }
    }

    #[inline]
    fn eval(&self, wi: DVec3, wo: DVec3) -> DVec3 {
        let mut buf = [0.0f32; MAX_CHANNELS];
        self.brdf.eval(wi, wo, &mut buf[..self.n]);
        sanitize(self.to_rgb(&buf[..self.n]))
    }

    /// (wi, pdf, weight, delta)
    #[inline]
    fn sample(&self, wo: DVec3, u: DVec2) -> Option<(DVec3, f64, DVec3, bool)> {
        let mut buf = [0.0f32; MAX_CHANNELS];
        let s = self.brdf.sample(wo, u, &mut buf[..self.n])?;
        let w = sanitize(self.to_rgb(&buf[..self.n]));
        if !(s.pdf > 0.0) || !s.wi.is_finite() {
            return None;
        }
        Some((s.wi, s.pdf, w, s.delta))
    }
}

/// Negative and non-finite values would poison a whole pixel: clamp them to 0.
#[inline]
fn sanitize(v: DVec3) -> DVec3 {
    let f = |x: f64| if x.is_finite() && x > 0.0 { x } else { 0.0 };
    DVec3::new(f(v.x), f(v.y), f(v.z))
}

/// The diffuse grey ground as a tiny inline material.
struct Ground {
    albedo: f64,
}

/// Power heuristic (β = 2) weight of strategy `a` against `b`.
#[inline]
fn power(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && (a2 + b2).is_finite() {
        a2 / (a2 + b2)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

/// Offset for spawning rays off surfaces (the scene is of unit scale).
const EPS: f64 = 1e-7;

struct Tracer<'a> {
    scene: &'a Scene,
    material: RgbMaterial<'a>,
    ground: Ground,
    max_depth: usize,
    sampling: Sampling,
}

/// Which surface a path is at.
enum Surf<'m> {
    Material(&'m RgbMaterial<'m>),
    Ground(&'m Ground),
}

impl Tracer<'_> {
    /// Radiance along the camera ray (eye, dir).
    fn radiance(&self, mut o: DVec3, mut d: DVec3, sampler: &mut PixelSampler) -> DVec3 {
        let scene = self.scene;
        let mut l = DVec3::ZERO;
        let mut beta = DVec3::ONE;
        // The BRDF-sampling pdf of the previous bounce (None: camera ray or delta lobe).
        let mut prev_pdf: Option<f64> = None;
        let mut prev_point = o;
        let mut depth = 0;
        loop {
            let hit = scene.intersect(o, d, f64::INFINITY);
            let (p, n, surf) = match hit {
                Hit::Miss => {
                    let le = scene.env.eval(d);
                    let w = self.emitter_weight(prev_pdf, || scene.env.pdf(d));
                    l += beta * le * w;
                    break;
                }
                Hit::Light { .. } => {
                    let le = scene.light_radiance();
                    let w = self.emitter_weight(prev_pdf, || scene.sphere_light_pdf(prev_point, d));
                    l += beta * le * w;
                    break;
                }
                Hit::Sphere { p, n, .. } => (p, n, Surf::Material(&self.material)),
                Hit::Ground { p, .. } => (p, DVec3::Z, Surf::Ground(&self.ground)),
            };
            if depth >= self.max_depth {
                break;
            }
            let frame = shading_frame(n);
            let wo = frame.to_local(-d);
            if wo.z <= 0.0 {
                break;
            }
            let delta = matches!(surf, Surf::Material(m) if m.delta);
            let origin = p + n * EPS;
            let dim = 1 + 4 * depth;

            // Next-event estimation.
            if !delta && self.sampling != Sampling::BrdfOnly {
                // Environment.
                if let Some((wi_w, pdf_l, le)) = scene.env.sample(sampler.pair(dim)) {
                    let wi = frame.to_local(wi_w);
                    if wi.z > 0.0 && scene.intersect(origin, wi_w, f64::INFINITY) == Hit::Miss {
                        let f = self.eval(&surf, wi, wo);
                        if f != DVec3::ZERO {
                            let w = self.light_weight(pdf_l, || self.pdf(&surf, wi, wo));
                            l += beta * f * (wi.z * w / pdf_l) * le;
                        }
                    }
                }
                // Extra light.
                match scene.light {
                    Some(Light::Sphere { .. }) => {
                        if let Some((wi_w, pdf_l, le)) =
                            scene.sample_sphere_light(origin, sampler.pair(dim + 1))
                        {
                            let wi = frame.to_local(wi_w);
                            if wi.z > 0.0
                                && matches!(
                                    scene.intersect(origin, wi_w, f64::INFINITY),
                                    Hit::Light { .. }
                                )
                            {
                                let f = self.eval(&surf, wi, wo);
                                let w = self.light_weight(pdf_l, || self.pdf(&surf, wi, wo));
                                l += beta * f * (wi.z * w / pdf_l) * le;
                            }
                        }
                    }
                    Some(Light::Point {
                        position,
                        intensity,
                    }) => {
                        let to = position - origin;
                        let dist2 = to.length_squared();
                        if let Some(wi_w) = geometry::normalize(to) {
                            let wi = frame.to_local(wi_w);
                            if wi.z > 0.0
                                && scene.intersect(origin, wi_w, dist2.sqrt()) == Hit::Miss
                            {
                                let f = self.eval(&surf, wi, wo);
                                l += beta * f * intensity * (wi.z / dist2);
                            }
                        }
                    }
                    None => {}
                }
            }

            // Continue the path.
            let Some((wi, pdf, weight, is_delta)) = self.sample(&surf, wo, sampler.pair(dim + 2))
            else {
                break;
            };
            if wi.z <= 0.0 {
                // Transmission is not traced.
                break;
            }
            beta *= weight;
            if beta == DVec3::ZERO {
                break;
            }
            prev_pdf = if is_delta { None } else { Some(pdf) };
            prev_point = origin;
            depth += 1;
            if depth >= 3 {
                let q = beta.max_element().min(0.95);
                if sampler.next_f64() >= q {
                    break;
                }
                beta /= q;
            }
            o = origin;
            d = frame.to_world(wi).normalize();
        }
        l
    }

    /// MIS weight of an emitter reached by a BRDF sample with density `prev_pdf`.
    #[inline]
    fn emitter_weight(&self, prev_pdf: Option<f64>, light_pdf: impl Fn() -> f64) -> f64 {
        match prev_pdf {
            None => 1.0, // camera ray or delta lobe: light sampling could not have found it
            Some(pb) => match self.sampling {
                Sampling::BrdfOnly => 1.0,
                Sampling::LightOnly => 0.0,
                Sampling::Mis | Sampling::Fixed => power(pb, light_pdf()),
            },
        }
    }

    /// MIS weight of a light sample with density `pdf_l`.
    #[inline]
    fn light_weight(&self, pdf_l: f64, brdf_pdf: impl Fn() -> f64) -> f64 {
        match self.sampling {
            Sampling::LightOnly => 1.0,
            Sampling::BrdfOnly => 0.0,
            Sampling::Mis | Sampling::Fixed => power(pdf_l, brdf_pdf()),
        }
    }

    #[inline]
    fn eval(&self, surf: &Surf, wi: DVec3, wo: DVec3) -> DVec3 {
        match surf {
            Surf::Material(m) => m.eval(wi, wo),
            Surf::Ground(g) => {
                if wi.z > 0.0 && wo.z > 0.0 {
                    DVec3::splat(g.albedo * FRAC_1_PI)
                } else {
                    DVec3::ZERO
                }
            }
        }
    }

    /// Density of the continuation strategy.
    #[inline]
    fn pdf(&self, surf: &Surf, wi: DVec3, wo: DVec3) -> f64 {
        match surf {
            Surf::Material(m) if self.sampling != Sampling::Fixed => {
                let p = m.brdf.pdf(wi, wo);
                if p.is_finite() && p > 0.0 { p } else { 0.0 }
            }
            _ => {
                if wi.z > 0.0 && wo.z > 0.0 {
                    wi.z * FRAC_1_PI
                } else {
                    0.0
                }
            }
        }
    }

    #[inline]
    fn sample(&self, surf: &Surf, wo: DVec3, u: DVec2) -> Option<(DVec3, f64, DVec3, bool)> {
        let cosine = |f: DVec3| {
            let wi = geometry::cosine_hemisphere(u);
            let pdf = wi.z * FRAC_1_PI;
            (pdf > 0.0).then_some((wi, pdf, f * PI, false))
        };
        match surf {
            Surf::Material(m) if self.sampling != Sampling::Fixed || m.delta => m.sample(wo, u),
            Surf::Material(m) => {
                let wi = geometry::cosine_hemisphere(u);
                let pdf = wi.z * FRAC_1_PI;
                (pdf > 0.0).then(|| (wi, pdf, m.eval(wi, wo) * PI, false))
            }
            Surf::Ground(g) => cosine(DVec3::splat(g.albedo * FRAC_1_PI)),
        }
    }
}

/// A shading frame whose tangent follows the sphere's lines of latitude (so anisotropic
/// materials look the same all around); the generic frame at the poles.
fn shading_frame(n: DVec3) -> Frame {
    let s = DVec3::Z.cross(n);
    let l = s.length();
    if l < 1e-6 {
        return Frame::from_normal(n);
    }
    let s = s / l;
    Frame {
        s,
        t: n.cross(s),
        n,
    }
}

/// Side of the square tiles the image is split into for parallel rendering.
const TILE: usize = 16;

/// Renders `brdf` on the sphere of the preview scene. Returns a linear RGB image (radiance).
///
/// `progress` sees one stage, `"rendering"`, counting pixels up to width × height
/// ([`Silent`](brdftab::progress::Silent) for none).
pub fn render(brdf: &dyn Brdf, opts: &RenderOptions, progress: &dyn Progress) -> Result<Image> {
    opts.validate()?;
    let _stage = Stage::begin(progress, "rendering", (opts.width * opts.height) as u64);
    let counter = Counter::new(progress);
    let scene = opts.scene();
    let tracer = Tracer {
        scene: &scene,
        material: RgbMaterial::new(brdf)?,
        ground: Ground {
            albedo: scene.ground_albedo,
        },
        max_depth: match opts.mode {
            Mode::Path => opts.max_depth,
            Mode::Lit => 1,
        },
        sampling: opts.sampling,
    };
    let (w, h, spp) = (opts.width, opts.height, opts.spp);
    let aspect = w as f64 / h as f64;
    let tiles_x = w.div_ceil(TILE);
    let tiles: Vec<(usize, usize)> = (0..h.div_ceil(TILE))
        .flat_map(|ty| (0..tiles_x).map(move |tx| (tx, ty)))
        .collect();
    let render_tile = |&(tx, ty): &(usize, usize)| -> Vec<f32> {
        let (x0, y0) = (tx * TILE, ty * TILE);
        let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
        let mut out = Vec::with_capacity((x1 - x0) * (y1 - y0) * 3);
        let mut sampler = PixelSampler::new(opts.seed, 0, spp);
        for y in y0..y1 {
            for x in x0..x1 {
                sampler.reset(opts.seed, (y * w + x) as u64);
                let mut sum = DVec3::ZERO;
                for s in 0..spp {
                    sampler.start(s);
                    let j = sampler.pair(0);
                    let d = scene.camera_ray(
                        (x as f64 + j.x) / w as f64,
                        (y as f64 + j.y) / h as f64,
                        aspect,
                    );
                    sum += sanitize(tracer.radiance(scene.eye, d, &mut sampler));
                }
                let v = sum / spp as f64;
                out.extend_from_slice(&[v.x as f32, v.y as f32, v.z as f32]);
            }
        }
        counter.add(((x1 - x0) * (y1 - y0)) as u64);
        out
    };
    let results: Vec<Vec<f32>> = match opts.threads {
        None => brdftab::par::install(|| tiles.par_iter().map(render_tile).collect()),
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| Error::Unsupported(format!("thread pool: {e}")))?;
            pool.install(|| tiles.par_iter().map(render_tile).collect())
        }
    };
    let mut img = Image::new(w, h, 3);
    for (&(tx, ty), data) in tiles.iter().zip(&results) {
        let (x0, y0) = (tx * TILE, ty * TILE);
        let tw = (x0 + TILE).min(w) - x0;
        for (row, chunk) in data.chunks_exact(tw * 3).enumerate() {
            let i = ((y0 + row) * w + x0) * 3;
            img.data[i..i + tw * 3].copy_from_slice(chunk);
        }
    }
    // A source that failed while it was read (a corrupt table chunk) rendered zeros.
    brdf.health()?;
    Ok(img)
}

/// Turns increments from several threads into [`Progress::set`] calls with the running total.
struct Counter<'a> {
    progress: &'a dyn Progress,
    done: std::sync::atomic::AtomicU64,
}

impl<'a> Counter<'a> {
    fn new(progress: &'a dyn Progress) -> Counter<'a> {
        Counter {
            progress,
            done: std::sync::atomic::AtomicU64::new(0),
        }
    }

    /// `k` more units are done.
    fn add(&self, k: u64) {
        let done = self.done.fetch_add(k, std::sync::atomic::Ordering::Relaxed) + k;
        self.progress.set(done);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::preview::compare::compare;
    use crate::preview::options::{EnvChoice, LightChoice};
    use brdftab::brdf::{BrdfSample, Flags};
    use brdftab::models::lambert::Lambert;
    use brdftab::progress::Silent;
    use brdftab::spectrum::Value;

    fn lambert(kd: f64) -> Lambert {
        Lambert::new(Value::Grey(kd), &Channels::Rgb).unwrap()
    }

    /// A glossy test material with its own importance sampling: f = kd/π + ks (n+2)/(2π) cosⁿα,
    /// α the angle between wi and the mirror direction of wo; sampled half by cosine, half by
    /// the Phong lobe. `pdf_scale` ≠ 1 makes `pdf` lie, to show the MIS test can fail.
    struct Glossy {
        kd: f64,
        ks: f64,
        n: f64,
        pdf_scale: f64,
        channels: Channels,
    }

    impl Glossy {
        fn new(pdf_scale: f64) -> Self {
            Glossy {
                kd: 0.3,
                ks: 0.6,
                n: 30.0,
                pdf_scale,
                channels: Channels::Rgb,
            }
        }
        fn lobe_pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
            let r = geometry::reflect_z(wo);
            let c = wi.dot(r).max(0.0);
            (self.n + 1.0) / (2.0 * PI) * c.powf(self.n)
        }
        fn true_pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
            0.5 * wi.z * FRAC_1_PI + 0.5 * self.lobe_pdf(wi, wo)
        }
    }

    impl Brdf for Glossy {
        fn channels(&self) -> &Channels {
            &self.channels
        }
        fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
            let v = match geometry::upper_pair(wi, wo) {
                Some((wi, wo)) => {
                    let c = wi.dot(geometry::reflect_z(wo)).max(0.0);
                    self.kd * FRAC_1_PI + self.ks * (self.n + 2.0) / (2.0 * PI) * c.powf(self.n)
                }
                None => 0.0,
            };
            out[..3].fill(v as f32);
        }
        fn flags(&self) -> Flags {
            Flags::SMOOTH_SYMMETRIC
        }
        fn describe(&self) -> String {
            "test glossy".into()
        }
        fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
            let wo = geometry::normalize(wo)?;
            if wo.z <= 0.0 {
                return None;
            }
            let wi = if u.x < 0.5 {
                geometry::cosine_hemisphere(DVec2::new(2.0 * u.x, u.y))
            } else {
                let u0 = 2.0 * u.x - 1.0;
                let cos_a = u0.powf(1.0 / (self.n + 1.0));
                let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
                let phi = 2.0 * PI * u.y;
                let local = DVec3::new(sin_a * phi.cos(), sin_a * phi.sin(), cos_a);
                Frame::from_normal(geometry::reflect_z(wo)).to_world(local)
            };
            if wi.z <= 0.0 {
                return None;
            }
            let pdf = self.true_pdf(wi, wo);
            let mut f = [0.0f32; 3];
            self.eval(wi, wo, &mut f);
            for (w, f) in weight[..3].iter_mut().zip(f) {
                *w = (f as f64 * wi.z / pdf) as f32;
            }
            Some(BrdfSample {
                wi,
                pdf,
                delta: false,
            })
        }
        fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
            match geometry::upper_pair(wi, wo) {
                Some((wi, wo)) => self.pdf_scale * self.true_pdf(wi, wo),
                None => 0.0,
            }
        }
    }

    fn tiny() -> RenderOptions {
        RenderOptions {
            width: 24,
            height: 24,
            spp: 16,
            ..Default::default()
        }
    }

    /// Mean of all samples and, from `k` renders with different seeds, its standard error.
    fn mean_and_se(brdf: &dyn Brdf, opts: &RenderOptions, k: u64) -> (f64, f64) {
        let means: Vec<f64> = (0..k)
            .map(|s| {
                let o = RenderOptions {
                    seed: 1000 + s,
                    ..opts.clone()
                };
                let img = render(brdf, &o, &Silent).unwrap();
                img.data.iter().map(|&v| v as f64).sum::<f64>() / img.data.len() as f64
            })
            .collect();
        let m = means.iter().sum::<f64>() / k as f64;
        let var = means.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (k - 1) as f64;
        (m, (var / k as f64).sqrt())
    }

    /// Classifies pixels: 0 = wholly background, 1 = on the sphere's silhouette, 2 = wholly on
    /// the sphere (all four corners hit it).
    fn coverage(opts: &RenderOptions) -> Vec<u8> {
        let scene = opts.scene();
        let mut cov = Vec::with_capacity(opts.width * opts.height);
        for y in 0..opts.height {
            for x in 0..opts.width {
                let hits = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                    .iter()
                    .filter(|(dx, dy)| {
                        let d = scene.camera_ray(
                            (x as f64 + dx) / opts.width as f64,
                            (y as f64 + dy) / opts.height as f64,
                            opts.width as f64 / opts.height as f64,
                        );
                        matches!(
                            scene.intersect(scene.eye, d, f64::INFINITY),
                            Hit::Sphere { .. }
                        )
                    })
                    .count();
                cov.push(match hits {
                    0 => 0,
                    4 => 2,
                    _ => 1,
                });
            }
        }
        cov
    }

    /// White furnace: a white Lambertian sphere (k_d = 1/π, albedo 1) under constant radiance 1
    /// reflects exactly 1 everywhere (a convex object never sees itself), and the background is 1.
    ///
    /// Statistics: stratification makes the noise of silhouette pixels (whose samples split
    /// between sphere and background) much larger than that of interior pixels, so interior
    /// pixels are tested one by one against the noise σ estimated from two independent renders
    /// of the interior (Var(a − b) = 2σ²); all pixels together are tested through the image mean
    /// against its standard error from six seeds.
    #[test]
    fn white_furnace() {
        let brdf = lambert(FRAC_1_PI);
        for mode in [Mode::Path, Mode::Lit] {
            for sampling in [
                Sampling::Mis,
                Sampling::BrdfOnly,
                Sampling::LightOnly,
                Sampling::Fixed,
            ] {
                let opts = RenderOptions {
                    env: EnvChoice::Constant([1.0; 3]),
                    mode,
                    sampling,
                    ..tiny()
                };
                let cov = coverage(&opts);
                let a = render(&brdf, &opts, &Silent).unwrap();
                let b = render(
                    &brdf,
                    &RenderOptions {
                        seed: 9,
                        ..opts.clone()
                    },
                    &Silent,
                )
                .unwrap();
                let interior: Vec<usize> = (0..cov.len()).filter(|&i| cov[i] == 2).collect();
                assert!(interior.len() > 150);
                let s2 = interior
                    .iter()
                    .map(|&i| ((a.data[3 * i] - b.data[3 * i]) as f64).powi(2))
                    .sum::<f64>()
                    / (2.0 * interior.len() as f64);
                let sigma = s2.sqrt();
                for (i, &c) in cov.iter().enumerate() {
                    let v = a.data[3 * i] as f64;
                    // Grey material, grey light: the three channels are identical.
                    assert_eq!(a.data[3 * i], a.data[3 * i + 2]);
                    match c {
                        0 => assert_eq!(v, 1.0, "background pixel {i}"),
                        // ~200 interior pixels: P(max |z| > 5) ≈ 1e-4.
                        2 => assert!(
                            (v - 1.0).abs() <= 5.0 * sigma + 1e-5,
                            "{mode:?} {sampling:?}: pixel {i} = {v}, σ = {sigma}"
                        ),
                        _ => {}
                    }
                }
                let (m, se) = mean_and_se(&brdf, &opts, 6);
                assert!(
                    (m - 1.0).abs() <= 5.0 * se + 1e-6,
                    "{mode:?} {sampling:?}: mean {m} ± {se}"
                );
                // BRDF sampling of a Lambertian under a constant environment is a zero-variance
                // estimator: weight 1 · radiance 1.
                if sampling == Sampling::BrdfOnly {
                    assert!(
                        sigma < 1e-6,
                        "BRDF-only furnace should be exact, σ = {sigma}"
                    );
                }
            }
        }
    }

    /// A black sphere reflects nothing: pixels wholly inside the sphere are exactly 0, also with
    /// a light and the ground (interreflections cannot add light to it).
    #[test]
    fn black_material_shows_only_background() {
        let brdf = lambert(0.0);
        for (light, ground) in [
            (LightChoice::None, false),
            (LightChoice::Area, true),
            (LightChoice::Point, true),
        ] {
            let opts = RenderOptions {
                light,
                ground,
                ..tiny()
            };
            let img = render(&brdf, &opts, &Silent).unwrap();
            let cov = coverage(&opts);
            let mut inside = 0;
            for (i, &c) in cov.iter().enumerate() {
                let p = &img.data[3 * i..3 * i + 3];
                if c == 2 {
                    inside += 1;
                    assert_eq!(p, &[0.0; 3], "pixel {i}");
                } else if c == 0 && !ground {
                    assert!(p.iter().all(|&v| v > 0.0), "background pixel {i}");
                }
            }
            assert!(inside > 100, "too few sphere pixels: {inside}");
        }
    }

    #[test]
    fn same_seed_is_bit_identical_across_thread_counts() {
        let brdf = Glossy::new(1.0);
        let opts = RenderOptions {
            light: LightChoice::Area,
            ground: true,
            spp: 4,
            ..tiny()
        };
        let a = render(
            &brdf,
            &RenderOptions {
                threads: Some(1),
                ..opts.clone()
            },
            &Silent,
        )
        .unwrap();
        let b = render(
            &brdf,
            &RenderOptions {
                threads: Some(3),
                ..opts.clone()
            },
            &Silent,
        )
        .unwrap();
        assert!(
            a.data
                .iter()
                .zip(&b.data)
                .all(|(x, y)| x.to_bits() == y.to_bits())
        );
        let c = render(&brdf, &RenderOptions { seed: 1, ..opts }, &Silent).unwrap();
        assert_ne!(a.data, c.data);
        assert_eq!(compare(&a, &a).unwrap().rel_rmse, 0.0);
    }

    /// MIS consistency: light+BRDF sampling with MIS, BRDF sampling alone and light sampling
    /// alone estimate the same integral. Each image mean is compared across strategies within
    /// 4.5 combined standard errors (estimated from independent seeds).
    #[test]
    fn mis_matches_brdf_only_and_light_only_for_a_glossy_model() {
        let brdf = Glossy::new(1.0);
        let base = RenderOptions {
            light: LightChoice::Area,
            ground: true,
            spp: 8,
            width: 16,
            height: 16,
            max_depth: 3,
            ..tiny()
        };
        let (m_mis, se_mis) = mean_and_se(&brdf, &base, 6);
        for sampling in [Sampling::BrdfOnly, Sampling::LightOnly, Sampling::Fixed] {
            let (m, se) = mean_and_se(
                &brdf,
                &RenderOptions {
                    sampling,
                    ..base.clone()
                },
                6,
            );
            let z = (m - m_mis) / (se * se + se_mis * se_mis).sqrt();
            assert!(
                z.abs() < 4.5,
                "{sampling:?}: {m} vs MIS {m_mis} (z = {z:.2})"
            );
        }
    }

    /// The same comparison detects a BRDF whose `pdf` disagrees with its `sample` (here 2×).
    #[test]
    fn mis_test_detects_a_wrong_pdf() {
        let base = RenderOptions {
            light: LightChoice::Area,
            ground: false,
            spp: 8,
            width: 16,
            height: 16,
            mode: Mode::Lit,
            ..tiny()
        };
        let (m_ok, se_ok) = mean_and_se(&Glossy::new(1.0), &base, 6);
        let (m_bad, se_bad) = mean_and_se(&Glossy::new(2.0), &base, 6);
        let z = (m_bad - m_ok) / (se_ok * se_ok + se_bad * se_bad).sqrt();
        assert!(z.abs() > 6.0, "wrong pdf not detected: z = {z:.2}");
    }

    #[test]
    fn invalid_options_are_errors_not_panics() {
        let brdf = lambert(0.1);
        for o in [
            RenderOptions { width: 0, ..tiny() },
            RenderOptions { spp: 0, ..tiny() },
            RenderOptions {
                max_depth: 0,
                ..tiny()
            },
            RenderOptions {
                threads: Some(0),
                ..tiny()
            },
        ] {
            assert!(render(&brdf, &o, &Silent).is_err());
        }
    }

    #[test]
    fn spectral_brdf_renders_as_its_colour() {
        // A grey spectral Lambertian renders like the RGB one (to f32 rounding).
        let ch = Channels::wavelengths(vec![400.0, 500.0, 600.0, 700.0]).unwrap();
        let spectral = Lambert::new(Value::Grey(0.2), &ch).unwrap();
        let rgb = lambert(0.2);
        let opts = RenderOptions { spp: 2, ..tiny() };
        let a = render(&spectral, &opts, &Silent).unwrap();
        let b = render(&rgb, &opts, &Silent).unwrap();
        assert!(compare(&a, &b).unwrap().rel_rmse < 1e-6);
    }

    #[test]
    fn an_rgb_colour_made_spectral_renders_as_that_colour() {
        // k_d given in RGB on spectral channels (the colour-preserving basis, sampled every
        // 10 nm) renders as the RGB Lambertian, up to what sampling the basis changes: the
        // projection of the sampled k_d spectrum against k_d, channel by channel.
        let ch = Channels::linspace(360.0, 830.0, 48).unwrap();
        let kd = Value::Rgb([0.25, 0.06, 0.02]);
        let sampled = kd.resolve(&ch);
        let Channels::Wavelengths(nm) = &ch else {
            unreachable!()
        };
        let w = brdftab::colour::srgb_weights(nm);
        let Value::Rgb(rgb) = kd else { unreachable!() };
        let colour_error = (0..3)
            .map(|c| {
                let p: f64 = w.iter().zip(&sampled).map(|(w, v)| w[c] * v).sum();
                (p / rgb[c] - 1.0).abs()
            })
            .fold(0.0, f64::max);
        assert!(colour_error < 1e-2, "{colour_error}"); // the dim blue channel: 0.5 %
        let spectral = Lambert::new(kd.clone(), &ch).unwrap();
        let rgb = Lambert::new(kd, &Channels::Rgb).unwrap();
        let opts = RenderOptions { spp: 2, ..tiny() };
        let a = render(&spectral, &opts, &Silent).unwrap();
        let b = render(&rgb, &opts, &Silent).unwrap();
        let e = compare(&a, &b).unwrap();
        // Same paths (Lambert's draws do not depend on channels): pixels differ by at most the
        // colour error (and f32 rounding).
        assert!(e.rel_rmse <= colour_error + 1e-5, "{e:?} vs {colour_error}");
    }

    #[test]
    fn progress_counts_every_pixel() {
        struct Max(std::sync::atomic::AtomicU64);
        impl Progress for Max {
            fn set(&self, done: u64) {
                self.0.fetch_max(done, std::sync::atomic::Ordering::Relaxed);
            }
        }
        let n = Max(std::sync::atomic::AtomicU64::new(0));
        render(
            &lambert(0.1),
            &RenderOptions {
                spp: 1,
                width: 37,
                height: 19,
                ..tiny()
            },
            &n,
        )
        .unwrap();
        assert_eq!(n.0.into_inner(), 37 * 19);
    }
}
