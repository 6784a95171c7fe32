//! Accuracy of one BRDF against another (a table against its source, a fit against data).
//!
//! Over direction pairs uniform on the hemisphere (independently for wi and wo), estimated from
//! N pairs of a deterministic seed — half of them drawn near the mirror direction and weighted
//! back to uniform ([`MirrorMixture`]), so that a near-mirror peak does not decide the figure by
//! whether a pair landed on it:
//!
//! - cosine-weighted relative RMSE: sqrt(Σ((f̂ − f) cos θi)² / Σ(f cos θi)²), summed over pairs
//!   and channels;
//! - max relative error: max |f̂ − f| / max(|f|, 1% of the RMS of f) — the floor keeps pairs
//!   where f is (nearly) 0 from dominating.
//!
//! [`compare_cap`] draws both directions uniformly within θ ≤ θmax instead. Measured data stored as
//! f_r·cos θo (RGL) turn into f_r ∝ 1/cos θo near the horizon, where a few grazing pairs then
//! dominate the whole-hemisphere figure; Ngan et al. (2005) drop data beyond 80° for that reason,
//! and the conversion report quotes both.

use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

use crate::analysis::mirror_pairs::MirrorMixture;
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::progress::{Progress, Silent};
use crate::rng::Pcg32;
use crate::spectrum::MAX_CHANNELS;

/// Result of [`compare`].
#[derive(Debug, Clone, Serialize)]
pub struct Accuracy {
    /// Number of pairs evaluated.
    pub pairs: usize,
    /// Cosine-weighted relative RMSE (see the module docs).
    pub rel_rmse: f64,
    /// Maximum relative error.
    pub max_rel: f64,
    /// The pair of the maximum relative error.
    #[serde(serialize_with = "ser_pair")]
    pub max_rel_at: (DVec3, DVec3),
    /// Cosine-weighted relative RMSE per channel.
    pub per_channel: Vec<f64>,
}

fn ser_pair<S: serde::Serializer>(
    p: &(DVec3, DVec3),
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    [p.0.to_array(), p.1.to_array()].serialize(s)
}

const BLOCK: usize = 4096;

/// The most pair × channel samples one comparison takes (2^24: about 1 GiB of kept samples,
/// 64 bytes each — the maximum relative error is found once every sample's floor is known).
/// The default 200 000 pairs fit with every channel count the library allows (64); a larger
/// count is an [`Error::InvalidArgument`] naming `pairs`, never an allocation that aborts the
/// process (`convert --pairs 1e18` through any host).
pub const MAX_SAMPLES: usize = 1 << 24;

/// Compares `approx` against `reference` over `pairs` random pairs with seed `seed`.
pub fn compare(
    approx: &dyn Brdf,
    reference: &dyn Brdf,
    pairs: usize,
    seed: u64,
) -> Result<Accuracy> {
    compare_cap(approx, reference, pairs, seed, std::f64::consts::FRAC_PI_2)
}

/// The cosine weight of the relative RMSE.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Weight {
    /// f_r cos θi: the reflected-radiance integrand for one outgoing direction (the default of
    /// [`compare`] and [`compare_cap`]).
    #[default]
    CosIn,
    /// f_r cos θi cos θo: symmetric in the two directions (the measured-table benchmark).
    CosInCosOut,
}

/// Like [`compare`], with both directions drawn uniformly over the cap θ ≤ `max_theta`.
pub fn compare_cap(
    approx: &dyn Brdf,
    reference: &dyn Brdf,
    pairs: usize,
    seed: u64,
    max_theta: f64,
) -> Result<Accuracy> {
    compare_weighted(approx, reference, pairs, seed, max_theta, Weight::CosIn)
}

/// Like [`compare_cap`], with the cosine weight `weight`.
pub fn compare_weighted(
    approx: &dyn Brdf,
    reference: &dyn Brdf,
    pairs: usize,
    seed: u64,
    max_theta: f64,
    weight: Weight,
) -> Result<Accuracy> {
    compare_region(
        approx,
        reference,
        pairs,
        seed,
        Region::Cap(max_theta),
        weight,
    )
}

/// Where [`compare_region`] draws its pairs (its figures are those of pairs uniform over the
/// region's solid angle).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Region {
    /// Both directions within this angle of the normal (radians; π/2 = the whole hemisphere).
    Cap(f64),
    /// Pairs with at least one direction farther than this angle from the normal (radians): the
    /// grazing band, where measured f_r grows like 1/cos θ and a cap hides every error.
    Band(f64),
}

