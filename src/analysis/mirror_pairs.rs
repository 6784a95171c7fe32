//! The relative RMSE over uniform random pairs, estimated without the heavy tail of a
//! near-mirror peak.
//!
//! The whole-domain figures ([`super::fidelity`]) average (f̂ − f)² cos²θi cos²θo over pairs
//! uniform in solid angle. A glossy measurement's peak is a fraction of a degree wide and
//! thousands of times brighter than the rest, so a uniform pair that lands on it carries most of
//! a 100 000-pair figure: `cg_sunflower`'s default table read 1.5–5.0 % in the grazing band over
//! five seeds (one pair at θh = 0.03°, 56 % of the squared error of four million). The quantity
//! is the same here, the pairs are not: half are drawn as before, half with the outgoing
//! direction mirrored about a half vector near the normal (uniform in one of five cones of 0.1°
//! to 24°, chosen at random), and every pair is weighted by the uniform density over the mixture
//! density (defensive importance sampling: the weight is at most 2, the peak is sampled
//! thousands of times instead of once or never). The ratio of the weighted sums estimates the
//! same ratio as uniform pairs do.

use glam::DVec3;
use rayon::prelude::*;

use super::accuracy::{MAX_SAMPLES, Region, Weight};
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::geometry;
use crate::rng::Pcg32;
use crate::spectrum::MAX_CHANNELS;

/// Half angles of the half-vector cones (degrees), each drawn with equal probability.
const CONES_DEG: [f64; 5] = [0.1, 0.4, 1.5, 6.0, 24.0];

/// Share of the pairs drawn near the mirror direction.
const MIRROR_SHARE: f64 = 0.5;

const BLOCK: usize = 4096;

/// The density of the half vector `h` (unit, upper) under the cone mixture, per steradian.
fn cone_density(h: DVec3, cones: &[(f64, f64)]) -> f64 {
    cones
        .iter()
        .filter(|&&(cos_s, _)| h.z >= cos_s)
        .map(|&(_, d)| d)
        .sum::<f64>()
        / cones.len() as f64
}

