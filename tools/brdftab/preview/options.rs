//! What a render is asked for: [`RenderOptions`] and its choices, checked before any pixel is
//! rendered (sizes, samples, threads and the memory they take, combinations that would drop
//! a light the user asked for).

use std::sync::Arc;

use super::sampler::STRATIFIED_PAIRS;
use super::scene::{Environment, Light, Scene};
use brdftab::error::{Error, Result};

/// What to compute.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Mode {
    /// Full path tracing (up to `max_depth` bounces).
    #[default]
    Path,
    /// Direct lighting only ("lit sphere"): one bounce.
    Lit,
}

/// Which sampling strategies reach the emitters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Sampling {
    /// Light sampling and `Brdf::sample`, combined with the power heuristic.
    #[default]
    Mis,
    /// `Brdf::sample` only (no light sampling; point lights are then invisible).
    BrdfOnly,
    /// Light sampling only for emitters; BRDF samples still continue paths but count emitters
    /// they hit only after delta lobes.
    LightOnly,
    /// Light sampling and cosine-hemisphere sampling, MIS-combined: the sampled directions do not
    /// depend on the material, so two materials rendered with the same seed see the same
    /// directions and their difference is nearly free of noise (Russian roulette aside). Delta
    /// lobes still use `Brdf::sample`.
    Fixed,
}

/// The environment of the scene.
#[derive(Debug, Clone, Default)]
pub enum EnvChoice {
    /// The smooth procedural sky ([`Environment::sky`]).
    #[default]
    Sky,
    /// Constant radiance (the furnace).
    Constant([f32; 3]),
    /// No environment light.
    Black,
    /// A given environment (e.g. loaded from an EXR lat-long map).
    Map(Arc<Environment>),
}

/// The extra light of the scene.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum LightChoice {
    /// None.
    #[default]
    None,
    /// [`Light::default_point`].
    Point,
    /// [`Light::default_area`].
    Area,
    /// A given light.
    Custom(Light),
}

/// A name from `choices` (`(name, value)`), or an argument error naming `what` and the choices.
fn choose<T: Clone>(what: &str, s: &str, choices: &[(&str, T)]) -> Result<T> {
    let t = s.trim().to_ascii_lowercase();
    match choices.iter().find(|(n, _)| *n == t) {
        Some((_, v)) => Ok(v.clone()),
        None => {
            let names: Vec<&str> = choices.iter().map(|c| c.0).collect();
            Err(Error::arg(
                what,
                format!("`{s}`: expected {}", names.join(", ")),
            ))
        }
    }
}

impl Mode {
    /// Parses `path` or `lit`.
    pub fn parse(s: &str) -> Result<Mode> {
        choose("mode", s, &[("path", Mode::Path), ("lit", Mode::Lit)])
    }
}

impl Sampling {
    /// Parses `mis`, `brdf`, `light` or `fixed`.
    pub fn parse(s: &str) -> Result<Sampling> {
        let c = [
            ("mis", Sampling::Mis),
            ("brdf", Sampling::BrdfOnly),
            ("light", Sampling::LightOnly),
            ("fixed", Sampling::Fixed),
        ];
        choose("sampling", s, &c)
    }
}

impl EnvChoice {
    /// Parses `sky`, `white` (constant 1, the furnace), `none`, or a lat-long `.exr` file (whose
    /// name need not be UTF-8).
    pub fn parse(s: impl AsRef<std::ffi::OsStr>) -> Result<EnvChoice> {
        let s = s.as_ref();
        let b = s.as_encoded_bytes();
        if b.len() >= 4 && b[b.len() - 4..].eq_ignore_ascii_case(b".exr") {
            return Ok(EnvChoice::Map(Arc::new(Environment::from_exr(s)?)));
        }
        let s = &*s.to_string_lossy();
        let c = [
            ("sky", EnvChoice::Sky),
            ("white", EnvChoice::Constant([1.0; 3])),
            ("none", EnvChoice::Black),
        ];
        choose("env", s, &c).map_err(|e| match e {
            Error::InvalidArgument { name, msg } => {
                Error::arg(name, format!("{msg} or a .exr file"))
            }
            e => e,
        })
    }
}

