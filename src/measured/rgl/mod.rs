//! RGL-EPFL measured BRDFs (Dupuy & Jakob, "An Adaptive Parameterization for Efficient Material
//! Acquisition and Rendering", ACM TOG 37(6), 2018), evaluated natively.
//!
//! A `.bsdf` file ([`tensor`](super::tensor) container) stores the reflectance not on a fixed
//! angular grid but in a *warped* domain adapted to each material: for every incident direction
//! (φi, θi) of the measurement, the visible normal distribution (`vndf`) defines a 2D warp from
//! the unit square onto the half-vector domain, and the reflectance (`rgb` or `spectra`) is
//! tabulated uniformly in the *unwarped* square. Evaluation therefore runs the warp backwards:
//!
//! 1. h = normalize(wi + wo); elevations by the stable form θ = 2·asin(|d − z| / 2), azimuths by
//!    atan2; unit coordinates u(θ) = sqrt(2θ/π), u(φ) = (φ + π)/2π (for isotropic files the half
//!    vector's azimuth is taken relative to φi and wrapped into [0, 1));
//! 2. the point of the unit square that the VNDF warp maps onto u(h) is found by inverting the
//!    piecewise-bilinear 2D distribution: conditional CDF along θ within the row, then the marginal
//!    CDF over rows (the `Marginal2D::invert` of the published reader). Every quantity — density,
//!    conditional and marginal CDF — is interpolated bilinearly over the conditioning parameters
//!    (φi, θi), each slice normalized on its own;
//! 3. the reflectance table is interpolated bilinearly at that point (and over (φi, θi), and over
//!    wavelength for spectral files), clipped at 0 (out-of-gamut RGB), and — when `jacobian` is
//!    set — multiplied by ndf(u(h)) / (4 σ(u(wi))), the Jacobian of the warp.
//!
//! The result is f_r · cos θo (what the reference reader's `eval(wi, wo)` returns — the
//! measurement includes the foreshortening of the outgoing direction); [`RglBrdf`] divides by
//! cos θo and returns f_r as every [`Brdf`] does. The tensor's incident axes are our `wi`.
//!
//! Anisotropic files store several φi; when their φi range covers only 1/2 or 1/4 of the circle
//! (a "reduction"), both directions are first moved into the stored range, as Mitsuba 3's
//! `measured` plugin does: reduction 2 assumes a half-turn symmetry and rotates both by π when
//! wi.y > 0; reduction 4 assumes mirror symmetry about both the x and y axes and reflects each
//! axis so that wi.x, wi.y ≤ 0.
//!
//! The algorithm follows the published reference (rgl-epfl/brdf-loader, `powitacq_rgb.inl`);
//! arithmetic here is f64 over the file's f32 data, so values agree with the f32 reference to
//! about 1e-6 relative away from discontinuities.

use std::f64::consts::{FRAC_2_PI, PI};
use std::path::Path;

use glam::DVec3;

use super::rgl_normal::{ContinuousAtNormal, NormalLimit};
use crate::brdf::{BakeSource, Brdf, Flags};
use crate::geometry;
use crate::spectrum::{ChannelMix, Channels, is_wavelength};
use crate::table::sampling::TableSampler;
pub(crate) use crate::table::warp2d::{Corners, Planes, Warp};

mod eval;
mod load;

/// An [`RglBrdf`] at one incident direction ([`RglBrdf::at_incidence`]).
pub(crate) struct AtIncidence<'a> {
    file: &'a RglBrdf,
    wi: DVec3,
    /// `None` where `wi` is below the horizon or not near unit length: `eval` is the file's.
    inc: Option<Incident>,
}

impl AtIncidence<'_> {
    /// The file's `eval(wi, wo)`, bit for bit.
    #[inline]
    pub(crate) fn eval(&self, wo: DVec3, out: &mut [f32]) {
        let v2 = wo.length_squared();
        match &self.inc {
            Some(inc) if geometry::is_near_unit_l2(v2) => {
                let out = &mut out[..self.file.channels.len()];
                out.fill(0.0);
                if wo.z > 0.0
                    && let Some(p) = self.file.outgoing(inc, geometry::unit_or_near(wo, v2))
                {
                    self.file.finish(p, out);
                }
            }
            _ => self.file.eval(self.wi, wo, out),
        }
    }
}

