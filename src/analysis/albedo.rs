//! Directional albedo by numerical quadrature.
//!
//! a(wi) = ∫ f_r(wi, wo) cos θo dωo over the upper hemisphere.

use glam::DVec3;
use std::f64::consts::PI;

use crate::brdf::Brdf;
use crate::geometry;
use crate::spectrum::MAX_CHANNELS;

/// Directional albedo of `brdf` for incident direction `wi`, every channel into `out`.
///
/// Gauss-Legendre in cos θo (exact for polynomial integrands in cos θ) times the midpoint rule in
/// φ (spectrally accurate for smooth periodic integrands).
pub fn quadrature<B: Brdf + ?Sized>(brdf: &B, wi: DVec3, out: &mut [f64]) {
    let c = brdf.channels().len().min(MAX_CHANNELS);
    out[..c].fill(0.0);
    let Some(wi) = geometry::normalize(wi) else {
        return;
    };
    if wi.z <= 0.0 {
        return;
    }
    let (nodes, weights) = gauss_legendre(64);
    let nphi = 128;
    let mut f = [0.0f32; MAX_CHANNELS];
    for (x, w) in nodes.iter().zip(&weights) {
        // Map [-1, 1] to cos θ in [0, 1].
        let mu = 0.5 * (x + 1.0);
        let wmu = 0.5 * w;
        let s = (1.0 - mu * mu).max(0.0).sqrt();
        for j in 0..nphi {
            let phi = 2.0 * PI * (j as f64 + 0.5) / nphi as f64;
            let wo = DVec3::new(s * phi.cos(), s * phi.sin(), mu);
            brdf.eval(wi, wo, &mut f[..c]);
            let wt = wmu * mu * 2.0 * PI / nphi as f64;
            for k in 0..c {
                out[k] += wt * f[k] as f64;
            }
        }
    }
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton iteration on the Legendre polynomial).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, 0.0);
            for j in 0..n {
                let p2 = p1;
                p1 = p0;
                p0 = ((2 * j + 1) as f64 * z * p1 - j as f64 * p2) / (j + 1) as f64;
            }
            dp = n as f64 * (z * p0 - p1) / (z * z - 1.0);
            let z1 = z;
            z = z1 - p0 / dp;
            if (z - z1).abs() < 1e-15 {
                break;
            }
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
        w[n - 1 - i] = w[i];
    }
    (x, w)
}
