//! Slice images of any BRDF: the MERL-style θh × θd image and the polar plot of f_r · cos θo.
//!
//! - [`halfdiff`]: f_r over θh (x, 0..90° left to right) × θd (y, 0..90° top to bottom) at a fixed
//!   φd (90° by default) — the standard view of isotropic measured data (Burley 2012): the
//!   specular peak is the left column, Fresnel grazing effects the bottom rows, retro-reflection
//!   the bottom-left corner.
//! - [`polar`]: f_r · cos θo over the outgoing hemisphere for one incident direction, in the
//!   azimuthal-equidistant projection (radius ∝ θo, angle = φo; +x to the right, +y up). Pixels
//!   outside the disk are NaN in the data, transparent black in PNGs.
//!
//! Images are linear f32 with one value per BRDF channel ([`SliceImage`]). [`write_exr`] writes
//! them as they are; [`write_png`] tone-maps one channel on a log scale through a viridis
//! colormap and appends a colorbar (bottom = min, top = max), returning the value range so the
//! caller can print a legend line.

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

use glam::DVec3;
use rayon::prelude::*;

use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::geometry;
use crate::spectrum::{Channels, MAX_CHANNELS};

/// A linear image: `width × height` pixels of `channels` f32 each, row-major from the top.
#[derive(Debug, Clone, PartialEq)]
pub struct SliceImage {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Channels per pixel (the BRDF's channel count).
    pub channels: usize,
    /// Names of the channels (`R G B` or wavelengths).
    pub channel_names: Vec<String>,
    /// `height × width × channels` values; NaN marks pixels outside the domain.
    pub data: Vec<f32>,
}

impl SliceImage {
    /// The value of channel `c` at pixel (x, y).
    pub fn get(&self, x: usize, y: usize, c: usize) -> f32 {
        self.data[(y * self.width + x) * self.channels + c]
    }

    /// One scalar per pixel: channel `c`, or (for `None`) luminance Y of RGB
    /// (0.2126 R + 0.7152 G + 0.0722 B), or the channel mean for spectral data.
    pub fn scalar(&self, channel: Option<usize>, rgb: bool) -> Vec<f32> {
        self.data
            .chunks_exact(self.channels)
            .map(|p| match channel {
                Some(c) => p[c],
                None if rgb && self.channels == 3 => 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2],
                None => p.iter().sum::<f32>() / p.len() as f32,
            })
            .collect()
    }
}

fn render(
    brdf: &dyn Brdf,
    width: usize,
    height: usize,
    pair: impl Fn(usize, usize) -> Option<(DVec3, DVec3, f64)> + Sync,
) -> SliceImage {
    let c = brdf.channels().len().min(MAX_CHANNELS);
    let mut data = vec![0.0f32; width * height * c];
    data.par_chunks_mut(width * c)
        .enumerate()
        .for_each(|(y, row)| {
            let mut f = [0.0f32; MAX_CHANNELS];
            for x in 0..width {
                let px = &mut row[x * c..(x + 1) * c];
                match pair(x, y) {
                    Some((wi, wo, w)) => {
                        brdf.eval(wi, wo, &mut f[..c]);
                        for k in 0..c {
                            px[k] = (f[k] as f64 * w) as f32;
                        }
                    }
                    None => px.fill(f32::NAN),
                }
            }
        });
    SliceImage {
        width,
        height,
        channels: c,
        channel_names: brdf.channels().names(),
        data,
    }
}

/// f_r over θh (x) × θd (y) at azimuth difference `phi_d` (radians), `size × size` pixels at
/// pixel centres, angles linear in 0..90°.
pub fn halfdiff(brdf: &dyn Brdf, size: usize, phi_d: f64) -> SliceImage {
    render(brdf, size, size, |x, y| {
        let theta_h = (x as f64 + 0.5) / size as f64 * FRAC_PI_2;
        let theta_d = (y as f64 + 0.5) / size as f64 * FRAC_PI_2;
        let (wi, wo) = geometry::from_half_diff(geometry::HalfDiff {
            theta_h,
            phi_h: 0.0,
            theta_d,
            phi_d,
        });
        // Pairs with a direction below the horizon are outside the domain.
        (wi.z > 0.0 && wo.z > 0.0).then_some((wi, wo, 1.0))
    })
}

