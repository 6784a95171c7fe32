//! How sharp a source's specular peak is at normal incidence, seen by the table sampler's
//! half-vector map: [`pole_share`], the share of the normal view's f_r cos θi that falls within
//! the map's first few θh cells.
//!
//! Why a module of its own: the sampler's resolution ([`super::SamplingResolution::for_source`])
//! and `info`'s report of its bytes must take the same decision from the same probe. A lobe a
//! tenth of a degree wide (GGX α = 0.002) lies within the first two cells of the default 64 θh
//! nodes, where the bilinear density cannot follow it: its weights' coefficient of variation was
//! 0.85. Such sources get twice the θh nodes.

use glam::DVec3;

use crate::brdf::Brdf;
use crate::spectrum::MAX_CHANNELS;

/// The share of the normal view's target density g(s) = f_r cos θi · 4 (ωo·h) · |dωh/d(s, y)|
/// (channel mean, along one azimuth of h: the view is the normal, so every azimuth of an
/// isotropic source is alike) that lies in s ∈ [0, `cells`/(`nodes` − 1)], integrated by the
/// trapezoid rule over the `nodes` nodes of the sampler's θh map `theta_of_s`. 0 when the
/// density is nowhere positive and finite.
pub(crate) fn pole_share(
    brdf: &dyn Brdf,
    nodes: usize,
    cells: usize,
    theta_of_s: impl Fn(f64) -> f64,
    jacobian: impl Fn(f64, f64) -> f64,
) -> f64 {
    let c = brdf.channels().len().clamp(1, MAX_CHANNELS);
    let mut f = [0.0f32; MAX_CHANNELS];
    let wo = DVec3::Z;
    let n = nodes.max(2);
    let g = |k: usize| {
        let s = k as f64 / (n - 1) as f64;
        let th = theta_of_s(s);
        let h = DVec3::new(th.sin(), 0.0, th.cos());
        let dot = wo.dot(h);
        let wi = 2.0 * dot * h - wo;
        if wi.z <= 0.0 {
            return 0.0;
        }
        brdf.eval(wi, wo, &mut f[..c]);
        let fr = f[..c].iter().map(|&x| x as f64).sum::<f64>() / c as f64;
        let v = fr * wi.z * 4.0 * dot * jacobian(s, th.sin());
        if v.is_finite() && v > 0.0 { v } else { 0.0 }
    };
    let gs: Vec<f64> = (0..n).map(g).collect();
    let cell = |k: usize| 0.5 * (gs[k] + gs[k + 1]);
    let total: f64 = (0..n - 1).map(cell).sum();
    if !(total > 0.0 && total.is_finite()) {
        return 0.0;
    }
    (0..cells.min(n - 1)).map(cell).sum::<f64>() / total
}
