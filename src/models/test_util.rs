//! Shared checks for the model tests: quadrature over the hemisphere, invalid inputs,
//! reciprocity, eval/eval_wavelength agreement and sample/pdf/weight consistency.

use glam::{DVec2, DVec3};
use proptest::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

use crate::analysis::albedo::gauss_legendre;
use crate::brdf::Brdf;
use crate::geometry;
use crate::rng::Pcg32;
use crate::spectrum::MAX_CHANNELS;

/// ∫ f(w) dω over the upper hemisphere: composite Gauss-Legendre in θ (`ngl` nodes per segment,
/// segments refined geometrically around θ = 0 down to `width`/16, for peaked integrands of
/// angular width `width`) times the midpoint rule with `nphi` points in φ.
pub fn integrate_hemisphere(f: impl Fn(DVec3) -> f64, width: f64, nphi: usize, ngl: usize) -> f64 {
    let mut breaks = vec![0.0];
    let mut t = width / 16.0;
    while t < FRAC_PI_2 {
        breaks.push(t);
        t *= 2.0;
    }
    breaks.push(FRAC_PI_2);
    let (x, w) = gauss_legendre(ngl);
    let mut sum = 0.0;
    for seg in breaks.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        for (xi, wi) in x.iter().zip(&w) {
            let theta = 0.5 * (a + b) + 0.5 * (b - a) * xi;
            let wt = 0.5 * (b - a) * wi * theta.sin();
            let mut row = 0.0;
            for j in 0..nphi {
                let phi = 2.0 * PI * (j as f64 + 0.5) / nphi as f64;
                row += f(geometry::spherical(theta, phi));
            }
            sum += wt * row * 2.0 * PI / nphi as f64;
        }
    }
    sum
}

/// Outgoing directions used by the sampling tests: normal, moderate, steep and near-grazing,
/// at azimuths off the axes so anisotropic lobes are exercised.
pub fn test_wos() -> Vec<DVec3> {
    [
        (0.0, 0.0),
        (30.0, 0.4),
        (60.0, 2.0),
        (80.0, -1.1),
        (88.0, 0.9),
    ]
    .iter()
    .map(|&(t, p): &(f64, f64)| geometry::spherical(t.to_radians(), p))
    .collect()
}

/// A proptest strategy for directions strictly above the horizon (unnormalized on purpose).
pub fn dir_strategy() -> impl Strategy<Value = DVec3> {
    (0.0f64..1.55, -PI..PI, 0.1f64..10.0).prop_map(|(t, p, len)| geometry::spherical(t, p) * len)
}

/// f(a, b) == f(b, a) per channel to f32 accuracy.
pub fn check_reciprocity<B: Brdf + ?Sized>(
    brdf: &B,
    a: DVec3,
    b: DVec3,
) -> std::result::Result<(), TestCaseError> {
    let c = brdf.channels().len();
    let mut f1 = [0.0f32; MAX_CHANNELS];
    let mut f2 = [0.0f32; MAX_CHANNELS];
    brdf.eval(a, b, &mut f1[..c]);
    brdf.eval(b, a, &mut f2[..c]);
    for k in 0..c {
        let (x, y) = (f1[k] as f64, f2[k] as f64);
        prop_assert!(
            (x - y).abs() <= 1e-5 * x.abs().max(y.abs()) + 1e-30,
            "channel {k}: f(a,b) = {x}, f(b,a) = {y} for a = {a}, b = {b}"
        );
    }
    Ok(())
}

/// Below-horizon, NaN, infinite and zero directions give 0 from eval, eval_wavelength and pdf,
/// and no sample (the contract's check, [`crate::testkit`]).
#[track_caller]
pub fn check_invalid_inputs_give_zero<B: Brdf + ?Sized>(brdf: &B) {
    crate::testkit::contract::assert_bad_input_gives_zero(brdf);
}

