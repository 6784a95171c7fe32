//! The numbers behind each view, computed from any `&dyn Brdf` in one batched evaluation each.
//!
//! Angles arrive in degrees (the page's units) and are turned into directions here; every
//! result is plain arrays the page draws. What one curve or one surface shows, `y`, is the
//! [`Channel`] the page asks for: the luminance (Rec. 709 weights of linear sRGB) or one of the
//! linear sRGB components; the per-channel values ride along where the page can use them. A spectral material is seen as a spectral renderer shows it: its channels'
//! spectrum projected to linear sRGB ([`brdftab::colour::srgb_weights`]), so its sphere has its
//! colour and its luminance is the photometric one (CIE ȳ), not the channels' plain mean.
//!
//! Every sweep samples the centres of equal cells (`centre`), as the library's tables and
//! `brdftab slice` do, so no direction lies at the horizon: there cos θ is 6e-17 and a measured
//! file's f_r (its stored f_r cos θ over cos θ) reaches 1e14, which is the data's limit, not a
//! value a plot can show.

use brdftab::Brdf;
use brdftab::analysis::albedo::albedo_curve_at;
use brdftab::geometry::{self, HalfDiff};
use brdftab::spectrum::Channels;
use glam::DVec3;
use rayon::prelude::*;

use crate::preview::image::to_srgb8;
use serde_json::{Value, json};

/// f_r of every pair (`wi[k]`, `wo[k]`), channel-interleaved; non-finite values become 0.
fn eval_pairs(brdf: &dyn Brdf, wi: &[DVec3], wo: &[DVec3]) -> Vec<f32> {
    let mut out = vec![0.0f32; wi.len() * brdf.channels().len()];
    brdf.eval_batch(wi, wo, &mut out);
    for x in &mut out {
        if !x.is_finite() {
            *x = 0.0;
        }
    }
    out
}

/// What a curve or surface of a view shows of a material's colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Channel {
    /// The luminance Y.
    #[default]
    Y,
    /// The linear sRGB red component (a spectrum's projection, unclipped).
    R,
    /// The linear sRGB green component.
    G,
    /// The linear sRGB blue component.
    B,
}

impl Channel {
    /// `y`, `r`, `g` or `b`.
    pub fn parse(s: &str) -> Option<Channel> {
        match s {
            "y" => Some(Channel::Y),
            "r" => Some(Channel::R),
            "g" => Some(Channel::G),
            "b" => Some(Channel::B),
            _ => None,
        }
    }

    /// Its name in a request and a cache key.
    pub fn name(self) -> &'static str {
        ["y", "r", "g", "b"][self as usize]
    }
}

/// How a material's channels are seen: linear sRGB as they are, or a spectrum's projection.
struct Seen {
    /// Wavelength channels: each channel's weight in R, G, B.
    weights: Option<Vec<[f64; 3]>>,
}

impl Seen {
    fn new(channels: &Channels) -> Self {
        Seen {
            weights: match channels {
                Channels::Rgb => None,
                Channels::Wavelengths(nm) => Some(brdftab::colour::srgb_weights(nm)),
            },
        }
    }

    /// Linear sRGB of one pair's channels, unclipped.
    fn project(&self, f: &[f32]) -> [f64; 3] {
        match (&self.weights, f) {
            (None, [r, g, b]) => [*r as f64, *g as f64, *b as f64],
            (None, _) => [0.0; 3],
            (Some(w), _) => {
                let mut c = [0f64; 3];
                for (wk, &x) in w.iter().zip(f) {
                    for (ci, wc) in c.iter_mut().zip(wk) {
                        *ci += wc * x as f64;
                    }
                }
                c
            }
        }
    }

    /// Linear sRGB for display (a spectrum's projection may leave the gamut: negative
    /// components are clipped).
    fn rgb(&self, f: &[f32]) -> [f32; 3] {
        self.project(f).map(|v| v.max(0.0) as f32)
    }

    /// Channel `ch` of the unclipped linear sRGB; the luminance is its Y (Rec. 709 weights;
    /// for a spectrum, the photometric luminance).
    fn component(&self, f: &[f32], ch: Channel) -> f32 {
        let c = self.project(f);
        match ch {
            Channel::Y => (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]) as f32,
            Channel::R => c[0] as f32,
            Channel::G => c[1] as f32,
            Channel::B => c[2] as f32,
        }
    }
}

/// Channel `ch` of each pair of an interleaved result.
fn components(brdf: &dyn Brdf, f: &[f32], ch: Channel) -> Vec<f32> {
    let c = brdf.channels().len().max(1);
    let seen = Seen::new(brdf.channels());
    f.chunks(c).map(|p| seen.component(p, ch)).collect()
}

/// The centre of cell `k` of `n` equal cells over [`lo`, `hi`].
fn centre(k: usize, n: usize, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * (k as f64 + 0.5) / n as f64
}

