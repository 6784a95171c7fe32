//! The two warps of a `.bsdf` file: the visible-normal distribution per incident direction
//! (`vndf`), and the luminance of the stored values (`luminance`) that readers importance-sample
//! the VNDF warp's input square by.
//!
//! `vndf` slice (φi, θi) holds, at node (u, v) of the (θ, φ) unit square of the half vector m
//! (θm = u²π/2, φm = 2πv − π, relative to φi for isotropic files),
//!
//! ```text
//! D(m) · max(0, m·ωi) · 2π² u sin θm        (the visible normals, per unit area of the square)
//! ```
//!
//! Readers normalize each slice themselves, so the σ(ωi) divisor is left out. The warp that
//! the readers build from it is built here with their own code (`rgl::Warp`), so that the
//! positions [`values`](super::values) samples at are the readers' positions.

use std::f64::consts::{FRAC_PI_2, PI};

use super::ndf::{Ndf, luminance_weights};
use super::{Layout, Values};
use crate::error::{Error, Result};
use crate::geometry;
use crate::measured::rgl::{Planes, Warp};
use crate::spectrum::Channels;

/// The VNDF slices and the warps built from them.
#[derive(Debug, Clone)]
pub struct Vndf {
    /// Rows and columns of one slice.
    pub shape: [usize; 2],
    /// The densities, φi × θi × n × n.
    pub data: Vec<f32>,
    pub(crate) warps: Vec<Warp>,
}

/// The incident direction of slice (`p`, `t`).
pub fn incident(layout: &Layout, p: usize, t: usize) -> glam::DVec3 {
    geometry::spherical(layout.theta_i[t] as f64, layout.phi_i[p] as f64)
}

/// Builds every VNDF slice of `layout` from the recovered distribution.
pub fn vndf(ndf: &Ndf, layout: &Layout) -> Result<Vndf> {
    let [n, _] = layout.vndf;
    let (np, nt) = (layout.phi_i.len(), layout.theta_i.len());
    let mut data = vec![0.0f32; np * nt * n * n];
    for p in 0..np {
        for t in 0..nt {
            let wi = incident(layout, p, t);
            let phi_i = if layout.isotropic {
                layout.phi_i[p] as f64
            } else {
                0.0
            };
            let s = p * nt + t;
            let slice = &mut data[s * n * n..(s + 1) * n * n];
            for y in 0..n {
                let v = y as f64 / (n - 1) as f64;
                for x in 0..n {
                    let u = x as f64 / (n - 1) as f64;
                    let theta_m = u * u * FRAC_PI_2;
                    let m = geometry::spherical(theta_m, 2.0 * PI * v - PI + phi_i);
                    let vis = ndf.d([u, v]) * m.dot(wi).max(0.0);
                    slice[x + y * n] = (vis * 2.0 * PI * PI * u * theta_m.sin()) as f32;
                }
            }
        }
    }
    with_warps(data, layout)
}

/// The VNDF slices of an existing parameterization.
pub fn given(p: &super::Parameterization, layout: &Layout) -> Result<Vndf> {
    with_warps(p.vndf.clone(), layout)
}

/// Builds the readers' warp of every slice of `data` (φi × θi × rows × columns).
pub fn with_warps(data: Vec<f32>, layout: &Layout) -> Result<Vndf> {
    let [ny, nx] = layout.vndf;
    let plane = nx * ny;
    let nt = layout.theta_i.len();
    let warps = data
        .chunks_exact(plane)
        .enumerate()
        .map(|(s, slice)| {
            Warp::build(Planes {
                nx,
                ny,
                data: slice.to_vec(),
            })
            .map_err(|(_, total)| {
                Error::arg(
                    "source",
                    format!(
                        "the visible-normal density for θi = {:.2}° integrates to {total}",
                        (layout.theta_i[s % nt] as f64).to_degrees()
                    ),
                )
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Vndf {
        shape: layout.vndf,
        data,
        warps,
    })
}

/// The `luminance` field: per sample, the luminance of the stored values (clipped at 0). A slice
/// that is 0 everywhere is stored as 1 everywhere (uniform sampling), which keeps it a density.
pub fn luminance(values: &Values, channels: &Channels, layout: &Layout) -> Vec<f32> {
    let wts = luminance_weights(channels);
    let c = wts.len();
    let plane = layout.n * layout.n;
    let slices = layout.phi_i.len() * layout.theta_i.len();
    let mut out = vec![0.0f32; slices * plane];
    for s in 0..slices {
        let src = &values.data[s * c * plane..(s + 1) * c * plane];
        let dst = &mut out[s * plane..(s + 1) * plane];
        for (k, d) in dst.iter_mut().enumerate() {
            let y: f64 = (0..c)
                .map(|ch| wts[ch] * (src[ch * plane + k] as f64).max(0.0))
                .sum();
            *d = y as f32;
        }
        if dst.iter().all(|&v| v <= 0.0) {
            dst.fill(1.0);
        }
    }
    out
}
