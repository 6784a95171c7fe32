//! How well the table sampler's conditioning views serve the views between them:
//! [`predicted_cv`], the coefficient of variation the weights f_r cos θi / pdf would have at a
//! view, computed from the sampler's density rather than drawn, and [`worst_excess`], the
//! worst of it over the views midway between grazing nodes, against the sampler's bars.
//!
//! Why a module of its own: the sampler's resolution
//! ([`super::SamplingResolution::for_source`]) is chosen per source. A lobe of the Phong family
//! (cos^n of the angle to the mirror direction) seen from 85° is a thin crescent in the half
//! vector's (θh, φh) — about a degree across in θh, ten times that in φh — whose shape changes
//! by a factor of two between neighbouring conditioning views: the reciprocal Phong at n = 1000
//! sampled with a CV of 0.25 there on the default 32 views × 64 φh nodes, 0.11 on 48 × 96.
//! Smooth and half-vector lobes (measured files, GGX, Blinn-Phong) do not need the finer
//! views, and the bytes they cost; only the density of the sampler itself tells the two apart.
//!
//! The figure is exact up to the quadrature: with g = f_r cos θi (channel mean) and p the
//! sampler's normalized density of wi, the weights' CV² is ∫ g²/p dωi / (∫ g dωi)² − 1.
//! Both integrals run over the sampler's own half-vector square (midpoint rule on cells of
//! half the nodes' spacing), so a lobe the nodes resolve is resolved by the rule; against
//! 40 000 drawn samples per view it agrees within 0.01 (reciprocal Phong n = 1000 at 85°:
//! 0.249 against 0.255 drawn).

use glam::DVec3;
use std::f64::consts::{PI, TAU};

use crate::brdf::Brdf;
use crate::spectrum::MAX_CHANNELS;

/// Views probed by [`worst_excess`]: from this θo (degrees) ...
pub(crate) const PROBE_FROM_DEG: f64 = 60.0;
/// ... to this one, the last view the sampler's bars cover.
pub(crate) const PROBE_TO_DEG: f64 = 85.0;
/// Up to this θo the CV bar is [`CV_BAR_NEAR`], beyond it [`CV_BAR_GRAZING`] (issue 24's bars).
pub(crate) const NEAR_TO_DEG: f64 = 75.0;
/// The weights' CV bar at views up to [`NEAR_TO_DEG`].
pub(crate) const CV_BAR_NEAR: f64 = 0.10;
/// The weights' CV bar at views from [`NEAR_TO_DEG`] to [`PROBE_TO_DEG`].
pub(crate) const CV_BAR_GRAZING: f64 = 0.2;
/// The share of a bar a predicted CV may use: the rest covers the prediction's quadrature error
/// (within 0.01 of a drawn figure). 0.9 sent the native reader of `cc_ibiza_sunset` (0.086
/// predicted midway between the views at 74.4°, 0.062 drawn at 75°) to 2.25× the bytes.
pub(crate) const BAR_SHARE: f64 = 0.95;

/// The half-vector map the sampler draws with: θh of s, and |dωi / d(s, y)| / (4 (wo·h)) of
/// (s, sin θh).
pub(crate) struct HalfMap<'a> {
    /// θh of the square's first coordinate.
    pub theta_of_s: &'a dyn Fn(f64) -> f64,
    /// sin θh · dθh/ds · dφh/dy.
    pub jacobian: &'a dyn Fn(f64, f64) -> f64,
}

/// The CV of the weights f_r cos θi / `pdf`(wi, `wo`) (channel mean of f_r) for wi drawn from
/// `pdf` at the view `wo` (any azimuth: the rule covers every azimuth of h), integrated on `ns` × `ny` cells of
/// the half-vector square mapped by `map`. 0 when f_r cos θi is nowhere positive.
pub(crate) fn predicted_cv(
    brdf: &dyn Brdf,
    pdf: &dyn Fn(DVec3, DVec3) -> f64,
    map: &HalfMap,
    wo: DVec3,
    ns: usize,
    ny: usize,
) -> f64 {
    let c = brdf.channels().len().clamp(1, MAX_CHANNELS);
    let mut f = [0.0f32; MAX_CHANNELS];
    let (ns, ny) = (ns.max(1), ny.max(1));
    let cell = 1.0 / (ns * ny) as f64;
    let (mut first, mut second) = (0.0f64, 0.0f64);
    for ks in 0..ns {
        let s = (ks as f64 + 0.5) / ns as f64;
        let th = (map.theta_of_s)(s);
        let (st, ct) = th.sin_cos();
        let jac = (map.jacobian)(s, st);
        for ky in 0..ny {
            let phi = TAU * (ky as f64 + 0.5) / ny as f64 - PI;
            let (sp, cp) = phi.sin_cos();
            let h = DVec3::new(st * cp, st * sp, ct);
            let d = wo.dot(h);
            let wi = 2.0 * d * h - wo;
            if d <= 0.0 || wi.z <= 0.0 {
                continue;
            }
            brdf.eval(wi, wo, &mut f[..c]);
            let g = f[..c].iter().map(|&x| x as f64).sum::<f64>() / c as f64 * wi.z;
            if !(g > 0.0 && g.is_finite()) {
                continue;
            }
            let dw = 4.0 * d * jac * cell;
            let p = pdf(wi, wo);
            first += g * dw;
            second += if p > 0.0 {
                g * g / p * dw
            } else {
                f64::INFINITY
            };
        }
    }
    if !(first > 0.0 && first.is_finite()) {
        return 0.0;
    }
    (second / (first * first) - 1.0).max(0.0).sqrt()
}

/// The views [`worst_excess`] probes for `nt` conditioning nodes uniform in
/// t = √(1 − cos θo): the midpoints between neighbouring nodes with θo in
/// [[`PROBE_FROM_DEG`], [`PROBE_TO_DEG`]], and [`PROBE_TO_DEG`] itself (θo, radians).
pub(crate) fn probe_views(nt: usize) -> Vec<f64> {
    let (from, to) = (PROBE_FROM_DEG.to_radians(), PROBE_TO_DEG.to_radians());
    let mut v: Vec<f64> = (0..nt.saturating_sub(1))
        .map(|k| {
            let t = (k as f64 + 0.5) / (nt - 1) as f64;
            (1.0 - t * t).clamp(-1.0, 1.0).acos()
        })
        .filter(|&th| th >= from && th <= to)
        .collect();
    v.push(to);
    v
}

/// The worst over [`probe_views`] of the predicted CV ([`predicted_cv`], on cells of half the
/// node spacing of an `nx` × `ny` sampler) divided by [`BAR_SHARE`] × its bar: above 1, the
/// sampler is expected to miss a bar at some view between its nodes.
pub(crate) fn worst_excess(
    brdf: &dyn Brdf,
    pdf: &dyn Fn(DVec3, DVec3) -> f64,
    map: &HalfMap,
    nx: usize,
    ny: usize,
    nt: usize,
) -> f64 {
    let near = NEAR_TO_DEG.to_radians();
    probe_views(nt)
        .into_iter()
        .map(|th| {
            let wo = DVec3::new(th.sin(), 0.0, th.cos());
            let cells = |n: usize| 2 * (n.max(2) - 1);
            let cv = predicted_cv(brdf, pdf, map, wo, cells(nx), cells(ny));
            let bar = if th <= near + 1e-12 {
                CV_BAR_NEAR
            } else {
                CV_BAR_GRAZING
            };
            cv / (BAR_SHARE * bar)
        })
        .fold(0.0, f64::max)
}