/// What a lookup derives from the incident direction alone ([`RglBrdf::at_incidence`]).
#[derive(Clone, Copy)]
struct Incident {
    /// The direction after the φ reduction's flips.
    wi: DVec3,
    /// The flips (signs of x and y), applied to the outgoing direction too.
    signs: Option<(f64, f64)>,
    phi_i: f64,
    k: Corners,
    /// σ(ωi) when the file has the Jacobian convention.
    sigma: f64,
}

/// Interval index `i` (clamped to [0, n−2]) with `values[i]` ≤ x, and the weight of `i + 1`
/// (clamped to [0, 1]). A single value gives (0, 0) — no interpolation.
#[inline]
fn param_weight<T: Copy + Into<f64>>(values: &[T], x: f64) -> (usize, usize, f64) {
    let n = values.len();
    if n < 2 {
        return (0, 0, 0.0);
    }
    let count = values.partition_point(|&v| v.into() <= x);
    let i = count.saturating_sub(1).min(n - 2);
    let (p0, p1) = (values[i].into(), values[i + 1].into());
    let w = ((x - p0) / (p1 - p0)).clamp(0.0, 1.0);
    (i, i + 1, w)
}

/// The file's spectral channels read at `nm`: linear between the two around it.
fn spectral_mix(wavelengths: &[f64], nm: f64) -> ChannelMix {
    let (c0, c1, t) = param_weight(wavelengths, nm);
    ChannelMix {
        index: [c0, c1, c1],
        weight: [1.0 - t, t, 0.0],
    }
}

/// Where a bake's view of an isotropic file ([`BakeSource::bake_view`]) replaces the normal slice's
/// pattern by its azimuthal mean: from θi = 0, fading out linearly by θi = 5° (or the file's
/// second θi sample, if nearer). The files' second sample is near 30°, but the pattern matters
/// only where a table cannot follow it — within a few degrees of the normal, where it turns
/// with φi faster than any grid resolves — and the view differs from the file by the pattern
/// wherever it applies: 5° keeps the tables within 0.8 % of the file inside 80° (30° would
/// cost 3 %) and their albedo at 1° within 1 % (2° leaves 4.6 %).
pub const NORMAL_BAND: f64 = 5.0 * (PI / 180.0);

/// u(θ) = sqrt(2θ/π).
#[inline]
pub(crate) fn theta2u(theta: f64) -> f64 {
    (theta * FRAC_2_PI).sqrt()
}

/// u(φ) = (φ + π) / 2π.
#[inline]
pub(crate) fn phi2u(phi: f64) -> f64 {
    (phi + PI) / (2.0 * PI)
}

pub(crate) use crate::geometry::elevation;

/// `a` with the sign opposite to `b`'s sign bit (enoki's `mulsign_neg`).
#[inline]
fn mulsign_neg(a: f64, b: f64) -> f64 {
    if b.is_sign_negative() { a } else { -a }
}

/// An RGL-EPFL `.bsdf` measurement, evaluated natively (see the module docs).
#[derive(Clone)]
pub struct RglBrdf {
    file: String,
    description: String,
    sha256: String,
    channels: Channels,
    isotropic: bool,
    jacobian: bool,
    reduction: u32,
    phi_i: Vec<f32>,
    theta_i: Vec<f32>,
    ndf: Planes,
    sigma: Planes,
    vndf: Warp,
    /// Luminance in the unwarped square, for importance sampling (absent: uniform).
    luminance: Option<Warp>,
    /// Reflectance: slices × file channels × ny × nx.
    table: Planes,
    /// File channels: 3 for RGB, else the wavelengths (nm) of `spectra`, as written
    /// (`load::decimal_nm`).
    wavelengths: Option<Vec<f64>>,
    /// Per output channel: the file channels it reads and their weights.
    out_map: Vec<ChannelMix>,
    /// A spectral file asked for RGB: each texel's spectrum projected to linear sRGB
    /// ([`crate::colour::srgb_weights`], negative values clipped first), three channels that
    /// `eval` reads ([`RglBrdf::out_channel`]); `eval_wavelength` reads the file's spectra.
    rgb_of_spectra: Option<Planes>,
    /// The azimuthal mean of the θi = 0 slice (isotropic files; made on the first
    /// [`BakeSource::bake_view`]).
    normal_limit: std::sync::OnceLock<NormalLimit>,
    /// Importance sampling of f_r cos θi given `wo`, built on first `sample`/`pdf`.
    sampler: std::sync::OnceLock<TableSampler>,
}

