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

use std::f64::consts::{FRAC_2_PI, FRAC_PI_2, PI};
use std::path::Path;

use glam::DVec3;

use super::rgl_normal::{ContinuousAtNormal, NormalLimit};
use super::tensor::{Dtype, Field, TensorFile};
use crate::brdf::{BakeSource, Brdf, Flags};
use crate::error::{Error, Result};
use crate::geometry;
use crate::spectrum::{ChannelMix, Channels, MAX_CHANNELS, is_wavelength};
use crate::table::sampling::TableSampler;
pub(crate) use crate::table::warp2d::{Corners, Planes, Warp};
use crate::table::warp2d::{NO_PARAMS, bilinear};

/// [`Warp::build`] for a field of `file`, with the file in the error.
fn warp_of(planes: Planes, file: &TensorFile, field: &Field) -> Result<Warp> {
    Warp::build(planes).map_err(|(s, total)| {
        file.error(
            field,
            format!("slice {s} integrates to {total}, not a positive density"),
        )
    })
}

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

/// The planes of a spectral table (`slices × wavelengths × ny × nx`) projected to linear sRGB
/// per texel (`slices × 3 × ny × nx`): what a spectral renderer's pixel shows of each measured
/// spectrum, read linearly between the file's wavelengths as everywhere. Negative values (noise
/// in dark channels) are clipped first, as the reader clips what it interpolates.
fn project_to_rgb(table: &Planes, nm: &[f64]) -> Planes {
    let w = crate::colour::srgb_weights(nm);
    let (n, plane) = (nm.len(), table.plane_len());
    let slices = table.data.len() / (n * plane).max(1);
    let mut data = vec![0f32; slices * 3 * plane];
    let mut acc = vec![[0f64; 3]; plane];
    for s in 0..slices {
        acc.fill([0.0; 3]);
        for (k, wk) in w.iter().enumerate() {
            let src = &table.data[(s * n + k) * plane..][..plane];
            for (a, &v) in acc.iter_mut().zip(src) {
                let v = (v as f64).max(0.0);
                for c in 0..3 {
                    a[c] += wk[c] * v;
                }
            }
        }
        for c in 0..3 {
            let dst = &mut data[(s * 3 + c) * plane..][..plane];
            for (d, a) in dst.iter_mut().zip(&acc) {
                // Finite data near f32's limit must not project to inf (0 · inf is NaN in the
                // interpolation): saturate, as `eval` saturates.
                *d = a[c].clamp(-(f32::MAX as f64), f32::MAX as f64) as f32;
            }
        }
    }
    Planes {
        nx: table.nx,
        ny: table.ny,
        data,
    }
}