impl Region {
    /// Checks the angle lies in the region kind's range.
    pub fn check(self) -> Result<()> {
        let (name, t) = match self {
            Region::Cap(t) => ("max_theta", t),
            Region::Band(t) => ("min_theta", t),
        };
        let ok = match self {
            Region::Cap(t) => t > 0.0 && t <= std::f64::consts::FRAC_PI_2,
            Region::Band(t) => (0.0..std::f64::consts::FRAC_PI_2).contains(&t),
        };
        if ok {
            Ok(())
        } else {
            Err(Error::arg(
                name,
                format!("{t} is not in the range of the region"),
            ))
        }
    }
}

/// Like [`compare_weighted`], over the pairs of `region`.
pub fn compare_region(
    approx: &dyn Brdf,
    reference: &dyn Brdf,
    pairs: usize,
    seed: u64,
    region: Region,
    weight: Weight,
) -> Result<Accuracy> {
    compare_region_with(approx, reference, pairs, seed, region, weight, &Silent)
}

/// [`compare_region`], asking `progress` to stop before each block of 4096 pairs
/// ([`Progress::cancelled`]: [`Error::Cancelled`]).
pub fn compare_region_with(
    approx: &dyn Brdf,
    reference: &dyn Brdf,
    pairs: usize,
    seed: u64,
    region: Region,
    weight: Weight,
    progress: &dyn Progress,
) -> Result<Accuracy> {
    region.check()?;
    let mixture = match region {
        Region::Cap(t) => MirrorMixture::new(t, None),
        Region::Band(t) => MirrorMixture::new(std::f64::consts::FRAC_PI_2, Some(t)),
    };
    let c = reference.channels().len();
    if approx.channels().len() != c || c > MAX_CHANNELS {
        return Err(Error::arg(
            "channels",
            format!("{} vs {} channels", approx.channels().len(), c),
        ));
    }
    check_pairs(pairs, c)?;
    let blocks = pairs.div_ceil(BLOCK);
    // Per block: (Σ w err² per channel, Σ w ref² per channel, Σ w f² and Σ w without the
    // cosines, samples (|err|, |f|, wi, wo)).
    type Block = (
        Vec<f64>,
        Vec<f64>,
        (f64, f64),
        Vec<(f64, f64, DVec3, DVec3)>,
    );
    let parts: Vec<Block> = crate::par::install(|| {
        (0..blocks)
            .into_par_iter()
            .map(|b| {
                crate::progress::check(progress)?;
                let mut rng = Pcg32::with_stream(seed, b as u64);
                let n = BLOCK.min(pairs - b * BLOCK);
                let mut e2 = vec![0.0; c];
                let mut r2 = vec![0.0; c];
                let mut f2 = (0.0, 0.0);
                let mut worst = Vec::with_capacity(n * c);
                let mut fa = [0.0f32; MAX_CHANNELS];
                let mut fr = [0.0f32; MAX_CHANNELS];
                for _ in 0..n {
                    let (wi, wo, wt) = mixture.draw(&mut rng);
                    approx.eval(wi, wo, &mut fa[..c]);
                    reference.eval(wi, wo, &mut fr[..c]);
                    let w = match weight {
                        Weight::CosIn => wi.z,
                        Weight::CosInCosOut => wi.z * wo.z,
                    };
                    for k in 0..c {
                        let (a, r) = (fa[k] as f64, fr[k] as f64);
                        let err = a - r;
                        e2[k] += wt * (err * w).powi(2);
                        r2[k] += wt * (r * w).powi(2);
                        f2.0 += wt * r * r;
                        f2.1 += wt;
                        worst.push((err.abs(), r.abs(), wi, wo));
                    }
                }
                Ok((e2, r2, f2, worst))
            })
            .collect::<Result<_>>()
    })?;
    // Either side failed while it was read (a corrupt table chunk): its zeros are no result.
    approx.health()?;
    reference.health()?;
    let mut e2 = vec![0.0; c];
    let mut r2 = vec![0.0; c];
    let mut f2 = (0.0, 0.0);
    for p in &parts {
        for k in 0..c {
            e2[k] += p.0[k];
            r2[k] += p.1[k];
        }
        f2.0 += p.2.0;
        f2.1 += p.2.1;
    }
    // 1 % of the RMS of f over the region's uniform pairs.
    let floor = 0.01 * (f2.0 / f2.1.max(f64::MIN_POSITIVE)).sqrt();
    let mut max_rel = 0.0;
    let mut at = (DVec3::ZERO, DVec3::ZERO);
    for p in &parts {
        for &(e, r, wi, wo) in &p.3 {
            let rel = e / r.max(floor).max(1e-300);
            if rel > max_rel || rel.is_nan() {
                max_rel = rel;
                at = (wi, wo);
            }
        }
    }
    let ratio = |e: f64, r: f64| {
        if r > 0.0 {
            (e / r).sqrt()
        } else if e > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    };
    Ok(Accuracy {
        pairs,
        rel_rmse: ratio(e2.iter().sum(), r2.iter().sum()),
        max_rel,
        max_rel_at: at,
        per_channel: (0..c).map(|k| ratio(e2[k], r2[k])).collect(),
    })
}