impl LightChoice {
    /// Parses `none`, `point` or `area`.
    pub fn parse(s: &str) -> Result<LightChoice> {
        let c = [
            ("none", LightChoice::None),
            ("point", LightChoice::Point),
            ("area", LightChoice::Area),
        ];
        choose("light", s, &c)
    }
}

/// The largest image [`render`](crate::preview::render) accepts, in pixels (8192 × 8192). The
/// CLI's peak memory is about 28 bytes a pixel for one render (the tiles' results, the image,
/// the encoder's copy: 477 MB at 4096 × 4096) and 85 for `--compare` (two images, the pair, the
/// difference: 1.42 GB), so the 2²⁸ pixels once allowed (16384 × 16384) asked for ~23 GB and
/// ended in an out-of-memory abort rather than an error; 2²⁶ is at most ~5.7 GB.
pub const MAX_PIXELS: usize = 1 << 26;

/// The most threads a render starts: its 16-pixel tiles give no more threads work than there
/// are cores, and an unbounded count (100000) asked the system for that many threads first.
pub const MAX_THREADS: usize = 1024;

/// The most memory the per-thread sample tables may hold together: each thread keeps
/// `STRATIFIED_PAIRS` × spp sample pairs of 16 bytes for the pixel it renders (218 MB at the
/// largest spp), so 2²⁰ spp on 64 threads asked for 14 GB.
pub const MAX_SAMPLE_BYTES: usize = 4 << 30;

/// Everything a render needs besides the material.
#[derive(Debug, Clone)]
pub struct RenderOptions {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// Samples per pixel.
    pub spp: usize,
    /// Seed: same seed, same image, bit for bit, whatever the thread count.
    pub seed: u64,
    /// Maximum number of surface interactions per path (1 = direct lighting only).
    pub max_depth: usize,
    /// Path tracing or direct lighting.
    pub mode: Mode,
    /// Sampling strategies.
    pub sampling: Sampling,
    /// The environment.
    pub env: EnvChoice,
    /// The extra light.
    pub light: LightChoice,
    /// Whether a diffuse grey ground plane (albedo 0.5) is under the sphere.
    pub ground: bool,
    /// Exposure in stops for the written file, PNG or EXR (not applied to the returned image).
    pub exposure: f32,
    /// Number of threads (`None` = rayon's global pool).
    pub threads: Option<usize>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 256,
            height: 256,
            spp: 64,
            seed: 0,
            max_depth: 8,
            mode: Mode::Path,
            sampling: Sampling::Mis,
            env: EnvChoice::Sky,
            light: LightChoice::None,
            ground: false,
            exposure: 0.0,
            threads: None,
        }
    }
}

impl RenderOptions {
    /// Builds the scene these options describe.
    pub fn scene(&self) -> Scene {
        let env = match &self.env {
            EnvChoice::Sky => Environment::sky(),
            EnvChoice::Constant(c) => Environment::constant(*c),
            EnvChoice::Black => Environment::black(),
            EnvChoice::Map(e) => (**e).clone(),
        };
        let light = match self.light {
            LightChoice::None => None,
            LightChoice::Point => Some(Light::default_point()),
            LightChoice::Area => Some(Light::default_area()),
            LightChoice::Custom(l) => Some(l),
        };
        Scene::new(env, light, self.ground)
    }