/// A file's wavelength (stored as f32) as the number written: the shortest decimal that reads
/// back as the same f32 (400.1, not 400.1000061035156, which named the channel
/// `400.1000061035156nm` and made `wavelengths` differ from what the writer was given). Strictly
/// increasing f32s stay strictly increasing, and each still rounds to its f32.
fn decimal_nm(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(x as f64)
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
    /// ([`decimal_nm`]).
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
    /// Opens a `.bsdf` file; RGB files give RGB channels, spectral files their own wavelengths
    /// (resampled evenly to [`MAX_CHANNELS`] when there are more).
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        Self::from_tensor(&TensorFile::open(path)?, None)
    }

    /// Opens a `.bsdf` file for a chosen channel set. A spectral file's channels are interpolated
    /// at the set's wavelengths; asked for RGB, its spectra are projected to linear sRGB (CIE
    /// 1931, D65: the colour a spectral renderer shows); an RGB file asked for
    /// wavelengths gives its R, G, B through the colour-preserving basis
    /// ([`Channels::mix_at`]); an RGB file asked for RGB, exactly its R, G, B.
    pub fn open_with_channels(path: impl AsRef<Path>, channels: &Channels) -> Result<Self> {
        Self::from_tensor(&TensorFile::open(path)?, Some(channels))
    }

    /// Builds from a parsed tensor file.
    pub fn from_tensor(tf: &TensorFile, channels: Option<&Channels>) -> Result<Self> {
        Self::build(tf, channels, true)
    }

    /// [`from_tensor`](Self::from_tensor) without the file's SHA-256 ([`sha256`](Self::sha256)
    /// is empty): the RGL writer's placement reads back a file of up to 32 MiB at each step,
    /// and hashing it was 0.34 s of a 12 s write (session 42).
    pub(crate) fn from_tensor_unhashed(tf: &TensorFile) -> Result<Self> {
        Self::build(tf, None, false)
    }

    fn build(tf: &TensorFile, channels: Option<&Channels>, hash: bool) -> Result<Self> {
        let field = |n: &str| tf.field(n);
        let f32s = |f: &Field| -> Result<Vec<f32>> {
            if f.dtype != Dtype::F32 {
                return Err(tf.error(f, format!("expected f32, found {}", f.dtype.name())));
            }
            tf.to_f32(f)
        };
        // Incident parameters: finite (checked by to_f32) and strictly increasing.
        let params = |name: &str| -> Result<Vec<f32>> {
            let f = field(name)?;
            tf.expect_ndim(f, 1)?;
            let v = f32s(f)?;
            if v.is_empty() {
                return Err(tf.error(f, "must not be empty"));
            }
            if v.windows(2).any(|w| w[1] <= w[0]) {
                return Err(tf.error(f, "values must be strictly increasing"));
            }
            Ok(v)
        };
        // Angles in radians within their domain: θi ∈ [0, π/2], φi ∈ [−π, π] (a file written in
        // degrees would otherwise be read as one clamped slice, silently wrong).
        let within = |name: &str, v: Vec<f32>, lo: f64, hi: f64| -> Result<Vec<f32>> {
            const SLACK: f64 = 1e-4;
            match v
                .iter()
                .find(|&&x| !(lo - SLACK..=hi + SLACK).contains(&(x as f64)))
            {
                Some(x) => Err(tf.error(
                    field(name)?,
                    format!("{x} is outside [{lo:.6}, {hi:.6}] (radians)"),
                )),
                None => Ok(v),
            }
        };
        let phi_i = within("phi_i", params("phi_i")?, -PI, PI)?;
        let theta_i = within("theta_i", params("theta_i")?, 0.0, FRAC_PI_2)?;
        let (np, nt) = (phi_i.len(), theta_i.len());

        let plane2 = |name: &str| -> Result<Planes> {
            let f = field(name)?;
            let s = tf.expect_ndim(f, 2)?;
            if s[0] < 2 || s[1] < 2 {
                return Err(tf.error(
                    f,
                    format!("needs at least 2×2 samples, has {}", f.describe()),
                ));
            }
            Ok(Planes {
                nx: s[1],
                ny: s[0],
                data: f32s(f)?,
            })
        };
        let ndf = plane2("ndf")?;
        let sigma = plane2("sigma")?;
        // D ≥ 0 with ∫ D cos θ dω = 1, and σ(ω) ≥ cos θ > 0 below the horizon (the last column,
        // θ = π/2, may be 0): otherwise the Jacobian ndf / 4σ is negative, infinite or 0 and
        // every lookup would silently read 0.
        if let Some(v) = ndf.data.iter().find(|&&v| v < 0.0) {
            return Err(tf.error(field("ndf")?, format!("negative density {v}")));
        }
        if ndf.data.iter().all(|&v| v == 0.0) {
            return Err(tf.error(field("ndf")?, "is 0 everywhere, not a distribution"));
        }
        let last = |i: usize| i % sigma.nx == sigma.nx - 1;
        if let Some((_, v)) =
            (sigma.data.iter().enumerate()).find(|&(i, &v)| v < 0.0 || (v == 0.0 && !last(i)))
        {
            return Err(tf.error(
                field("sigma")?,
                format!("{v} where a projected area must be positive"),
            ));
        }

        let vf = field("vndf")?;
        let vs = tf.expect_ndim(vf, 4)?.to_vec();
        if vs[0] != np || vs[1] != nt || vs[2] < 2 || vs[3] < 2 {
            return Err(tf.error(
                vf,
                format!(
                    "shape {} does not match φi × θi = {np} × {nt} (× ≥2 × ≥2)",
                    vf.describe()
                ),
            ));
        }
        let mut vdata = f32s(vf)?;
        if vdata.iter().any(|&v| v < 0.0) {
            // A density must be non-negative; clamp tiny negative fitting noise.
            vdata.iter_mut().for_each(|v| *v = v.max(0.0));
        }
        let vndf = warp_of(
            Planes {
                nx: vs[3],
                ny: vs[2],
                data: vdata,
            },
            tf,
            vf,
        )?;

        let luminance = match tf.get("luminance") {
            Some(lf) => {
                let ls = tf.expect_ndim(lf, 4)?.to_vec();
                if ls[0] != np || ls[1] != nt || ls[2] < 2 || ls[3] < 2 {
                    return Err(tf.error(
                        lf,
                        format!(
                            "shape {} does not match φi × θi = {np} × {nt}",
                            lf.describe()
                        ),
                    ));
                }
                let mut d = f32s(lf)?;
                d.iter_mut().for_each(|v| *v = v.max(0.0));
                Some(warp_of(
                    Planes {
                        nx: ls[3],
                        ny: ls[2],
                        data: d,
                    },
                    tf,
                    lf,
                )?)
            }
            None => None,
        };

        let (tfield, wavelengths) = if let Some(f) = tf.get("rgb") {
            (f, None)
        } else if let Some(f) = tf.get("spectra") {
            let wf = field("wavelengths")?;
            tf.expect_ndim(wf, 1)?;
            let wl = f32s(wf)?;
            if wl.is_empty() || wl.windows(2).any(|w| w[1] <= w[0]) || wl[0] <= 0.0 {
                return Err(tf.error(wf, "wavelengths must be positive and strictly increasing"));
            }
            (
                f,
                Some(wl.into_iter().map(decimal_nm).collect::<Vec<f64>>()),
            )
        } else {
            return Err(Error::format(
                tf.file_name(),
                Some("rgb"),
                None,
                "neither `rgb` nor `spectra` is present",
            ));
        };
        let ts = tf.expect_ndim(tfield, 5)?.to_vec();
        let nch = wavelengths.as_ref().map_or(3, |w| w.len());
        if ts[0] != np || ts[1] != nt || ts[2] != nch || ts[3] < 2 || ts[4] < 2 {
            return Err(tf.error(
                tfield,
                format!(
                    "shape {} does not match φi × θi × channels = {np} × {nt} × {nch} (× ≥2 × ≥2)",
                    tfield.describe()
                ),
            ));
        }
        let table = Planes {
            nx: ts[4],
            ny: ts[3],
            data: f32s(tfield)?,
        };

        let jacobian = match tf.get("jacobian") {
            Some(f) => tf.to_f64(f)?.first().copied().unwrap_or(0.0) != 0.0,
            None => false,
        };
        let description = match tf.get("description") {
            Some(f) => String::from_utf8_lossy(tf.raw(f))
                .trim_end_matches('\0')
                .to_string(),
            None => String::new(),
        };

        let isotropic = np <= 2;
        let mut reduction = 1;
        if !isotropic {
            let span = (phi_i[np - 1] - phi_i[0]) as f64;
            let r = (2.0 * PI / span).round();
            reduction = match r as i64 {
                1 => 1,
                2 => 2,
                4 => 4,
                _ => {
                    return Err(Error::Unsupported(format!(
                        "{}: φi spans {span:.4} rad, a reduction of {r} (only 1, 2, 4 are defined)",
                        tf.file_name()
                    )));
                }
            };
        }

        // Output channels.
        let channels = match (channels, &wavelengths) {
            (Some(c), _) => c.clone(),
            (None, None) => Channels::Rgb,
            (None, Some(wl)) if wl.len() <= MAX_CHANNELS => Channels::wavelengths(wl.clone())?,
            (None, Some(wl)) => Channels::linspace(wl[0], wl[wl.len() - 1], MAX_CHANNELS)?,
        };
        let rgb_of_spectra = match (&channels, &wavelengths) {
            (Channels::Rgb, Some(wl)) => Some(project_to_rgb(&table, wl)),
            _ => None,
        };
        let out_map = match (&channels, &wavelengths) {
            (Channels::Rgb, _) => (0..3)
                .map(|i| ChannelMix {
                    index: [i; 3],
                    weight: [1.0, 0.0, 0.0],
                })
                .collect(),
            (c, None) => (0..c.len())
                .map(|i| Channels::Rgb.mix_at(c.wavelength(i)))
                .collect(),
            (c, Some(wl)) => (0..c.len())
                .map(|i| spectral_mix(wl, c.wavelength(i)))
                .collect(),
        };

        use sha2::Digest;
        let sha256 = if hash {
            format!("{:x}", sha2::Sha256::digest(tf.bytes()))
        } else {
            String::new()
        };
        Ok(RglBrdf {
            file: tf.file_name().to_string(),
            description,
            sha256,
            channels,
            isotropic,
            jacobian,
            reduction,
            phi_i,
            theta_i,
            ndf,
            sigma,
            vndf,
            luminance,
            table,
            wavelengths,
            out_map,
            rgb_of_spectra,
            normal_limit: std::sync::OnceLock::new(),
            sampler: std::sync::OnceLock::new(),
        })
    }

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

    fn corners(&self, phi_i: f64, theta_i: f64) -> Corners {
        let (p0, p1, wp) = param_weight(&self.phi_i, phi_i);
        let (t0, t1, wt) = param_weight(&self.theta_i, theta_i);
        let nt = self.theta_i.len();
        Corners {
            slice: [p0 * nt + t0, p0 * nt + t1, p1 * nt + t0, p1 * nt + t1],
            w: [
                (1.0 - wp) * (1.0 - wt),
                (1.0 - wp) * wt,
                wp * (1.0 - wt),
                wp * wt,
            ],
        }
    }

    /// The warped point, the corners and the Jacobian factor for a pair; `None` → value 0.
    #[inline]
    fn prepare(&self, wi: DVec3, wo: DVec3) -> Option<([f64; 2], Corners, f64, f64)> {
        let (wi, wo) = geometry::upper_pair(wi, wo)?;
        self.outgoing(&self.incident(wi), wo)
    }

    /// What [`prepare`](Self::prepare) derives from the incident direction alone (`wi` as
    /// `upper_pair` returns it).
    #[inline]
    fn incident(&self, mut wi: DVec3) -> Incident {
        let mut signs = None;
        if self.reduction >= 2 {
            let sy = wi.y;
            let sx = if self.reduction == 4 { wi.x } else { sy };
            wi.x = mulsign_neg(wi.x, sx);
            wi.y = mulsign_neg(wi.y, sy);
            signs = Some((sx, sy));
        }
        let theta_i = elevation(wi);
        let phi_i = wi.y.atan2(wi.x);
        let u_wi = [theta2u(theta_i), phi2u(phi_i)];
        let k = self.corners(phi_i, theta_i);
        let sigma = if self.jacobian {
            bilinear(&self.sigma, &NO_PARAMS, 0, 0, u_wi)
        } else {
            1.0
        };
        Incident {
            wi,
            signs,
            phi_i,
            k,
            sigma,
        }
    }

    /// [`prepare`](Self::prepare) of `wo` (as `upper_pair` returns it) for an incidence.
    #[inline]
    fn outgoing(&self, inc: &Incident, mut wo: DVec3) -> Option<([f64; 2], Corners, f64, f64)> {
        let cos_o = wo.z;
        if let Some((sx, sy)) = inc.signs {
            wo.x = mulsign_neg(wo.x, sx);
            wo.y = mulsign_neg(wo.y, sy);
        }
        let wm = geometry::normalize(inc.wi + wo)?;
        let theta_m = elevation(wm);
        let phi_m = wm.y.atan2(wm.x);
        let mut u_wm = [
            theta2u(theta_m),
            phi2u(if self.isotropic {
                phi_m - inc.phi_i
            } else {
                phi_m
            }),
        ];
        u_wm[1] -= u_wm[1].floor();
        let k = inc.k;
        let sample = self.vndf.invert(u_wm, &k);
        let scale = if self.jacobian {
            let ndf = bilinear(&self.ndf, &NO_PARAMS, 0, 0, u_wm);
            let sigma = inc.sigma;
            if sigma.is_nan() || sigma <= 0.0 {
                return None;
            }
            ndf / (4.0 * sigma)
        } else {
            1.0
        };
        Some((sample, k, scale, cos_o))
    }

    /// This file at one incident direction: [`AtIncidence::eval`] is `eval(wi, wo)` to the bit,
    /// with what depends on `wi` alone (its azimuth and elevation, the slices around it, σ)
    /// found once. The RGL writer's placement measures albedos of the file it reads back,
    /// thousands of outgoing directions per incidence (session 42).
    pub(crate) fn at_incidence(&self, wi: DVec3) -> AtIncidence<'_> {
        let l2 = wi.length_squared();
        // `upper_pair` treats each direction alone when both are near unit length.
        let inc = (wi.z > 0.0 && geometry::is_near_unit_l2(l2))
            .then(|| self.incident(geometry::unit_or_near(wi, l2)));
        AtIncidence {
            file: self,
            wi,
            inc,
        }
    }

    /// The channels of a prepared pair (`out` zeroed).
    #[inline]
    fn finish(&self, (sample, k, scale, cos_o): ([f64; 2], Corners, f64, f64), out: &mut [f32]) {
        for (o, mix) in out.iter_mut().zip(&self.out_map) {
            let v = mix.apply(|c| self.out_channel(sample, &k, c));
            let f = v * scale / cos_o;
            // Negative ndf/sigma (only in corrupt files) or NaN must not leak out; a value
            // beyond f32 (measured f_r grows like 1/cos θo: 3.7e99 at cos 1e-100) saturates, as
            // the original Phong's does, rather than dropping to 0 where `eval_wavelength`
            // gives it.
            *o = if f > 0.0 {
                f.min(f32::MAX as f64) as f32
            } else {
                0.0
            };
        }
    }

    /// Output channel `c`'s value before the cosine: the file's channel, or for a spectral file
    /// asked for RGB the projected planes'.
    #[inline]
    fn out_channel(&self, sample: [f64; 2], k: &Corners, c: usize) -> f64 {
        match &self.rgb_of_spectra {
            Some(t) => {
                let plane = t.plane_len();
                bilinear(t, k, 3 * plane, c * plane, sample).max(0.0)
            }
            None => self.channel(sample, k, c),
        }
    }

    /// The stored reflectance of file channel `c` at the warped point, clipped at 0.
    #[inline]
    fn channel(&self, sample: [f64; 2], k: &Corners, c: usize) -> f64 {
        let nch = self.wavelengths.as_ref().map_or(3, |w| w.len());
        let plane = self.table.plane_len();
        bilinear(&self.table, k, nch * plane, c * plane, sample).max(0.0)
    }

    /// Signs for the φ reduction of anisotropic files, from the tensor-incident direction.
    #[inline]
    fn reduction_signs(&self, inc: DVec3) -> Option<(f64, f64)> {
        (self.reduction >= 2).then(|| {
            let sy = inc.y;
            (if self.reduction == 4 { inc.x } else { sy }, sy)
        })
    }

    #[inline]
    fn flip(v: DVec3, signs: Option<(f64, f64)>) -> DVec3 {
        match signs {
            Some((sx, sy)) => DVec3::new(mulsign_neg(v.x, sx), mulsign_neg(v.y, sy), v.z),
            None => v,
        }
    }

    /// Solid-angle density with which the measurement's own sampler (luminance warp, then VNDF
    /// warp, then reflection about the half vector) draws `out` for the tensor-incident
    /// direction `inc`.
    pub fn tensor_pdf(&self, inc: DVec3, out: DVec3) -> f64 {
        let Some((inc, out)) = geometry::upper_pair(inc, out) else {
            return 0.0;
        };
        let signs = self.reduction_signs(inc);
        let (inc, out) = (Self::flip(inc, signs), Self::flip(out, signs));
        let Some(wm) = geometry::normalize(inc + out) else {
            return 0.0;
        };
        let theta_i = elevation(inc);
        let phi_i = inc.y.atan2(inc.x);
        let phi_m = wm.y.atan2(wm.x);
        let mut u_wm = [
            theta2u(elevation(wm)),
            phi2u(if self.isotropic { phi_m - phi_i } else { phi_m }),
        ];
        u_wm[1] -= u_wm[1].floor();
        let k = self.corners(phi_i, theta_i);
        let (sample, vndf_pdf) = self.vndf.invert_pdf(u_wm, &k);
        let lum = self.luminance.as_ref().map_or(1.0, |l| l.eval(sample, &k));
        let sin_m = (wm.x * wm.x + wm.y * wm.y).sqrt();
        let jac = (2.0 * PI * PI * u_wm[0] * sin_m).max(1e-6) * 4.0 * inc.dot(wm);
        let pdf = vndf_pdf * lum / jac;
        if pdf.is_finite() && pdf > 0.0 {
            pdf
        } else {
            0.0
        }
    }

    /// Draws an outgoing direction for the tensor-incident direction `inc` with the
    /// measurement's sampler; returns it with its solid-angle density.
    pub fn tensor_sample(&self, inc: DVec3, u: glam::DVec2) -> Option<(DVec3, f64)> {
        let inc = geometry::normalize(inc)?;
        if inc.z <= 0.0 {
            return None;
        }
        let signs = self.reduction_signs(inc);
        let inc = Self::flip(inc, signs);
        let theta_i = elevation(inc);
        let phi_i = inc.y.atan2(inc.x);
        let k = self.corners(phi_i, theta_i);
        let (sample, lum_pdf) = match &self.luminance {
            Some(l) => l.sample([u.y, u.x], &k),
            None => ([u.y, u.x], 1.0),
        };
        let (u_m, ndf_pdf) = self.vndf.sample(sample, &k);
        let theta_m = u_m[0] * u_m[0] * FRAC_PI_2;
        let mut phi_m = (2.0 * u_m[1] - 1.0) * PI;
        if self.isotropic {
            phi_m += phi_i;
        }
        let m = geometry::spherical(theta_m, phi_m);
        let jac = (2.0 * PI * PI * u_m[0] * theta_m.sin()).max(1e-6) * 4.0 * inc.dot(m);
        let out = geometry::reflect(inc, m);
        let pdf = ndf_pdf * lum_pdf / jac;
        if out.z <= 0.0 || !(pdf.is_finite() && pdf > 0.0) {
            return None;
        }
        Some((Self::flip(out, signs), pdf))
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