/// The in-plane polar curve in the plane of incidence at azimuth φi (`phi_i_deg`, from the
/// local x axis, along which an anisotropic model's α_x runs): light at θi on the far side of
/// the normal (azimuth φi + 180°), the viewer at the centres of `n` cells of θo ∈ [−90°, 90°] in
/// that plane, positive θo towards the mirror direction (azimuth φi). φi = 0 is the x–z plane
/// with the light on the −x side. The answer carries `phi_i` and the material's `isotropic`
/// flag (φi changes nothing for an isotropic material but the directions' rounding).
pub fn polar(brdf: &dyn Brdf, theta_i_deg: f64, phi_i_deg: f64, n: usize, ch: Channel) -> Value {
    let phi = phi_i_deg.to_radians();
    // `phi + PI` and `phi + 0.0`: at φi = 0 the very directions of the x–z plane.
    let wi = geometry::spherical(theta_i_deg.to_radians(), phi + std::f64::consts::PI);
    let thetas: Vec<f64> = (0..n).map(|k| centre(k, n, -90.0, 90.0)).collect();
    let wo: Vec<DVec3> = thetas
        .iter()
        .map(|t| {
            let side = if *t < 0.0 { std::f64::consts::PI } else { 0.0 };
            geometry::spherical(t.abs().to_radians(), phi + side)
        })
        .collect();
    let f = eval_pairs(brdf, &vec![wi; n], &wo);
    let c = brdf.channels().len().max(1);
    let per_channel: Vec<Vec<f32>> = (0..c)
        .map(|ch| f.iter().skip(ch).step_by(c).copied().collect())
        .collect();
    json!({
        "theta_o": thetas, "phi_i": phi_i_deg, "y": components(brdf, &f, ch), "channel": ch.name(),
        "f": per_channel, "delta": has_delta(brdf), "isotropic": brdf.flags().isotropic,
    })
}

/// Whether `brdf` has a delta lobe (a mirror or refractor, alone or as a term of a sum): f_r
/// holds none of it, so no plot of f_r shows it, while the albedo counts it.
pub fn has_delta(brdf: &dyn Brdf) -> bool {
    let f = brdf.flags();
    f.delta || f.lobes.delta
}

/// The lobe for light at (θi, φi + 180°): channel `ch` of f_r over the outgoing hemisphere on
/// an `nt` × `np` grid of (θo at the centres of `nt` cells of [0°, 90°], φo = φi + 360° j / `np`),
/// row by row; `theta_o` lists the rows' angles. The columns start at the plane of incidence's
/// mirror side whatever φi (`phi_i`, in the answer, is where the page turns them to).
pub fn lobe(
    brdf: &dyn Brdf,
    theta_i_deg: f64,
    phi_i_deg: f64,
    nt: usize,
    np: usize,
    ch: Channel,
) -> Value {
    let phi = phi_i_deg.to_radians();
    let wi = geometry::spherical(theta_i_deg.to_radians(), phi + std::f64::consts::PI);
    let rows: Vec<f64> = (0..nt).map(|i| centre(i, nt, 0.0, 90.0)).collect();
    let mut wo = Vec::with_capacity(nt * np);
    for t in rows.iter().map(|t| t.to_radians()) {
        for j in 0..np {
            wo.push(geometry::spherical(
                t,
                phi + std::f64::consts::TAU * j as f64 / np as f64,
            ));
        }
    }
    let f = eval_pairs(brdf, &vec![wi; wo.len()], &wo);
    json!({ "nt": nt, "np": np, "theta_o": rows, "phi_i": phi_i_deg, "y": components(brdf, &f, ch), "channel": ch.name() })
}

/// The MERL-style θh × θd slice at φd = 90°: `n` × `n` values of channel `ch`, θh along rows' columns
/// (`y[d * n + h]`), both angles at the centres of `n` cells of [0°, 90°] (`theta`).
pub fn slice(brdf: &dyn Brdf, n: usize, ch: Channel) -> Value {
    let angles: Vec<f64> = (0..n).map(|k| centre(k, n, 0.0, 90.0)).collect();
    let mut wi = Vec::with_capacity(n * n);
    let mut wo = Vec::with_capacity(n * n);
    for d in 0..n {
        for h in 0..n {
            let (i, o) = geometry::from_half_diff(HalfDiff {
                theta_h: angles[h].to_radians(),
                phi_h: 0.0,
                theta_d: angles[d].to_radians(),
                phi_d: std::f64::consts::FRAC_PI_2,
            });
            wi.push(i);
            wo.push(o);
        }
    }
    let f = eval_pairs(brdf, &wi, &wo);
    json!({ "n": n, "theta": angles, "y": components(brdf, &f, ch), "channel": ch.name() })
}

