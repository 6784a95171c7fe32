//! The preview scene: a unit sphere (optionally resting on a diffuse grey ground plane) seen by a
//! pinhole camera, lit by an environment and optionally one point or small spherical light.
//!
//! World frame: **z is up**. The sphere has radius 1 and centre (0, 0, 1), so it rests on the
//! ground z = 0 when the ground is on. The camera looks at the sphere's centre from the −y side,
//! slightly above, with a 28° vertical field of view (the sphere fills about three quarters of the
//! image height).
//!
//! Environments are lat-long tables, looked up with the nearest texel, so radiance is piecewise
//! constant and importance sampling by luminance × sin θ is exact up to the luminance weighting
//! (pbrt's `ImageInfiniteLight` approach). Row 0 is the zenith (+z), the last row the nadir;
//! column u covers azimuth φ = 2πu measured from +x towards +y — pbrt-v3's layout; Mitsuba 3's
//! `envmap` (y up, u = atan2(x, −z)/2π) shows the same file mirrored, and renders this scene's
//! lighting with the columns flipped and `to_world` taking its (x, y, z) to world (−z, −x, y)
//! (`bindings/python/bench/render_vs_mitsuba.py`). The default [`Environment::sky`] is
//! deliberately smooth — a blue-white gradient, a broad warm "sun" lobe (σ ≈ 7°) and a dim ground
//! colour below the horizon — so that renders converge quickly and two renders can be compared
//! at a low noise floor.

use std::f64::consts::PI;
use std::path::Path;

use glam::{DVec2, DVec3};

use super::image::{Image, read_exr};
use brdftab::error::{Error, Result};

/// A piecewise-constant 1D distribution on [0, 1) with `func.len()` bins.
#[derive(Debug, Clone)]
struct Distribution1D {
    func: Vec<f64>,
    /// `cdf[i]` = ∫₀^{i/n} (normalized), `cdf[n]` = 1.
    cdf: Vec<f64>,
    /// ∫₀¹ func.
    integral: f64,
}

impl Distribution1D {
    fn new(func: Vec<f64>) -> Self {
        let n = func.len();
        let mut cdf = vec![0.0; n + 1];
        for i in 0..n {
            cdf[i + 1] = cdf[i] + func[i] / n as f64;
        }
        let integral = cdf[n];
        if integral > 0.0 {
            for c in &mut cdf {
                *c /= integral;
            }
        } else {
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f64 / n as f64;
            }
        }
        cdf[n] = 1.0;
        Distribution1D {
            func,
            cdf,
            integral,
        }
    }

    /// Sample x ∈ [0, 1), its density, and the bin index.
    fn sample(&self, u: f64) -> (f64, f64, usize) {
        let n = self.func.len();
        // Largest i with cdf[i] <= u.
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .saturating_sub(1)
            .min(n - 1);
        let width = self.cdf[i + 1] - self.cdf[i];
        let du = if width > 0.0 {
            ((u - self.cdf[i]) / width).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let x = ((i as f64 + du) / n as f64).min(1.0 - f64::EPSILON);
        let pdf = if self.integral > 0.0 {
            self.func[i] / self.integral
        } else {
            1.0
        };
        (x, pdf, i)
    }

    fn pdf(&self, i: usize) -> f64 {
        if self.integral > 0.0 {
            self.func[i] / self.integral
        } else {
            1.0
        }
    }
}

/// An environment: radiance arriving from every direction at infinity, as an RGB lat-long table.
#[derive(Debug, Clone)]
pub struct Environment {
    width: usize,
    height: usize,
    /// Linear RGB radiance per texel, row-major, row 0 = zenith.
    texels: Vec<[f32; 3]>,
    /// Conditional distributions over u, one per row.
    rows: Vec<Distribution1D>,
    /// Marginal distribution over rows (v).
    marginal: Distribution1D,
    /// True when every texel is zero (nothing to sample).
    black: bool,
    /// A short description.
    name: String,
}