/// What [`RglBrdf::summary`] reports about a file.
#[derive(Debug, Clone)]
pub struct RglSummary {
    /// The `description` field.
    pub description: String,
    /// Number of stored incident azimuths and elevations.
    pub phi_i: usize,
    /// Number of stored incident elevations.
    pub theta_i: usize,
    /// Resolution of the reflectance table (rows × columns).
    pub resolution: (usize, usize),
    /// Resolution of the VNDF warp.
    pub vndf_resolution: (usize, usize),
    /// Isotropic (≤ 2 incident azimuths)?
    pub isotropic: bool,
    /// φ reduction of anisotropic files (1, 2 or 4).
    pub reduction: u32,
    /// `rgb` or `spectral (n wavelengths a–b nm)`.
    pub kind: String,
}

impl RglBrdf {
    /// The file's `description` field.
    pub fn description(&self) -> &str {
        &self.description
    }

    /// SHA-256 of the file, lower-case hex.
    pub fn sha256(&self) -> &str {
        &self.sha256
    }

    /// Facts about the file for `brdftab info`.
    pub fn summary(&self) -> RglSummary {
        RglSummary {
            description: self.description.clone(),
            phi_i: self.phi_i.len(),
            theta_i: self.theta_i.len(),
            resolution: (self.table.ny, self.table.nx),
            vndf_resolution: (self.vndf.pdf.ny, self.vndf.pdf.nx),
            isotropic: self.isotropic,
            reduction: self.reduction,
            kind: match &self.wavelengths {
                None => "rgb".into(),
                Some(w) => format!(
                    "spectral ({} wavelengths {}–{} nm)",
                    w.len(),
                    w[0],
                    w[w.len() - 1]
                ),
            },
        }
    }

    /// The sampler of [`Brdf::sample`] and [`Brdf::pdf`] (built on first use).
    pub fn sampler(&self) -> &TableSampler {
        self.sampler
            .get_or_init(|| TableSampler::for_source(self, self.isotropic, false))
    }

    /// The reference reader's value, f_r · cos θo, per channel (for tests and comparisons).
    pub fn eval_cos(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        self.eval(wi, wo, out);
        if let Some((wi, wo)) = geometry::upper_pair(wi, wo) {
            let _ = wi;
            for v in out[..self.channels.len()].iter_mut() {
                *v = (*v as f64 * wo.z) as f32;
            }
        }
    }
}

impl std::fmt::Debug for RglBrdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RglBrdf")
            .field("file", &self.file)
            .field("description", &self.description)
            .field("channels", &self.channels)
            .field("summary", &self.summary())
            .finish_non_exhaustive()
    }
}

impl Brdf for RglBrdf {
    fn bake_source(&self) -> Option<&dyn BakeSource> {
        Some(self)
    }