    /// Checks the options before any work: every refusal names the field.
    pub(crate) fn validate(&self) -> Result<()> {
        let bad = |name: &str, msg: &str| {
            Err(Error::InvalidArgument {
                name: name.into(),
                msg: msg.into(),
            })
        };
        if self.width == 0 || self.height == 0 {
            return bad("size", "width and height must be positive");
        }
        let pixels = self.width.saturating_mul(self.height);
        if pixels > MAX_PIXELS {
            return Err(Error::InvalidArgument {
                name: "size".into(),
                msg: format!(
                    "{}×{} is {pixels} pixels; at most {MAX_PIXELS} (8192×8192)",
                    self.width, self.height
                ),
            });
        }
        if self.spp == 0 || self.spp > 1 << 20 {
            return bad("spp", "samples per pixel must be in 1..=1048576");
        }
        if self.max_depth == 0 {
            return bad("max_depth", "must be at least 1");
        }
        if self.threads == Some(0) {
            return bad("threads", "must be at least 1");
        }
        if self.threads.is_some_and(|n| n > MAX_THREADS) {
            return bad("threads", "must be at most 1024");
        }
        let workers = self.threads.unwrap_or_else(brdftab::par::threads);
        let bytes = (workers.saturating_mul(self.spp)).saturating_mul(STRATIFIED_PAIRS * 16);
        if bytes > MAX_SAMPLE_BYTES {
            let name = if self.threads.is_some() {
                "threads"
            } else {
                "spp"
            };
            return Err(Error::InvalidArgument {
                name: name.into(),
                msg: format!(
                    "{} samples per pixel on {workers} threads hold {:.1} GB of sample values \
                     (at most {:.1} GB): use fewer samples or threads",
                    self.spp,
                    bytes as f64 / 1e9,
                    MAX_SAMPLE_BYTES as f64 / 1e9
                ),
            });
        }
        // BRDF sampling never finds a point: the image would lack the light asked for.
        let point = matches!(
            self.light,
            LightChoice::Point | LightChoice::Custom(Light::Point { .. })
        );
        if point && self.sampling == Sampling::BrdfOnly {
            return bad(
                "light",
                "a point light is reached only by light sampling; sampling `brdf` renders \
                 without it (use `mis`, `light` or `fixed`, or an area light)",
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny() -> RenderOptions {
        RenderOptions {
            width: 24,
            height: 24,
            spp: 16,
            ..Default::default()
        }
    }

    #[test]
    fn a_point_light_that_brdf_sampling_cannot_reach_is_refused() {
        let opts = |light, sampling| RenderOptions {
            light,
            sampling,
            ..tiny()
        };
        let e = opts(LightChoice::Point, Sampling::BrdfOnly)
            .validate()
            .unwrap_err();
        assert!(
            matches!(&e, Error::InvalidArgument { name, .. } if name == "light"),
            "{e}"
        );
        let custom = LightChoice::Custom(Light::default_point());
        assert!(opts(custom, Sampling::BrdfOnly).validate().is_err());
        assert!(
            opts(LightChoice::Area, Sampling::BrdfOnly)
                .validate()
                .is_ok()
        );
        assert!(
            opts(LightChoice::Point, Sampling::LightOnly)
                .validate()
                .is_ok()
        );
    }

    #[test]
    fn thread_counts_and_sample_tables_beyond_the_limits_are_refused() {
        let opts = |threads, spp| RenderOptions {
            threads: Some(threads),
            spp,
            ..tiny()
        };
        assert!(opts(MAX_THREADS, 64).validate().is_ok());
        assert!(opts(8, 1 << 20).validate().is_ok());
        for (threads, spp) in [(MAX_THREADS + 1, 1), (100_000, 64), (64, 1 << 20)] {
            let e = opts(threads, spp).validate().unwrap_err();
            assert!(
                matches!(&e, Error::InvalidArgument { name, .. } if name == "threads"),
                "{e}"
            );
        }
    }

    #[test]
    fn sizes_beyond_the_pixel_limit_are_refused_before_rendering() {
        let size = |width, height| RenderOptions {
            width,
            height,
            ..tiny()
        };
        assert!(size(8192, 8192).validate().is_ok());
        assert!(size(1 << 26, 1).validate().is_ok());
        for (w, h) in [
            (16384, 16384),
            (8193, 8192),
            ((1 << 26) + 1, 1),
            (usize::MAX, 2),
        ] {
            let e = size(w, h).validate().unwrap_err();
            assert!(
                matches!(&e, Error::InvalidArgument { name, .. } if name == "size"),
                "{e}"
            );
        }
    }
}