/// f_r · cos θo over the outgoing hemisphere for incident direction `wi`, `size × size` pixels,
/// azimuthal-equidistant projection (see the module docs).
pub fn polar(brdf: &dyn Brdf, size: usize, wi: DVec3) -> SliceImage {
    render(brdf, size, size, |x, y| {
        let u = 2.0 * (x as f64 + 0.5) / size as f64 - 1.0;
        let v = 1.0 - 2.0 * (y as f64 + 0.5) / size as f64;
        let r = (u * u + v * v).sqrt();
        if r >= 1.0 {
            return None;
        }
        let wo = geometry::spherical(r * FRAC_PI_2, v.atan2(u));
        Some((wi, wo, wo.z))
    })
}

/// Writes an image as an OpenEXR file of linear f32 RGB: RGB images as they are; other channel
/// counts write `channel` (or the mean of the channels) as grey. NaN pixels become 0.
pub fn write_exr(img: &SliceImage, channel: Option<usize>, path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    let grey = (img.channels != 3 || channel.is_some()).then(|| img.scalar(channel, false));
    let fin = |v: f32| if v.is_finite() { v } else { 0.0 };
    exr::prelude::write_rgb_file(path, img.width, img.height, |x, y| {
        if let Some(g) = &grey {
            let v = fin(g[y * img.width + x]);
            (v, v, v)
        } else {
            let p = (y * img.width + x) * 3;
            (fin(img.data[p]), fin(img.data[p + 1]), fin(img.data[p + 2]))
        }
    })
    .map_err(|e| Error::Io {
        context: path.display().to_string(),
        source: std::io::Error::other(e.to_string()),
    })
}

/// The value range a PNG's colors span (for a legend line).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Legend {
    /// Value at the bottom of the colorbar (darkest color).
    pub min: f32,
    /// Value at the top of the colorbar (brightest color).
    pub max: f32,
}

