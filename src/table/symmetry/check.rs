//! Whether a source has a symmetry: the violation measured on random pairs and where the source
//! is large, and the [`verify`] and [`detect`] built on it.

use glam::DVec3;
use std::f64::consts::TAU;

use super::{Symmetry, SymmetryKind};
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::geometry;
use crate::rng::Pcg32;
use crate::spectrum::MAX_CHANNELS;

/// The three symmetry tests on one pair: which transformed pair to compare with.
fn transformed(which: usize, wi: DVec3, wo: DVec3, angle: f64) -> (DVec3, DVec3) {
    match which {
        0 => {
            let (s, c) = angle.sin_cos();
            let r = |v: DVec3| DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z);
            (r(wi), r(wo))
        }
        1 => (wo, wi),
        _ => (DVec3::new(wi.x, -wi.y, wi.z), DVec3::new(wo.x, -wo.y, wo.z)),
    }
}

/// The worst relative difference between f(wi, wo) and f at the transformed pair, for
/// `which` = 0 (isotropy: common rotation), 1 (reciprocity: swap), 2 (bilateral: y → −y), over
/// `pairs` random pairs uniform on the hemisphere (seeded). Relative to max(|a|, |b|) floored at
/// 1e-6 × the largest value seen, so values that are 0 up to rounding do not count.
/// Returns (error, a description of the worst pair).
pub fn violation(brdf: &dyn Brdf, which: usize, pairs: usize, seed: u64) -> (f64, String) {
    let mut rng = Pcg32::with_stream(seed, which as u64 + 11);
    worst_violation(brdf, which, pairs, &mut rng, |rng| {
        let wi = geometry::uniform_hemisphere(rng.next_dvec2());
        let wo = geometry::uniform_hemisphere(rng.next_dvec2());
        Some((wi, wo))
    })
}

/// [`violation`] over pairs where the source is large: wo uniform on the hemisphere, wi drawn
/// by the source's own sampler ([`Brdf::sample`]; delta draws are skipped). Random pairs never
/// meet a lobe narrower than a degree or so — f_r is 0 to f32 at every one of them and at its
/// transformed pair, which looks symmetric whatever the lobe is.
pub fn sampled_violation(brdf: &dyn Brdf, which: usize, pairs: usize, seed: u64) -> (f64, String) {
    let mut rng = Pcg32::with_stream(seed, which as u64 + 23);
    let mut weight = [0.0f32; MAX_CHANNELS];
    let c = brdf.channels().len().min(MAX_CHANNELS);
    worst_violation(brdf, which, pairs, &mut rng, |rng| {
        let wo = geometry::uniform_hemisphere(rng.next_dvec2());
        let s = brdf.sample(wo, rng.next_dvec2(), &mut weight[..c])?;
        (!s.delta).then_some((s.wi, wo))
    })
}

/// The worst relative difference over `pairs` draws of `draw` (module docs of [`violation`]).
fn worst_violation(
    brdf: &dyn Brdf,
    which: usize,
    pairs: usize,
    rng: &mut Pcg32,
    mut draw: impl FnMut(&mut Pcg32) -> Option<(DVec3, DVec3)>,
) -> (f64, String) {
    let c = brdf.channels().len().min(MAX_CHANNELS);
    let mut fa = [0.0f32; MAX_CHANNELS];
    let mut fb = [0.0f32; MAX_CHANNELS];
    let mut samples = Vec::with_capacity(pairs);
    let mut scale = 0.0f64;
    for _ in 0..pairs {
        let Some((wi, wo)) = draw(rng) else {
            continue;
        };
        // Keep away from the horizon: grazing values are numerically fragile in many models.
        if wi.z < 0.02 || wo.z < 0.02 {
            continue;
        }
        let angle = rng.next_f64() * TAU;
        let (ti, to) = transformed(which, wi, wo, angle);
        brdf.eval(wi, wo, &mut fa[..c]);
        brdf.eval(ti, to, &mut fb[..c]);
        for k in 0..c {
            let (a, b) = (fa[k] as f64, fb[k] as f64);
            if a.is_finite() && b.is_finite() {
                scale = scale.max(a.abs()).max(b.abs());
                samples.push((a, b, wi, wo));
            }
        }
    }
    let floor = (scale * 1e-6).max(1e-30);
    let mut worst = (0.0, String::new());
    for (a, b, wi, wo) in samples {
        let e = (a - b).abs() / a.abs().max(b.abs()).max(floor);
        if e > worst.0 {
            worst = (
                e,
                format!(
                    "wi=({:.4},{:.4},{:.4}) wo=({:.4},{:.4},{:.4}): {a:.6e} vs {b:.6e}",
                    wi.x, wi.y, wi.z, wo.x, wo.y, wo.z
                ),
            );
        }
    }
    worst
}

/// The violation of symmetry `which` that [`verify`] and [`detect`] judge: over random pairs
/// ([`violation`]) and, for a symmetry the source does not declare, over pairs where it is
/// large too ([`sampled_violation`]): a model's flags are exact where it has a symmetry, and a
/// lobe random pairs miss must not pass for symmetric against them (Ward α = (1e-4, 4e-4) was
/// detected isotropic and its table baked so). The larger of the two.
fn judged_violation(brdf: &dyn Brdf, which: usize, tol: f64) -> (f64, String) {
    let v = violation(brdf, which, CHECK_PAIRS, 0x5EED);
    let f = brdf.flags();
    let declared = [f.isotropic, f.reciprocal, f.bilateral][which];
    if declared || !(v.0 <= tol) {
        return v;
    }
    let s = sampled_violation(brdf, which, CHECK_PAIRS, 0x5EED);
    if s.0 > v.0 || s.0.is_nan() { s } else { v }
}

/// Default tolerance of [`verify`] and [`detect`] (relative).
pub const DEFAULT_TOLERANCE: f64 = 1e-3;
/// Number of random pairs [`verify`] and [`detect`] evaluate.
pub const CHECK_PAIRS: usize = 20_000;

/// Checks that `brdf` has every symmetry in `sym` within relative tolerance `tol` (on random
/// pairs, and one the source does not declare also where it is large, as [`detect`]); the
/// first violated one gives [`Error::Symmetry`].
pub fn verify(brdf: &dyn Brdf, sym: Symmetry, tol: f64) -> Result<()> {
    let wanted = [sym.isotropic, sym.reciprocal, sym.bilateral];
    for (k, &w) in wanted.iter().enumerate() {
        if !w {
            continue;
        }
        let (e, at) = judged_violation(brdf, k, tol);
        if e > tol || e.is_nan() {
            return Err(Error::Symmetry {
                symmetry: SymmetryKind::ALL[k],
                error: e,
                tolerance: tol,
                at,
            });
        }
    }
    Ok(())
}

/// Detects which symmetries `brdf` has within relative tolerance `tol` by evaluating it on
/// [`CHECK_PAIRS`] random pairs per symmetry, and a symmetry it does not declare on as many
/// pairs drawn by its own sampler, where it is large (a lobe random pairs miss).
pub fn detect(brdf: &dyn Brdf, tol: f64) -> Symmetry {
    let ok = |k| judged_violation(brdf, k, tol).0 <= tol;
    Symmetry {
        isotropic: ok(0),
        reciprocal: ok(1),
        bilateral: ok(2),
    }
}