/// The bound of [`compare_region`]'s work, checked before it (a bake checks it before it writes
/// anything): `pairs` × `c` channels at most [`MAX_SAMPLES`].
pub(crate) fn check_pairs(pairs: usize, c: usize) -> Result<()> {
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
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry;
    use crate::spec::ModelSpec;
    use crate::spectrum::Channels;

    fn model(s: &str) -> Box<dyn Brdf> {
        ModelSpec::parse(s).unwrap().build(&Channels::Rgb).unwrap()
    }

    /// The plain estimator: pairs uniform over the region, unweighted.
    fn uniform_rmse(a: &dyn Brdf, r: &dyn Brdf, pairs: usize, seed: u64, region: Region) -> f64 {
        let (cap, band_z) = match region {
            Region::Cap(t) => (t, f64::INFINITY),
            Region::Band(t) => (std::f64::consts::FRAC_PI_2, t.cos()),
        };
        let span = 1.0 - cap.cos();
        let mut rng = Pcg32::new(seed);
        let mut dir = || {
            let u = rng.next_dvec2();
            geometry::uniform_hemisphere(glam::DVec2::new(1.0 - span + span * u.x, u.y))
        };
        let (mut e2, mut r2) = (0.0, 0.0);
        let (mut fa, mut fr) = ([0.0f32; 3], [0.0f32; 3]);
        let mut n = 0;
        while n < pairs {
            let (wi, wo) = (dir(), dir());
            if wi.z.min(wo.z) >= band_z {
                continue;
            }
            n += 1;
            a.eval(wi, wo, &mut fa);
            r.eval(wi, wo, &mut fr);
            let w = wi.z * wo.z;
            for k in 0..3 {
                e2 += ((fa[k] - fr[k]) as f64 * w).powi(2);
                r2 += (fr[k] as f64 * w).powi(2);
            }
        }
        (e2 / r2).sqrt()
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
            let u = uniform_rmse(a.as_ref(), r.as_ref(), 400_000, 3, region);
            let m = compare_region(a.as_ref(), r.as_ref(), 400_000, 3, region, w)
                .unwrap()
                .rel_rmse;
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
        let whole = Region::Cap(std::f64::consts::FRAC_PI_2);
        let spread = |f: &dyn Fn(u64) -> f64| -> f64 {
            let v: Vec<f64> = (1..6).map(f).collect();
            let lo = v.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = v.iter().cloned().fold(0.0, f64::max);
            hi / lo
        };
        let w = Weight::CosInCosOut;
        let m = spread(&|s| {
            compare_region(a.as_ref(), r.as_ref(), 20_000, s, whole, w)
                .unwrap()
                .rel_rmse
        });
        assert!(m < 1.05, "mixture: spread {m}");
        // The uniform pairs' spread, for contrast (what the mixture is for).
        let u = spread(&|s| uniform_rmse(a.as_ref(), r.as_ref(), 20_000, s, whole));
        assert!(u > 1.2, "uniform: spread {u}");
    }

    #[test]
    fn a_pair_count_beyond_the_bound_is_an_argument_error_not_an_abort() {
        let rgb = Channels::Rgb;
        let a = ModelSpec::parse(r#"{"model":"lambert","kd":0.5}"#)
            .unwrap()
            .build(&rgb)
            .unwrap();
        // 2^62 pairs asked for 2^62 × 3 × 64 bytes of samples: the allocation aborted.
        for pairs in [1 << 62, usize::MAX, MAX_SAMPLES / 3 + 1] {
            let e = compare(a.as_ref(), a.as_ref(), pairs, 1).unwrap_err();
            assert!(
                matches!(e, Error::InvalidArgument { ref name, .. } if name == "pairs"),
                "{pairs}: {e}"
            );
        }
        assert_eq!(
            compare(a.as_ref(), a.as_ref(), 1000, 1).unwrap().rel_rmse,
            0.0
        );
    }
}