impl Environment {
    /// An environment from a lat-long RGB table (`texels.len() == width * height`). Negative and
    /// non-finite radiance is clamped to 0.
    pub fn from_texels(
        width: usize,
        height: usize,
        texels: Vec<[f32; 3]>,
        name: impl Into<String>,
    ) -> Result<Self> {
        if width == 0 || height == 0 || texels.len() != width * height {
            return Err(Error::InvalidArgument {
                name: "environment".into(),
                msg: format!(
                    "{} texels for a {width}×{height} lat-long map",
                    texels.len()
                ),
            });
        }
        let texels: Vec<[f32; 3]> = texels
            .into_iter()
            .map(|t| t.map(|v| if v.is_finite() && v > 0.0 { v } else { 0.0 }))
            .collect();
        let mut rows = Vec::with_capacity(height);
        let mut row_integrals = Vec::with_capacity(height);
        for y in 0..height {
            let sin_theta = (PI * (y as f64 + 0.5) / height as f64).sin();
            let func: Vec<f64> = texels[y * width..(y + 1) * width]
                .iter()
                .map(|t| luminance(*t) * sin_theta)
                .collect();
            let d = Distribution1D::new(func);
            row_integrals.push(d.integral);
            rows.push(d);
        }
        let marginal = Distribution1D::new(row_integrals);
        let black = marginal.integral <= 0.0;
        Ok(Environment {
            width,
            height,
            texels,
            rows,
            marginal,
            black,
            name: name.into(),
        })
    }

    /// A lat-long environment map from an image (3+ channels: R, G, B; 1 channel: grey).
    pub fn from_image(img: &Image, name: impl Into<String>) -> Result<Self> {
        let rgb = img.to_rgb()?;
        let texels = rgb
            .data
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2]])
            .collect();
        Self::from_texels(rgb.width, rgb.height, texels, name)
    }

    /// Reads a lat-long OpenEXR environment map (see the module docs for its orientation).
    pub fn from_exr(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let img = read_exr(path)?;
        Self::from_image(&img, path.display().to_string())
    }

    /// Constant radiance from every direction (the furnace).
    pub fn constant(rgb: [f32; 3]) -> Self {
        // Enough rows for sampling to follow sin θ closely; columns are all equal.
        let (w, h) = (4, 64);
        Self::from_texels(w, h, vec![rgb; w * h], format!("constant {rgb:?}"))
            .expect("valid constant table")
    }

    /// No light from the environment.
    pub fn black() -> Self {
        let mut e = Self::constant([0.0; 3]);
        e.name = "black".into();
        e
    }

    /// The default procedural sky (see the module docs), tabulated at 512 × 256.
    pub fn sky() -> Self {
        let (w, h) = (512, 256);
        let sun = sun_direction();
        let mut texels = Vec::with_capacity(w * h);
        for y in 0..h {
            let theta = PI * (y as f64 + 0.5) / h as f64;
            for x in 0..w {
                let phi = 2.0 * PI * (x as f64 + 0.5) / w as f64;
                let d = brdftab::geometry::spherical(theta, phi);
                texels.push(sky_radiance(d, sun));
            }
        }
        Self::from_texels(w, h, texels, "sky").expect("valid sky table")
    }

    /// A short description.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// True when the environment emits nothing.
    pub fn is_black(&self) -> bool {
        self.black
    }

    fn texel_index(&self, dir: DVec3) -> Option<(usize, usize)> {
        let d = brdftab::geometry::normalize(dir)?;
        let theta = d.z.clamp(-1.0, 1.0).acos();
        let mut phi = d.y.atan2(d.x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let x = ((phi / (2.0 * PI) * self.width as f64) as usize).min(self.width - 1);
        let y = ((theta / PI * self.height as f64) as usize).min(self.height - 1);
        Some((x, y))
    }

    /// Radiance arriving from world direction `dir` (towards the environment).
    pub fn eval(&self, dir: DVec3) -> DVec3 {
        match self.texel_index(dir) {
            Some((x, y)) => rgb(self.texels[y * self.width + x]),
            None => DVec3::ZERO,
        }
    }

    /// Draws a direction with density ∝ luminance; returns (direction, solid-angle pdf, radiance).
    pub fn sample(&self, u: DVec2) -> Option<(DVec3, f64, DVec3)> {
        if self.black {
            return None;
        }
        let (v, pdf_v, y) = self.marginal.sample(u.y);
        let (uu, pdf_u, x) = self.rows[y].sample(u.x);
        let theta = PI * v;
        let sin_theta = theta.sin();
        if sin_theta <= 0.0 {
            return None;
        }
        let dir = brdftab::geometry::spherical(theta, 2.0 * PI * uu);
        let pdf = pdf_u * pdf_v / (2.0 * PI * PI * sin_theta);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some((dir, pdf, rgb(self.texels[y * self.width + x])))
    }

    /// The solid-angle density with which [`Environment::sample`] draws `dir`.
    pub fn pdf(&self, dir: DVec3) -> f64 {
        if self.black {
            return 0.0;
        }
        let Some(d) = brdftab::geometry::normalize(dir) else {
            return 0.0;
        };
        let Some((x, y)) = self.texel_index(d) else {
            return 0.0;
        };
        let sin_theta = (1.0 - d.z * d.z).max(0.0).sqrt();
        if sin_theta <= 0.0 {
            return 0.0;
        }
        self.rows[y].pdf(x) * self.marginal.pdf(y) / (2.0 * PI * PI * sin_theta)
    }
}