/// A sphere seen from +z (orthographic) under a distant light from (θ, φ) measured from the view
/// axis: radiance f_r · cos θi · π (a white Lambertian surface shows its albedo), times
/// `exposure`, as `size` × `size` sRGB bytes (RGB, row by row; black off the sphere).
pub fn sphere(
    brdf: &dyn Brdf,
    light_theta_deg: f64,
    light_phi_deg: f64,
    size: usize,
    exposure: f64,
) -> Value {
    let light = geometry::spherical(light_theta_deg.to_radians(), light_phi_deg.to_radians());
    let view = DVec3::Z;
    let (mut wi, mut wo, mut pixels) = (Vec::new(), Vec::new(), Vec::new());
    for py in 0..size {
        for px in 0..size {
            let x = (px as f64 + 0.5) / size as f64 * 2.0 - 1.0;
            let y = 1.0 - (py as f64 + 0.5) / size as f64 * 2.0;
            let r2 = x * x + y * y;
            if r2 >= 1.0 {
                continue;
            }
            let n = DVec3::new(x, y, (1.0 - r2).sqrt());
            // The tangent follows the sphere's latitude (local x), so anisotropy shows as on a
            // turned object.
            let t = DVec3::Y.cross(n).try_normalize().unwrap_or(DVec3::X);
            let b = n.cross(t);
            let local = |d: DVec3| DVec3::new(d.dot(t), d.dot(b), d.dot(n));
            wi.push(local(light));
            wo.push(local(view));
            pixels.push(py * size + px);
        }
    }
    let f = eval_pairs(brdf, &wi, &wo);
    let c = brdf.channels().len().max(1);
    let seen = Seen::new(brdf.channels());
    let mut rgb = vec![0u8; size * size * 3];
    for (k, &p) in pixels.iter().enumerate() {
        let cos = wi[k].z.max(0.0) * std::f64::consts::PI * exposure;
        let v = &f[k * c..(k + 1) * c];
        let px = seen.rgb(v);
        for (ch, x) in px.iter().enumerate() {
            rgb[p * 3 + ch] = to_srgb8((*x as f64 * cos) as f32, 1.0);
        }
    }
    json!({ "size": size, "rgb": rgb })
}

/// The directional albedo at θ′ = 0°, 5°, ..., 85°, 89° per channel and its luminance, for
/// light at azimuth φi + 180° (as [`polar`] and [`lobe`] place it; the library's
/// [`albedo_curve_at`] names the light's own azimuth): the library's [`Brdf::albedo`], as
/// `brdftab albedo` gives it (closed forms where a model has one, delta lobes' reflectance, the
/// bounded quadrature of data). The answer carries `phi_i` and the `isotropic` flag.
pub fn albedo(brdf: &(dyn Brdf + Sync), phi_i_deg: f64, ch: Channel) -> Value {
    let light = phi_i_deg.to_radians() + std::f64::consts::PI;
    let mut deg: Vec<f64> = (0..18).map(|k| 5.0 * k as f64).collect();
    deg.push(89.0);
    let a: Vec<Vec<f64>> = brdftab::par::install(|| {
        deg.par_iter()
            .map(|d| {
                let rad = d.to_radians();
                albedo_curve_at(brdf, &[rad], light).map_or_else(|_| vec![], |mut c| c.remove(0))
            })
            .collect()
    });
    let seen = Seen::new(brdf.channels());
    let y: Vec<f64> = a
        .iter()
        .map(|row| {
            let f: Vec<f32> = row.iter().map(|&x| x as f32).collect();
            seen.component(&f, ch) as f64
        })
        .collect();
    json!({
        "theta": deg, "phi_i": phi_i_deg, "y": y, "a": a, "channel": ch.name(),
        "isotropic": brdf.flags().isotropic,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use brdftab::spec::ModelSpec;

    fn build(spec: &str, ch: &Channels) -> Box<dyn Brdf + Send + Sync> {
        ModelSpec::parse(spec).unwrap().build(ch).unwrap()
    }

    #[test]
    fn a_spectral_material_is_seen_in_its_colour() {
        // An RGB k_d on 10 nm channels (the RGB basis) and the RGB Lambertian: the same sphere
        // to an 8-bit code (the sampled basis's colour error is ≤ 0.5 %); it used to be grey.
        let spec = r#"{"model": "lambert", "kd": [0.25, 0.06, 0.02]}"#;
        let ch = Channels::linspace(360.0, 830.0, 48).unwrap();
        let (a, b) = (build(spec, &Channels::Rgb), build(spec, &ch));
        let (a, b) = (
            sphere(a.as_ref(), 30.0, 0.0, 16, 1.0),
            sphere(b.as_ref(), 30.0, 0.0, 16, 1.0),
        );
        let (a, b) = (a["rgb"].as_array().unwrap(), b["rgb"].as_array().unwrap());
        assert_eq!(a.len(), b.len());
        let worst = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x.as_i64().unwrap() - y.as_i64().unwrap()).abs())
            .max()
            .unwrap();
        assert!(worst <= 1, "{worst}");
        assert!(a.iter().any(|x| x.as_i64().unwrap() > 100));
        // A flat spectrum's luminance is its value (the photometric weights sum to 1).
        let grey = build(r#"{"model": "lambert", "kd": 0.2}"#, &ch);
        for y in polar(grey.as_ref(), 30.0, 0.0, 8, Channel::Y)["y"]
            .as_array()
            .unwrap()
        {
            assert!((y.as_f64().unwrap() - 0.2).abs() < 1e-6, "{y}");
        }
    }
}