/// Viridis, polynomial approximation (t in [0, 1]).
pub fn viridis(t: f64) -> [u8; 3] {
    const C: [[f64; 3]; 7] = [
        [
            0.277_727_327_223_417_7,
            0.005_407_344_544_966_578,
            0.334_099_805_335_306_1,
        ],
        [
            0.105_093_043_108_577_4,
            1.404_613_529_898_575,
            1.384_590_162_594_685,
        ],
        [
            -0.330_861_828_725_556_3,
            0.214_847_559_468_213,
            0.095_095_163_028_236_59,
        ],
        [
            -4.634_230_498_983_486,
            -5.799_100_973_351_585,
            -19.332_440_956_279_87,
        ],
        [
            6.228_269_936_347_081,
            14.179_933_366_805_09,
            56.690_552_600_681_05,
        ],
        [
            4.776_384_997_670_288,
            -13.745_145_377_746_01,
            -65.353_032_633_372_34,
        ],
        [
            -5.435_455_855_934_631,
            4.645_852_612_178_535,
            26.312_435_249_583_2,
        ],
    ];
    let t = t.clamp(0.0, 1.0);
    let mut rgb = [0u8; 3];
    for (k, out) in rgb.iter_mut().enumerate() {
        let mut v = C[6][k];
        for i in (0..6).rev() {
            v = v * t + C[i][k];
        }
        *out = (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    }
    rgb
}

/// Writes one channel (or luminance) as a tone-mapped PNG: log10 scale between the largest
/// value and max(smallest positive value, largest / 10⁶), viridis colors, a colorbar on the right.
/// Returns the range for a legend line.
pub fn write_png(
    img: &SliceImage,
    channel: Option<usize>,
    path: impl AsRef<Path>,
) -> Result<Legend> {
    let path = path.as_ref();
    let rgb = img.channel_names == Channels::Rgb.names();
    let vals = img.scalar(channel, rgb);
    let max = vals
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f32, f32::max);
    let min_pos = vals
        .iter()
        .copied()
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold(f32::INFINITY, f32::min);
    let (lo, hi) = if max > 0.0 {
        (min_pos.max(max * 1e-6), max)
    } else {
        (0.0, 0.0)
    };
    let t_of = |v: f32| -> f64 {
        if hi <= 0.0 || hi <= lo {
            return if v > 0.0 { 1.0 } else { 0.0 };
        }
        if v <= lo {
            return 0.0;
        }
        ((v as f64).log10() - (lo as f64).log10()) / ((hi as f64).log10() - (lo as f64).log10())
    };
    let bar_gap = (img.width / 32).max(2);
    let bar_w = (img.width / 16).max(4);
    let w = img.width + bar_gap + bar_w;
    let h = img.height;
    let mut px = vec![0u8; w * h * 4];
    for y in 0..h {
        for x in 0..img.width {
            let v = vals[y * img.width + x];
            let o = (y * w + x) * 4;
            if v.is_finite() {
                let c = viridis(t_of(v));
                px[o..o + 3].copy_from_slice(&c);
                px[o + 3] = 255;
            }
        }
        let t = 1.0 - (y as f64 + 0.5) / h as f64;
        let c = viridis(t);
        for x in img.width + bar_gap..w {
            let o = (y * w + x) * 4;
            px[o..o + 3].copy_from_slice(&c);
            px[o + 3] = 255;
        }
    }
    let file = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w as u32, h as u32);
    enc.set_color(png::ColorType::Rgba);
    enc.set_depth(png::BitDepth::Eight);
    let io = |e: png::EncodingError| Error::Io {
        context: path.display().to_string(),
        source: std::io::Error::other(e.to_string()),
    };
    let mut wr = enc.write_header().map_err(io)?;
    wr.write_image_data(&px).map_err(io)?;
    wr.finish().map_err(io)?;
    Ok(Legend { min: lo, max: hi })
}

/// The incident direction of polar angle `theta` and azimuth `phi` (radians); a convenience for
/// callers that take degrees at the edge.
pub fn incident(theta: f64, phi: f64) -> DVec3 {
    geometry::spherical(theta.clamp(0.0, FRAC_PI_2), phi.rem_euclid(2.0 * PI))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::lambert::Lambert;
    use crate::spectrum::Value;

    #[test]
    fn lambert_slices() {
        let l = Lambert::new(Value::Grey(0.5), &Channels::Rgb).unwrap();
        let img = halfdiff(&l, 16, FRAC_PI_2);
        // θh + θd ≥ 90° puts a direction below the horizon (at φd = 90° only when both large).
        assert_eq!(img.get(0, 0, 0), 0.5);
        let p = polar(&l, 33, DVec3::Z);
        assert!((p.get(16, 16, 1) - 0.5).abs() < 1e-6); // centre: cos θo = 1
        assert!(p.get(0, 0, 0).is_nan()); // corner: outside the disk
        let x = p.get(24, 16, 0) as f64; // θo = (8/16.5)·90°
        let theta = (8.0 / 16.5) * FRAC_PI_2;
        assert!((x - 0.5 * theta.cos()).abs() < 1e-6, "{x}");
    }

    #[test]
    fn viridis_ends() {
        // The polynomial fit is within a few levels of matplotlib's table.
        let close = |a: [u8; 3], b: [u8; 3]| a.iter().zip(b).all(|(x, y)| x.abs_diff(y) <= 4);
        assert!(close(viridis(0.0), [68, 1, 84]), "{:?}", viridis(0.0));
        assert!(close(viridis(1.0), [253, 231, 37]), "{:?}", viridis(1.0));
        assert!(close(viridis(0.5), [33, 145, 140]), "{:?}", viridis(0.5));
    }
}