/// Direction towards the default sky's sun: elevation 40°, from the camera's left and behind it.
pub fn sun_direction() -> DVec3 {
    DVec3::new(-0.55, -0.75, 0.83).normalize()
}

/// The default sky's radiance in world direction `d` (unit) with the sun towards `sun`.
fn sky_radiance(d: DVec3, sun: DVec3) -> [f32; 3] {
    let zenith = DVec3::new(0.30, 0.50, 0.95);
    let horizon = DVec3::new(0.95, 0.97, 1.0);
    let ground = DVec3::new(0.16, 0.14, 0.12);
    let up = d.z.max(0.0);
    let sky = horizon.lerp(zenith, up.sqrt());
    // Blend sky into ground over a few degrees below the horizon, smoothly.
    let t = ((-d.z) / 0.08).clamp(0.0, 1.0);
    let t = t * t * (3.0 - 2.0 * t);
    let base = sky.lerp(ground, t);
    // A broad sun lobe exp(k (cos γ − 1)), k = 30 → σ ≈ 10.5°, peak 6 × warm white.
    let cos_g = d.dot(sun);
    let sun_l = 6.0 * (30.0 * (cos_g - 1.0)).exp() * DVec3::new(1.0, 0.92, 0.80);
    let l = base + sun_l * (1.0 - t);
    [l.x as f32, l.y as f32, l.z as f32]
}

#[inline]
fn luminance(t: [f32; 3]) -> f64 {
    0.2126 * t[0] as f64 + 0.7152 * t[1] as f64 + 0.0722 * t[2] as f64
}

#[inline]
fn rgb(t: [f32; 3]) -> DVec3 {
    DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64)
}

/// An additional light besides the environment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    /// An isotropic point light with radiant intensity `intensity` (W/sr per channel).
    Point {
        /// Position in world space.
        position: DVec3,
        /// Radiant intensity per RGB channel.
        intensity: DVec3,
    },
    /// A small emitting sphere of uniform radiance, sampled by the cone it subtends.
    Sphere {
        /// Centre in world space.
        center: DVec3,
        /// Radius.
        radius: f64,
        /// Emitted radiance per RGB channel.
        radiance: DVec3,
    },
}

impl Light {
    /// The default point light: upper left front of the sphere, irradiance ≈ 0.6 at the sphere.
    pub fn default_point() -> Self {
        Light::Point {
            position: DVec3::new(-2.5, -2.5, 4.0),
            intensity: DVec3::splat(15.0),
        }
    }

    /// The default small spherical ("area") light at the same place, similar irradiance.
    pub fn default_area() -> Self {
        Light::Sphere {
            center: DVec3::new(-2.5, -2.5, 4.0),
            radius: 0.35,
            radiance: DVec3::splat(15.0 / (PI * 0.35 * 0.35)),
        }
    }
}

/// What a ray hits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Hit {
    /// Nothing: the ray escapes to the environment.
    Miss,
    /// The material sphere at distance `t`, point `p`, outward normal `n`.
    Sphere {
        /// Ray parameter.
        t: f64,
        /// Hit point.
        p: DVec3,
        /// Unit outward normal.
        n: DVec3,
    },
    /// The ground plane z = 0 (from above).
    Ground {
        /// Ray parameter.
        t: f64,
        /// Hit point.
        p: DVec3,
    },
    /// The spherical light.
    Light {
        /// Ray parameter.
        t: f64,
    },
}

/// The scene: geometry, camera, environment, light.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Centre of the material sphere (radius 1).
    pub sphere_center: DVec3,
    /// Whether the ground plane z = 0 is present.
    pub ground: bool,
    /// Diffuse albedo of the ground (grey).
    pub ground_albedo: f64,
    /// The environment.
    pub env: Environment,
    /// An optional additional light.
    pub light: Option<Light>,
    /// Camera position.
    pub eye: DVec3,
    /// Camera basis: forward, right, up (unit).
    pub forward: DVec3,
    /// Camera right.
    pub right: DVec3,
    /// Camera up.
    pub up: DVec3,
    /// tan(vertical fov / 2).
    pub tan_half_fov: f64,
}