    fn channels(&self) -> &Channels {
        &self.channels
    }

    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let n = self.channels.len();
        let out = &mut out[..n];
        out.fill(0.0);
        if let Some(p) = self.prepare(wi, wo) {
            self.finish(p, out);
        }
    }

    fn eval_wavelength(&self, wi: DVec3, wo: DVec3, nm: f64) -> f64 {
        if !is_wavelength(nm) {
            return f64::NAN; // not a wavelength: no value (Channels::mix_at)
        }
        let mix = match &self.wavelengths {
            Some(wl) => spectral_mix(wl, nm),
            None => Channels::Rgb.mix_at(nm),
        };
        let Some((sample, k, scale, cos_o)) = self.prepare(wi, wo) else {
            return 0.0;
        };
        let v = mix.apply(|c| self.channel(sample, &k, c));
        let f = v * scale / cos_o;
        if f.is_finite() && f > 0.0 { f } else { 0.0 }
    }

    /// [`RglBrdf::eval_wavelength`] at each wavelength with one warp inversion for all of
    /// them (the inversion is most of a lookup's cost).
    fn eval_at_wavelengths(&self, wi: DVec3, wo: DVec3, nm: &[f64], out: &mut [f32]) {
        let Some((sample, k, scale, cos_o)) = self.prepare(wi, wo) else {
            for (o, &x) in out.iter_mut().zip(nm) {
                *o = if is_wavelength(x) { 0.0 } else { f32::NAN };
            }
            return;
        };
        for (o, &x) in out.iter_mut().zip(nm) {
            if !is_wavelength(x) {
                *o = f32::NAN;
                continue;
            }
            let mix = match &self.wavelengths {
                Some(wl) => spectral_mix(wl, x),
                None => Channels::Rgb.mix_at(x),
            };
            let f = mix.apply(|c| self.channel(sample, &k, c)) * scale / cos_o;
            *o = if f.is_finite() && f > 0.0 {
                f as f32
            } else {
                0.0
            };
        }
    }

    /// Importance sampling by conditional half-vector warps of f_r cos θi given `wo`
    /// ([`TableSampler`], built from this reader on first use: 131 k evaluations).
    ///
    /// The file's own warps ([`RglBrdf::tensor_sample`]) are conditioned on the tensor's
    /// incident direction, our `wi`, while `sample` must draw `wi` given `wo`; run with the
    /// roles swapped they are exact but follow f_r(wo, wi) cos θo rather than f_r(wi, wo) cos θi,
    /// and measured reflectance is not reciprocal enough for that: the weights' coefficient of
    /// variation was 0.1–0.6 over views 3–75°, against ≤ 0.06 with the table sampler.
    fn sample(
        &self,
        wo: DVec3,
        u: glam::DVec2,
        weight: &mut [f32],
    ) -> Option<crate::brdf::BrdfSample> {
        self.sampler().sample(self, wo, u, weight)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.sampler().pdf(wi, wo)
    }

    /// By quadrature to [`crate::analysis::albedo::Options::DATA`] (see [`Brdf::albedo`]).
    fn albedo(&self, wi: DVec3, out: &mut [f64]) {
        crate::brdf::albedo_with(self, wi, &crate::quadrature::Options::DATA, out)
    }

    fn flags(&self) -> Flags {
        Flags {
            isotropic: self.isotropic,
            lobes: crate::brdf::Lobes::GLOSSY,
            ..Flags::default()
        }
    }

    fn describe(&self) -> String {
        let s = self.summary();
        format!(
            "RGL measured BRDF \"{}\" ({}; {}, {}×{} table, {} φi × {} θi{})",
            s.description,
            Path::new(&self.file)
                .file_name()
                .map(|f| f.to_string_lossy().to_string())
                .unwrap_or_default(),
            s.kind,
            s.resolution.0,
            s.resolution.1,
            s.phi_i,
            s.theta_i,
            if s.isotropic {
                ", isotropic".to_string()
            } else {
                format!(", reduction {}", s.reduction)
            }
        )
    }
}

impl BakeSource for RglBrdf {
    fn bake_view(&self) -> Option<Box<dyn Brdf + '_>> {
        // Anisotropic files store the normal slice once per φi and interpolate between them:
        // their limit is the reader's own (left as it is).
        if !self.isotropic || self.theta_i.len() < 2 {
            return None;
        }
        let limit = self.normal_limit.get_or_init(|| NormalLimit::new(self));
        let t0 = self.theta_i[0] as f64;
        let slice = [t0, (self.theta_i[1] as f64).min(t0 + NORMAL_BAND)];
        Some(Box::new(ContinuousAtNormal::new(self, limit, slice)))
    }
}
