//! Opening an RGL `.bsdf` file: its fields checked and turned into the warps, tables and
//! channel maps that evaluation reads ([`RglBrdf::open`] and friends).

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

use super::{Planes, RglBrdf, Warp, spectral_mix};
use crate::error::{Error, Result};
use crate::measured::tensor::{Dtype, Field, TensorFile};
use crate::spectrum::{ChannelMix, Channels, MAX_CHANNELS};

/// [`Warp::build`] for a field of `file`, with the file in the error.
fn warp_of(planes: Planes, file: &TensorFile, field: &Field) -> Result<Warp> {
    Warp::build(planes).map_err(|(s, total)| {
        file.error(
            field,
            format!("slice {s} integrates to {total}, not a positive density"),
        )
    })
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

    pub(super) fn build(tf: &TensorFile, channels: Option<&Channels>, hash: bool) -> Result<Self> {
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
}