/// eval_wavelength at each channel's wavelength equals eval's value for that channel.
pub fn check_eval_wavelength_matches_channels<B: Brdf + ?Sized>(brdf: &B) {
    let mut rng = Pcg32::new(11);
    let c = brdf.channels().len();
    for _ in 0..200 {
        let wi = geometry::uniform_hemisphere(rng.next_dvec2());
        let wo = geometry::uniform_hemisphere(rng.next_dvec2());
        let mut f = [0.0f32; MAX_CHANNELS];
        brdf.eval(wi, wo, &mut f[..c]);
        for (k, &fk) in f[..c].iter().enumerate() {
            let nm = brdf.channels().wavelength(k);
            let g = brdf.eval_wavelength(wi, wo, nm);
            assert!(
                (g - fk as f64).abs() <= 2e-6 * g.abs() + 1e-30,
                "channel {k} ({nm} nm): eval {fk} vs eval_wavelength {g}"
            );
        }
    }
}

/// For `n` random samples at each `wo`: the returned pdf equals `pdf(wi, wo)`, the weight
/// equals f_r cos θi / pdf per channel, `eval_pdf` agrees, sampled directions are unit and above
/// the horizon (the contract's check, [`crate::testkit`]).
#[track_caller]
pub fn check_sampling_consistency<B: Brdf + ?Sized>(brdf: &B, wos: &[DVec3], n: usize) {
    crate::testkit::contract::assert_sampling_consistent(brdf, wos, n);
}

/// Chi-square tests of each model's sampler at every [`test_wos`] direction (see [`chi2_cases`]).
pub fn chi2_models(models: &[&dyn Brdf]) {
    let mut cases: Vec<(&dyn Brdf, DVec3)> = Vec::new();
    for &m in models {
        for wo in test_wos() {
            cases.push((m, wo));
        }
    }
    chi2_cases(&cases);
}

/// Runs the chi-square test (`crate::analysis::chi2`) for every `(sampler, wo)` case with a
/// Šidák-corrected overall significance of 1 %, and fails listing the cases that do not pass.
pub fn chi2_cases(cases: &[(&dyn Brdf, DVec3)]) {
    use crate::analysis::chi2::{Chi2Options, sidak, test};
    let o = Chi2Options {
        samples: 200_000,
        ..Default::default()
    };
    let alpha = sidak(0.01, cases.len());
    let mut failures = Vec::new();
    for (brdf, wo) in cases {
        let r = test(*brdf, *wo, &o);
        if !r.passes(alpha) {
            failures.push(format!("{} at wo = {wo}: {r:?}", brdf.describe()));
        }
    }
    assert!(
        failures.is_empty(),
        "chi-square failures:\n{}",
        failures.join("\n")
    );
}

/// A sampler given by closures, seen as a `Brdf` so the chi-square harness can test it:
/// `sample(u)` draws a direction (ignoring `wo`), `pdf(w)` is its density. `eval` is 0.
pub struct FnSampler<S, P> {
    /// Draws a direction from two uniform numbers.
    pub sample: S,
    /// Its density (solid angle).
    pub pdf: P,
    /// What is being sampled.
    pub name: String,
}

impl<S, P> Brdf for FnSampler<S, P>
where
    S: Fn(DVec2) -> Option<DVec3> + Send + Sync,
    P: Fn(DVec3) -> f64 + Send + Sync,
{
    fn channels(&self) -> &crate::spectrum::Channels {
        static RGB: crate::spectrum::Channels = crate::spectrum::Channels::Rgb;
        &RGB
    }
    fn eval(&self, _: DVec3, _: DVec3, out: &mut [f32]) {
        out.fill(0.0);
    }
    fn flags(&self) -> crate::brdf::Flags {
        crate::brdf::Flags::default()
    }
    fn describe(&self) -> String {
        self.name.clone()
    }
    fn sample(&self, _: DVec3, u: DVec2, _: &mut [f32]) -> Option<crate::brdf::BrdfSample> {
        let wi = (self.sample)(u)?;
        Some(crate::brdf::BrdfSample {
            wi,
            pdf: (self.pdf)(wi),
            delta: false,
        })
    }
    fn pdf(&self, wi: DVec3, _: DVec3) -> f64 {
        (self.pdf)(wi)
    }
}