/// Intersection of the ray o + t d (d unit) with a sphere; the nearest t > `t_min`.
#[inline]
fn ray_sphere(o: DVec3, d: DVec3, c: DVec3, r: f64, t_min: f64) -> Option<f64> {
    let oc = o - c;
    let b = oc.dot(d);
    // Numerically stable discriminant (Hearn & Baker / Ray Tracing Gems ch. 7).
    let f = oc - b * d;
    let disc = r * r - f.length_squared();
    if disc < 0.0 {
        return None;
    }
    let cterm = oc.length_squared() - r * r;
    let q = -b - b.signum() * disc.sqrt();
    let (t0, t1) = if q != 0.0 {
        let a = cterm / q;
        (a.min(q), a.max(q))
    } else {
        (-disc.sqrt(), disc.sqrt())
    };
    if t0 > t_min {
        Some(t0)
    } else if t1 > t_min {
        Some(t1)
    } else {
        None
    }
}

impl Scene {
    /// The standard scene with the given environment, light and ground.
    pub fn new(env: Environment, light: Option<Light>, ground: bool) -> Self {
        let center = DVec3::new(0.0, 0.0, 1.0);
        let eye = center + 5.2 * DVec3::new(0.0, -1.0, 0.2).normalize();
        let forward = (center - eye).normalize();
        let right = forward.cross(DVec3::Z).normalize();
        let up = right.cross(forward);
        Scene {
            sphere_center: center,
            ground,
            ground_albedo: 0.5,
            env,
            light,
            eye,
            forward,
            right,
            up,
            tan_half_fov: (14.0f64).to_radians().tan(),
        }
    }

    /// The primary ray direction through image position (sx, sy) ∈ \[0,1\]² (y down), for an
    /// image of aspect ratio `aspect` = width / height.
    pub fn camera_ray(&self, sx: f64, sy: f64, aspect: f64) -> DVec3 {
        let px = (2.0 * sx - 1.0) * self.tan_half_fov * aspect;
        let py = (1.0 - 2.0 * sy) * self.tan_half_fov;
        (self.forward + px * self.right + py * self.up).normalize()
    }

    /// The first thing the ray o + t d (d unit) hits with t in (t_min, t_max).
    pub fn intersect(&self, o: DVec3, d: DVec3, t_max: f64) -> Hit {
        let t_min = 0.0;
        let mut best = Hit::Miss;
        let mut best_t = t_max;
        if let Some(t) = ray_sphere(o, d, self.sphere_center, 1.0, t_min)
            && t < best_t
        {
            best_t = t;
            let p = o + t * d;
            best = Hit::Sphere {
                t,
                p,
                n: (p - self.sphere_center).normalize(),
            };
        }
        if self.ground && d.z < 0.0 && o.z > 0.0 {
            let t = -o.z / d.z;
            if t > t_min && t < best_t {
                best_t = t;
                let mut p = o + t * d;
                p.z = 0.0;
                best = Hit::Ground { t, p };
            }
        }
        if let Some(Light::Sphere { center, radius, .. }) = self.light
            && let Some(t) = ray_sphere(o, d, center, radius, t_min)
            && t < best_t
        {
            best = Hit::Light { t };
        }
        best
    }