/// Cosine-weighted relative RMSE of `approx` against `reference` over the pairs of `region`
/// (uniform in solid angle, as [`super::accuracy::compare_region`]), estimated from `pairs`
/// mixture pairs (see the module docs).
pub fn rel_rmse(
    approx: &dyn Brdf,
    reference: &dyn Brdf,
    pairs: usize,
    seed: u64,
    region: Region,
    weight: Weight,
) -> Result<f64> {
    region.check()?;
    let c = reference.channels().len();
    if approx.channels().len() != c || c > MAX_CHANNELS {
        return Err(Error::arg(
            "channels",
            format!("{} vs {} channels", approx.channels().len(), c),
        ));
    }
    if pairs.checked_mul(c).is_none_or(|n| n > MAX_SAMPLES) {
        return Err(Error::arg(
            "pairs",
            format!(
                "{pairs} pairs × {c} channels: at most {MAX_SAMPLES} samples are compared \
                 ({} pairs of {c} channels)",
                MAX_SAMPLES / c.max(1)
            ),
        ));
    }
    // Both directions range over a cap of this solid angle; the region is the whole product
    // (Cap) or the pairs with a direction beyond the band's edge (Band).
    let (cap, band_z) = match region {
        Region::Cap(t) => (t, f64::INFINITY),
        Region::Band(t) => (std::f64::consts::FRAC_PI_2, t.cos()),
    };
    let span = 1.0 - cap.cos();
    let omega = 2.0 * std::f64::consts::PI * span;
    let cap_z = 1.0 - span;
    // Uniform density of a pair over the product of the caps; the region's own normalization
    // cancels in the ratio.
    let p_uniform = 1.0 / (omega * omega);
    let cones: Vec<(f64, f64)> = CONES_DEG
        .iter()
        .map(|&d| {
            let s = d.to_radians();
            // 1 − cos s without cancellation.
            let one_minus = 2.0 * (0.5 * s).sin().powi(2);
            (
                1.0 - one_minus,
                1.0 / (2.0 * std::f64::consts::PI * one_minus),
            )
        })
        .collect();
    let in_cap = |w: DVec3| w.z > 0.0 && w.z >= cap_z;
    let blocks = pairs.div_ceil(BLOCK);
    let parts: Vec<(f64, f64)> = crate::par::install(|| {
        (0..blocks)
            .into_par_iter()
            .map(|b| {
                let mut rng = Pcg32::with_stream(seed, b as u64);
                let n = BLOCK.min(pairs - b * BLOCK);
                let (mut e2, mut r2) = (0.0, 0.0);
                let mut fa = [0.0f32; MAX_CHANNELS];
                let mut fr = [0.0f32; MAX_CHANNELS];
                let uniform = |u: glam::DVec2| {
                    geometry::uniform_hemisphere(glam::DVec2::new(cap_z + span * u.x, u.y))
                };
                for _ in 0..n {
                    let wi = uniform(rng.next_dvec2());
                    let wo = if rng.next_f64() < MIRROR_SHARE {
                        let (cos_s, _) = cones[rng.below(cones.len() as u32) as usize];
                        let u = rng.next_dvec2();
                        let h = geometry::uniform_hemisphere(glam::DVec2::new(
                            1.0 - u.x * (1.0 - cos_s),
                            u.y,
                        ));
                        geometry::reflect(wi, h)
                    } else {
                        uniform(rng.next_dvec2())
                    };
                    if !in_cap(wo) || wi.z.min(wo.z) >= band_z {
                        continue;
                    }
                    // The mirror component's density of wo: the half vector's over the
                    // reflection's Jacobian 4 (wi·h).
                    let mirror = geometry::normalize(wi + wo)
                        .map_or(0.0, |h| cone_density(h, &cones) / (4.0 * wi.dot(h)));
                    let p_wo = (1.0 - MIRROR_SHARE) / omega + MIRROR_SHARE * mirror;
                    let wt = p_uniform / (p_wo / omega);
                    approx.eval(wi, wo, &mut fa[..c]);
                    reference.eval(wi, wo, &mut fr[..c]);
                    let w = match weight {
                        Weight::CosIn => wi.z,
                        Weight::CosInCosOut => wi.z * wo.z,
                    };
                    for k in 0..c {
                        let (a, r) = (fa[k] as f64, fr[k] as f64);
                        e2 += wt * ((a - r) * w).powi(2);
                        r2 += wt * (r * w).powi(2);
                    }
                }
                (e2, r2)
            })
            .collect()
    });
    approx.health()?;
    reference.health()?;
    let (e2, r2) = parts.iter().fold((0.0, 0.0), |s, p| (s.0 + p.0, s.1 + p.1));
    Ok(if r2 > 0.0 {
        (e2 / r2).sqrt()
    } else if e2 > 0.0 {
        f64::INFINITY
    } else {
        0.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::accuracy::compare_region;
    use crate::spec::ModelSpec;
    use crate::spectrum::Channels;

    fn model(s: &str) -> Box<dyn Brdf> {
        ModelSpec::parse(s).unwrap().build(&Channels::Rgb).unwrap()
    }

    #[test]
    fn estimates_what_uniform_pairs_estimate() {
        // A broad lobe against a slightly different one: no heavy tail, so 400 000 uniform pairs
        // pin the figure to a few parts in a thousand; the mixture must agree within its own
        // and their sampling error (a wrong weight would be off by tens of percent).
        let a = model(r#"{"model":"ggx","alpha":0.3,"fresnel":{"conductor":"Cu"}}"#);
        let r = model(r#"{"model":"ggx","alpha":0.33,"fresnel":{"conductor":"Cu"}}"#);
        for region in [
            Region::Cap(std::f64::consts::FRAC_PI_2),
            Region::Cap(80f64.to_radians()),
            Region::Band(80f64.to_radians()),
        ] {
            let w = Weight::CosInCosOut;
            let u = compare_region(a.as_ref(), r.as_ref(), 400_000, 3, region, w)
                .unwrap()
                .rel_rmse;
            let m = rel_rmse(a.as_ref(), r.as_ref(), 400_000, 3, region, w).unwrap();
            assert!((m / u - 1.0).abs() < 0.03, "{region:?}: {m} vs {u}");
        }
    }

    #[test]
    fn a_sharp_peak_does_not_make_the_figure_a_lottery() {
        // Two near-mirror lobes (α = 0.005 and 0.006): the error is on the peaks, a fraction of
        // a degree wide. Uniform pairs almost never land there, so their figure swings from seed
        // to seed; the mixture's must agree with itself within a few percent.
        let a = model(r#"{"model":"ggx","alpha":0.005,"fresnel":{"conductor":"Ag"}}"#);
        let r = model(r#"{"model":"ggx","alpha":0.006,"fresnel":{"conductor":"Ag"}}"#);
        let w = Weight::CosInCosOut;
        let whole = Region::Cap(std::f64::consts::FRAC_PI_2);
        let figures = |f: &dyn Fn(u64) -> f64| -> (f64, f64) {
            let v: Vec<f64> = (1..6).map(f).collect();
            let lo = v.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = v.iter().cloned().fold(0.0, f64::max);
            (lo, hi)
        };
        let (lo, hi) = figures(&|s| rel_rmse(a.as_ref(), r.as_ref(), 20_000, s, whole, w).unwrap());
        assert!(hi / lo < 1.05, "mixture: {lo} .. {hi}");
        // The uniform pairs' spread, for contrast (what the mixture is for).
        let (ulo, uhi) = figures(&|s| {
            compare_region(a.as_ref(), r.as_ref(), 20_000, s, whole, w)
                .unwrap()
                .rel_rmse
        });
        assert!(uhi / ulo > 1.2, "uniform: {ulo} .. {uhi}");
    }
}
