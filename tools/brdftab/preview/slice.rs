//! Slice images of any BRDF: the MERL-style θh × θd image and the polar plot of f_r · cos θo.
//!
//! - [`halfdiff`]: f_r over θh (x, 0..90° left to right) × θd (y, 0..90° top to bottom) at a fixed
//!   φd (90° by default) — the standard view of isotropic measured data (Burley 2012): the
//!   specular peak is the left column, Fresnel grazing effects the bottom rows, retro-reflection
//!   the bottom-left corner.
//! - [`polar`]: f_r · cos θo over the outgoing hemisphere for one incident direction, in the
//!   azimuthal-equidistant projection (radius ∝ θo, angle = φo; +x to the right, +y up). Pixels
//!   outside the disk are NaN in the data and the darkest colour in PNGs.
//!
//! Images are [`render::image::Image`](crate::preview::image::Image)s: linear f32, one channel per
//! BRDF channel, named after them. [`write()`] stores them as EXR (as they are) or as PNG (one
//! channel or the luminance, log scale through viridis with a colorbar strip below, via
//! [`false_color`](crate::preview::image::false_color)) and returns the legend line.

use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

use glam::DVec3;
use rayon::prelude::*;

use crate::preview::image::{self, ExrPrecision, FalseColor, Image};
use brdftab::brdf::Brdf;
use brdftab::error::{Error, Result};
use brdftab::geometry;
use brdftab::spectrum::MAX_CHANNELS;

fn render(
    brdf: &dyn Brdf,
    width: usize,
    height: usize,
    pair: impl Fn(usize, usize) -> Option<(DVec3, DVec3, f64)> + Sync,
) -> Image {
    let c = brdf.channels().len().min(MAX_CHANNELS);
    let mut data = vec![0.0f32; width * height * c];
    brdftab::par::install(|| {
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
            })
    });
    Image {
        width,
        height,
        channels: c,
        names: brdf.channels().names(),
        data,
    }
}

/// f_r over θh (x) × θd (y) at azimuth difference `phi_d` (radians) and half-vector azimuth
/// φh = 0 (all one for an isotropic BRDF), `size × size` pixels at pixel centres, angles linear
/// in 0..90°.
pub fn halfdiff(brdf: &dyn Brdf, size: usize, phi_d: f64) -> Image {
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
pub fn polar(brdf: &dyn Brdf, size: usize, wi: DVec3) -> Image {
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

/// One scalar per pixel as a 1-channel image: channel `c`, or (for `None`) the luminance of RGB
/// images and the channel mean of others.
pub fn scalar(img: &Image, channel: Option<usize>) -> Image {
    let rgb = img.names == ["R", "G", "B"];
    let data = img
        .data
        .chunks_exact(img.channels.max(1))
        .map(|p| match channel {
            Some(c) => p[c.min(p.len() - 1)],
            None if rgb => image::luminance_of(p),
            None => p.iter().sum::<f32>() / p.len() as f32,
        })
        .collect();
    Image {
        width: img.width,
        height: img.height,
        channels: 1,
        names: vec![match channel {
            Some(c) => img.names.get(c).cloned().unwrap_or_default(),
            None if rgb => "Y".into(),
            None => "mean".into(),
        }],
        data,
    }
}

/// Writes a slice by extension: `.exr` — linear f32, every channel (or only `channel`);
/// `.png` — `channel` (default luminance / channel mean) on a log10 scale through viridis with a
/// colorbar strip below (low end left). Returns a legend line describing the mapping.
pub fn write(img: &Image, channel: Option<usize>, path: impl AsRef<Path>) -> Result<String> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "exr" => {
            let one;
            let out = match channel {
                Some(_) => {
                    one = scalar(img, channel);
                    &one
                }
                None => img,
            };
            image::write_exr(out, path, ExrPrecision::F32)?;
            Ok(format!("linear f32, channels {}", out.names.join(" ")))
        }
        "png" => {
            let one = scalar(img, channel);
            let (fc, legend) = image::false_color(&one, &FalseColor::default());
            image::write_png(&fc, path, 0.0)?;
            Ok(format!("{}, {legend}", one.names[0]))
        }
        _ => Err(Error::arg("output", "must end in .exr or .png")),
    }
}

/// The incident direction of polar angle `theta` and azimuth `phi` (radians); a convenience for
/// callers that take degrees at the edge. `theta` outside [0, π/2) is an argument error (it
/// was clamped into [0, π/2], so `--theta-in 120` drew the grazing slice without a word).
pub fn incident(theta: f64, phi: f64) -> brdftab::Result<DVec3> {
    if !(0.0..FRAC_PI_2).contains(&theta) {
        return Err(brdftab::Error::arg(
            "theta",
            format!("{theta} is outside [0, π/2) (radians): the light must be above the horizon"),
        ));
    }
    Ok(geometry::spherical(theta, phi.rem_euclid(2.0 * PI)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdftab::models::lambert::Lambert;
    use brdftab::spectrum::{Channels, Value};

    #[test]
    fn lambert_slices() {
        let l = Lambert::new(Value::Grey(0.5), &Channels::Rgb).unwrap();
        let img = halfdiff(&l, 16, FRAC_PI_2);
        // θh + θd ≥ 90° puts a direction below the horizon (at φd = 90° only when both large).
        assert_eq!(img.pixel(0, 0)[0], 0.5);
        let p = polar(&l, 33, DVec3::Z);
        assert!((p.pixel(16, 16)[1] - 0.5).abs() < 1e-6); // centre: cos θo = 1
        assert!(p.pixel(0, 0)[0].is_nan()); // corner: outside the disk
        let x = p.pixel(24, 16)[0] as f64; // θo = (8/16.5)·90°
        let theta = (8.0 / 16.5) * FRAC_PI_2;
        assert!((x - 0.5 * theta.cos()).abs() < 1e-6, "{x}");
    }

    #[test]
    fn writes_exr_and_png() {
        let l = Lambert::new(Value::Rgb([0.1, 0.2, 0.3]), &Channels::Rgb).unwrap();
        let img = polar(&l, 16, DVec3::Z);
        let dir = brdftab::testkit::TempDir::new("slice");
        let legend = write(&img, None, dir.join("a.png")).unwrap();
        assert!(legend.contains("log10"), "{legend}");
        write(&img, None, dir.join("a.exr")).unwrap();
        let back = image::read_exr(dir.join("a.exr")).unwrap();
        assert_eq!(back.channels, 3);
        assert_eq!(back.pixel(8, 8), img.pixel(8, 8));
        write(&img, Some(2), dir.join("b.exr")).unwrap();
        assert_eq!(image::read_exr(dir.join("b.exr")).unwrap().channels, 1);
        assert!(write(&img, None, dir.join("a.tiff")).is_err());
    }
}