    /// Draws a direction from `p` towards the spherical light, uniformly in the cone it subtends:
    /// (direction, solid-angle pdf, radiance). `None` for point lights, no light, or `p`
    /// inside the light.
    pub fn sample_sphere_light(&self, p: DVec3, u: DVec2) -> Option<(DVec3, f64, DVec3)> {
        let Some(Light::Sphere {
            center,
            radius,
            radiance,
        }) = self.light
        else {
            return None;
        };
        let to_c = center - p;
        let d2 = to_c.length_squared();
        if d2 <= radius * radius {
            return None;
        }
        let axis = to_c / d2.sqrt();
        let sin2_max = radius * radius / d2;
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        // 1 − cos θmax without cancellation for small lights.
        let one_minus = sin2_max / (1.0 + cos_max);
        let cos_t = 1.0 - u.x * one_minus;
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        let frame = brdftab::geometry::Frame::from_normal(axis);
        let dir = frame.to_world(DVec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t));
        Some((dir, 1.0 / (2.0 * PI * one_minus), radiance))
    }

    /// The solid-angle density of [`Scene::sample_sphere_light`] for direction `d` from `p`
    /// (0 outside the cone).
    pub fn sphere_light_pdf(&self, p: DVec3, d: DVec3) -> f64 {
        let Some(Light::Sphere { center, radius, .. }) = self.light else {
            return 0.0;
        };
        let to_c = center - p;
        let d2 = to_c.length_squared();
        if d2 <= radius * radius {
            return 0.0;
        }
        let sin2_max = radius * radius / d2;
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        if d.dot(to_c) / d2.sqrt() < cos_max {
            return 0.0;
        }
        1.0 / (2.0 * PI * sin2_max / (1.0 + cos_max))
    }

    /// Emitted radiance of the spherical light (0 when there is none).
    pub fn light_radiance(&self) -> DVec3 {
        match self.light {
            Some(Light::Sphere { radiance, .. }) => radiance,
            _ => DVec3::ZERO,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// ∫ pdf dω = 1 and E[L/pdf] = ∫ L dω for the sky (against a direct quadrature).
    #[test]
    fn env_sampling_is_normalized_and_unbiased() {
        let env = Environment::sky();
        let mut rng = Rng::new(7);
        let n = 200_000;
        // Uniform-sphere estimate of ∫ pdf dω.
        let mut s = 0.0;
        for _ in 0..n {
            let d = brdftab::geometry::uniform_sphere(rng.next_dvec2());
            s += env.pdf(d) * 4.0 * PI;
        }
        let norm = s / n as f64;
        assert!((norm - 1.0).abs() < 0.02, "∫pdf = {norm}");
        // Importance-sampled estimate of ∫ lum dω vs the table's exact sum.
        let mut est = 0.0;
        for _ in 0..n {
            let (d, pdf, l) = env.sample(rng.next_dvec2()).unwrap();
            assert!((env.pdf(d) - pdf).abs() <= 1e-6 * pdf, "pdf mismatch");
            assert_eq!(env.eval(d), l);
            est += (0.2126 * l.x + 0.7152 * l.y + 0.0722 * l.z) / pdf;
        }
        let est = est / n as f64;
        let mut exact = 0.0;
        for y in 0..env.height {
            let (t0, t1) = (
                PI * y as f64 / env.height as f64,
                PI * (y + 1) as f64 / env.height as f64,
            );
            let dw = 2.0 * PI / env.width as f64 * (t0.cos() - t1.cos());
            for x in 0..env.width {
                exact += luminance(env.texels[y * env.width + x]) * dw;
            }
        }
        // Luminance·sinθ sampling leaves only the sinθ-within-row variation: tiny variance.
        assert!((est / exact - 1.0).abs() < 0.005, "{est} vs {exact}");
    }

    #[test]
    fn sphere_light_pdf_matches_sampling() {
        let scene = Scene::new(Environment::black(), Some(Light::default_area()), false);
        let p = DVec3::new(0.0, 0.0, 2.0);
        let mut rng = Rng::new(3);
        for _ in 0..1000 {
            let (d, pdf, _) = scene.sample_sphere_light(p, rng.next_dvec2()).unwrap();
            assert!((scene.sphere_light_pdf(p, d) - pdf).abs() < 1e-9 * pdf);
            assert!(matches!(
                scene.intersect(p, d, f64::INFINITY),
                Hit::Light { .. }
            ));
        }
    }

    #[test]
    fn camera_sees_the_sphere_in_the_centre_and_sky_in_the_corner() {
        let scene = Scene::new(Environment::sky(), None, false);
        let d = scene.camera_ray(0.5, 0.5, 1.0);
        assert!(matches!(
            scene.intersect(scene.eye, d, f64::INFINITY),
            Hit::Sphere { .. }
        ));
        let d = scene.camera_ray(0.0, 0.0, 1.0);
        assert_eq!(scene.intersect(scene.eye, d, f64::INFINITY), Hit::Miss);
    }
}

#[cfg(test)]
mod exr_env_tests {
    use super::*;

    #[test]
    fn exr_lat_long_map_loads_with_orientation() {
        // Bright top half (sky), dark bottom half: the zenith is bright, the nadir dark.
        let img = Image::from_fn(16, 8, 3, |_, y, o| o.fill(if y < 4 { 2.0 } else { 0.5 }));
        let dir = brdftab::testkit::TempDir::new("env");
        let p = dir.join("env.exr");
        crate::preview::image::write_exr(&img, &p, crate::preview::image::ExrPrecision::F16)
            .unwrap();
        let env = Environment::from_exr(&p).unwrap();
        assert_eq!(env.eval(DVec3::Z), DVec3::splat(2.0));
        assert_eq!(env.eval(-DVec3::Z), DVec3::splat(0.5));
        assert!(env.pdf(DVec3::new(0.0, 0.6, 0.8)) > env.pdf(DVec3::new(0.0, 0.6, -0.8)));
        assert!(Environment::from_exr("/nonexistent/env.exr").is_err());
    }
}
