//! Tests of the weighted sum: its value is the weighted terms', its flags and albedo follow
//! the terms', and its mixture sampler (delta terms included) passes chi-square.

use super::*;
use crate::fresnel::FresnelSpec;
use crate::geometry;
use crate::models::test_util::*;
use crate::models::{
    blinn_phong::BlinnPhong, ggx::Ggx, lambert::Lambert, oren_nayar::OrenNayar, ward::Ward,
};
use crate::rng::Pcg32;
use crate::spec::ModelSpec;
use crate::spectrum::Value;
use proptest::prelude::*;

fn lambert(kd: f64) -> Box<dyn Brdf + Send + Sync> {
    Box::new(Lambert::new(Value::Grey(kd), &Channels::Rgb).unwrap())
}

fn ggx(ax: f64, ay: f64) -> Box<dyn Brdf + Send + Sync> {
    Box::new(
        Ggx::new(
            ax,
            ay,
            Value::Rgb([0.9, 0.7, 0.5]),
            FresnelSpec::None,
            &Channels::Rgb,
        )
        .unwrap(),
    )
}

fn plastic() -> Sum {
    Sum::new(
        vec![lambert(0.2), ggx(0.1, 0.1)],
        Some(vec![1.0, 0.5]),
        &Channels::Rgb,
    )
    .unwrap()
}

fn three() -> Sum {
    Sum::new(
        vec![
            Box::new(Ward::new(Value::Grey(0.3), 0.08, 0.4, &Channels::Rgb).unwrap()),
            Box::new(BlinnPhong::new(Value::Grey(0.4), 60.0, &Channels::Rgb).unwrap()),
            Box::new(OrenNayar::new(Value::Grey(0.15), 0.5, &Channels::Rgb).unwrap()),
        ],
        None,
        &Channels::Rgb,
    )
    .unwrap()
}

/// A test-only mirror (delta) with constant reflectance, for the delta-term rules.
struct TestMirror(Channels, f32);
impl Brdf for TestMirror {
    fn channels(&self) -> &Channels {
        &self.0
    }
    fn eval(&self, _: DVec3, _: DVec3, out: &mut [f32]) {
        out[..3].fill(0.0);
    }
    fn flags(&self) -> Flags {
        Flags {
            delta: true,
            lobes: crate::brdf::Lobes::DELTA,
            ..Flags::SMOOTH_SYMMETRIC
        }
    }
    fn describe(&self) -> String {
        "test mirror".into()
    }
    fn sample(&self, wo: DVec3, _: DVec2, w: &mut [f32]) -> Option<BrdfSample> {
        let wo = geometry::normalize(wo).filter(|w| w.z > 0.0)?;
        w[..3].fill(self.1);
        Some(BrdfSample {
            wi: geometry::reflect_z(wo),
            pdf: 1.0,
            delta: true,
        })
    }
    fn pdf(&self, _: DVec3, _: DVec3) -> f64 {
        0.0
    }
}

#[test]
fn sum_equals_weighted_terms() {
    let s = plastic();
    let (a, b) = (lambert(0.2), ggx(0.1, 0.1));
    let mut rng = Pcg32::new(8);
    for _ in 0..2000 {
        let wi = geometry::uniform_sphere(rng.next_dvec2());
        let wo = geometry::uniform_sphere(rng.next_dvec2());
        let (mut f, mut fa, mut fb) = ([0.0f32; 3], [0.0f32; 3], [0.0f32; 3]);
        s.eval(wi, wo, &mut f);
        a.eval(wi, wo, &mut fa);
        b.eval(wi, wo, &mut fb);
        for c in 0..3 {
            let expect = fa[c] as f64 + 0.5 * fb[c] as f64;
            assert!(
                (f[c] as f64 - expect).abs() <= 1e-7 * expect,
                "{} vs {expect}",
                f[c]
            );
        }
        let expect = a.eval_wavelength(wi, wo, 500.0) + 0.5 * b.eval_wavelength(wi, wo, 500.0);
        assert!((s.eval_wavelength(wi, wo, 500.0) - expect).abs() <= 1e-12 * expect);
    }
}

#[test]
fn built_from_spec_with_default_weights() {
    let spec = ModelSpec::parse(
        r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.1},
            {"model": "oren_nayar", "kd": 0.2, "sigma": 0.0}]}"#,
    )
    .unwrap();
    let s = spec.build(&Channels::Rgb).unwrap();
    let mut f = [0.0f32; 3];
    s.eval(
        DVec3::new(0.1, 0.2, 1.0),
        DVec3::new(-0.5, 0.0, 0.5),
        &mut f,
    );
    assert!((f[0] as f64 - 0.3).abs() < 1e-7);
}

#[test]
fn flags_are_the_and_of_terms_and_lobes_their_union() {
    let both = crate::brdf::Lobes::DIFFUSE.union(crate::brdf::Lobes::GLOSSY);
    assert_eq!(
        plastic().flags(),
        Flags {
            lobes: both,
            ..Flags::SMOOTH_SYMMETRIC
        }
    );
    let aniso = Sum::new(vec![lambert(0.2), ggx(0.1, 0.3)], None, &Channels::Rgb).unwrap();
    assert!(!aniso.flags().isotropic && aniso.flags().reciprocal && !aniso.flags().delta);
    let mirror = || -> Box<dyn Brdf + Send + Sync> { Box::new(TestMirror(Channels::Rgb, 0.5)) };
    let mixed = Sum::new(vec![lambert(0.2), mirror()], None, &Channels::Rgb).unwrap();
    assert!(!mixed.flags().delta);
    let all = Sum::new(vec![mirror(), mirror()], None, &Channels::Rgb).unwrap();
    assert!(all.flags().delta);
    let lobes = mixed.flags().lobes;
    assert!(lobes.diffuse && lobes.delta && !lobes.glossy);
}

#[test]
fn delta_terms_are_skipped_by_eval_and_chosen_by_sample() {
    let s = Sum::new(
        vec![lambert(0.2), Box::new(TestMirror(Channels::Rgb, 0.5))],
        Some(vec![1.0, 2.0]),
        &Channels::Rgb,
    )
    .unwrap();
    let wo = geometry::spherical(0.6, 0.2);
    let mut f = [0.0f32; 3];
    s.eval(geometry::reflect_z(wo), wo, &mut f);
    assert!((f[0] - 0.2).abs() < 1e-7);
    // Albedos: Lambert 0.2π, mirror 2 · 0.5 = 1.
    let p = s.selection_probabilities(wo);
    let expect_mirror = 1.0 / (1.0 + 0.2 * std::f64::consts::PI);
    assert!((p[1] - expect_mirror).abs() < 1e-3, "{p:?}");
    // The mean sample weight is the total reflectance towards wo: 0.2π + 1.
    let mut rng = Pcg32::new(2);
    let (n, mut sum, mut deltas) = (100_000, 0.0, 0);
    for _ in 0..n {
        let mut w = [0.0f32; 3];
        if let Some(smp) = s.sample(wo, rng.next_dvec2(), &mut w) {
            if smp.delta {
                deltas += 1;
                assert!((smp.wi - geometry::reflect_z(wo)).length() < 1e-12);
                assert!((smp.pdf - p[1]).abs() < 1e-12);
            }
            sum += w[0] as f64;
        }
    }
    let mean = sum / n as f64;
    let expect = 0.2 * std::f64::consts::PI + 1.0;
    // Weights are 1/p per branch: the estimator is exact per branch, the only variance is the
    // branch choice (σ ≈ 1e-3 here) — allow 5σ.
    assert!((mean - expect).abs() < 5e-3, "{mean} vs {expect}");
    assert!((deltas as f64 / n as f64 - p[1]).abs() < 0.01);
}

/// Counts every call of a term's eval, sample and pdf, and integrates its albedo by the
/// trait's default quadrature through the counted `eval` (as every model but Lambert and
/// the deltas does).
struct Counting(
    Box<dyn Brdf + Send + Sync>,
    std::sync::Arc<std::sync::atomic::AtomicUsize>,
);

impl Counting {
    fn tick(&self) {
        self.1.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }
}

impl Brdf for Counting {
    fn channels(&self) -> &Channels {
        self.0.channels()
    }
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        self.tick();
        self.0.eval(wi, wo, out)
    }
    fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
        self.tick();
        self.0.sample(wo, u, weight)
    }
    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.tick();
        self.0.pdf(wi, wo)
    }
    fn flags(&self) -> Flags {
        self.0.flags()
    }
    fn describe(&self) -> String {
        self.0.describe()
    }
}

#[test]
fn nested_sums_are_built_in_bounded_work() {
    // Issue #23: the selection table took each term's `Brdf::albedo` at 24 angles — a
    // 1e-6 quadrature of thousands of evaluations each, and for a nested sum the albedos
    // of all its terms, so the work grew with the square of the depth (a 1 KB spec nesting
    // 20 sums took 49 s to open). Now each level draws 24 × 64 samples of each term (× 2
    // for anisotropic ones), a nested sum's sample costing at most one draw, one pdf and
    // one evaluation of each of its leaves.
    let calls = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let leaf =
        |a: f64| -> Box<dyn Brdf + Send + Sync> { Box::new(Counting(ggx(a, a), calls.clone())) };
    let depth = 12;
    let mut chain = leaf(0.1);
    for k in 0..depth {
        chain = Box::new(
            Sum::new(
                vec![leaf(0.05 + 0.01 * k as f64), chain],
                None,
                &Channels::Rgb,
            )
            .unwrap(),
        );
    }
    let n = calls.load(std::sync::atomic::Ordering::Relaxed);
    let leaves = depth + 1;
    let bound = depth * TABLE_SIZE * 64 * 3 * leaves;
    assert!(
        n <= bound,
        "{n} calls of the leaves for a depth {depth} chain (bound {bound})"
    );
    // Still a working sampler: the mean weight is the albedo.
    let wo = geometry::spherical(0.5, 0.3);
    let mut rng = Pcg32::new(5);
    let (m, mut mean) = (20_000, 0.0);
    for _ in 0..m {
        let mut w = [0.0f32; 3];
        if chain.sample(wo, rng.next_dvec2(), &mut w).is_some() {
            mean += w[0] as f64 / m as f64;
        }
    }
    let mut a = [0.0; 3];
    chain.albedo(wo, &mut a);
    assert!(
        (mean - a[0]).abs() < 0.05 * a[0],
        "{mean} vs albedo {}",
        a[0]
    );
}

#[test]
fn selection_estimates_follow_the_albedo() {
    // The sample-weight estimate of a glossy term's albedo is within a few percent of the
    // quadrature, at every bin, so the selection is close to the ideal one.
    let s = Sum::new(vec![lambert(0.1), ggx(0.2, 0.2)], None, &Channels::Rgb).unwrap();
    for k in 0..TABLE_SIZE {
        let mu = (k as f64 + 0.5) / TABLE_SIZE as f64;
        let wo = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
        let mut a = [0.0; 3];
        ggx(0.2, 0.2).albedo(wo, &mut a);
        let mean = a.iter().sum::<f64>() / 3.0;
        let ideal = mean / (mean + 0.1 * std::f64::consts::PI);
        let p = s.selection_probabilities(wo);
        assert!((p[1] - ideal).abs() < 0.01, "bin {k}: {p:?} vs {ideal}");
    }
}

#[test]
fn lambert_plus_real_mirror_from_spec() {
    // The mean sample weight is the reflectance towards wo: k_d π + F(cos θo).
    let spec = ModelSpec::parse(
        r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.1},
            {"model": "mirror", "fresnel": {"n": 1.5, "k": 0.0}}]}"#,
    )
    .unwrap();
    let s = spec.build(&Channels::Rgb).unwrap();
    assert!(!s.flags().delta);
    let mut rng = Pcg32::new(21);
    for deg in [10.0f64, 70.0] {
        let wo = geometry::spherical(deg.to_radians(), 1.0);
        let expect = 0.1 * std::f64::consts::PI + crate::fresnel::dielectric(wo.z, 1.5);
        let n = 50_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let mut w = [0.0f32; 3];
            if s.sample(wo, rng.next_dvec2(), &mut w).is_some() {
                sum += w[0] as f64;
            }
        }
        let mean = sum / n as f64;
        // Each branch's weight is its reflectance / p_j; only the branch choice varies.
        assert!(
            (mean - expect).abs() < 0.02 * expect,
            "{deg}°: {mean} vs {expect}"
        );
    }
}

/// The mean weight of `sample_wavelengths` over stratified numbers is the reflectance
/// towards wo at each wavelength — k_d π plus each mirror's Fresnel term there — for the
/// two-term RGB path and the general one. Each branch's weight is its reflectance over its
/// choice probability, so the strata leave an error of at most two strata's weights.
#[test]
fn spectral_sample_weights_of_delta_terms_are_the_terms_reflectance() {
    let mirror = |m: &str| -> Box<dyn Brdf + Send + Sync> {
        Box::new(
            crate::models::mirror::Mirror::new(&FresnelSpec::Conductor(m.into()), &Channels::Rgb)
                .unwrap(),
        )
    };
    let nm = [420.0, 480.0, 530.0, 610.0, 700.0];
    let sums = [
        Sum::new(vec![lambert(0.1), mirror("Au")], None, &Channels::Rgb).unwrap(),
        Sum::new(
            vec![lambert(0.1), mirror("Au"), mirror("Cu")],
            Some(vec![1.0, 0.5, 0.5]),
            &Channels::Rgb,
        )
        .unwrap(),
    ];
    let fresnel = |m: &str, cos: f64, x: f64| {
        crate::fresnel::Fresnel::new(&FresnelSpec::Conductor(m.into()), &Channels::Rgb, "f")
            .unwrap()
            .eval_at(cos, x)
    };
    for (k, s) in sums.iter().enumerate() {
        for deg in [5.0f64, 60.0] {
            let wo = geometry::spherical(deg.to_radians(), 0.4);
            let n = 8192;
            let (mut sum, mut most) = ([0.0f64; 5], 0.0f64);
            for i in 0..n {
                let u = DVec2::new((i as f64 + 0.5) / n as f64, 0.37);
                let mut w = [0.0f32; 5];
                let d = s.sample_wavelengths(wo, u, &nm, &mut w).unwrap();
                if d.delta {
                    assert!((d.wi - geometry::reflect_z(wo)).length() < 1e-12);
                }
                for (a, &x) in sum.iter_mut().zip(&w) {
                    *a += x as f64;
                    most = most.max(x as f64);
                }
            }
            for (j, &x) in nm.iter().enumerate() {
                let metals = match k {
                    0 => fresnel("Au", wo.z, x),
                    _ => 0.5 * (fresnel("Au", wo.z, x) + fresnel("Cu", wo.z, x)),
                };
                let expect = 0.1 * std::f64::consts::PI + metals;
                let mean = sum[j] / n as f64;
                let tol = 2.0 * most / n as f64;
                assert!(
                    (mean - expect).abs() <= tol,
                    "sum {k}, {deg}°, {x} nm: {mean} vs {expect} (± {tol})"
                );
            }
        }
    }
}

#[test]
fn selection_follows_albedo() {
    // A white Lambert (albedo 1) and a GGX with F = 1 weighted by 0 gets nothing.
    let s = Sum::new(
        vec![lambert(1.0 / std::f64::consts::PI), ggx(0.2, 0.2)],
        Some(vec![1.0, 0.0]),
        &Channels::Rgb,
    )
    .unwrap();
    assert_eq!(s.selection_probabilities(DVec3::Z), vec![1.0, 0.0]);
    // Equal albedo terms get (nearly) equal probability.
    let s = Sum::new(vec![lambert(0.1), lambert(0.3)], None, &Channels::Rgb).unwrap();
    let p = s.selection_probabilities(geometry::spherical(0.4, 0.0));
    assert!((p[0] - 0.25).abs() < 1e-6, "{p:?}");
}

#[test]
fn invalid_construction_is_an_error() {
    assert!(Sum::new(vec![], None, &Channels::Rgb).is_err());
    assert!(Sum::new(vec![lambert(0.1)], Some(vec![1.0, 2.0]), &Channels::Rgb).is_err());
    assert!(Sum::new(vec![lambert(0.1)], Some(vec![-1.0]), &Channels::Rgb).is_err());
    assert!(Sum::new(vec![lambert(0.1)], Some(vec![f64::NAN]), &Channels::Rgb).is_err());
    let ch = Channels::linspace(400.0, 700.0, 4).unwrap();
    assert!(Sum::new(vec![lambert(0.1)], None, &ch).is_err());
    let many = (0..=MAX_TERMS).map(|_| lambert(0.01)).collect();
    let err = Sum::new(many, None, &Channels::Rgb)
        .unwrap_err()
        .to_string();
    assert!(err.contains("at most 16"), "{err}");
    let most = (0..MAX_TERMS).map(|_| lambert(0.01)).collect();
    assert!(Sum::new(most, None, &Channels::Rgb).is_ok());
}

#[test]
fn nothing_is_sampled_when_no_term_reflects() {
    // Weights 0: f = 0 everywhere, no term can be chosen, the density is 0 — for the pair
    // sampler and the general one.
    for n in [2, 3] {
        let s = Sum::new(
            (0..n).map(|_| lambert(0.2)).collect(),
            Some(vec![0.0; n]),
            &Channels::Rgb,
        )
        .unwrap();
        let wo = geometry::spherical(0.3, 0.1);
        let mut w = [1.0f32; 3];
        assert!(s.sample(wo, DVec2::new(0.3, 0.7), &mut w).is_none());
        assert_eq!(s.pdf(DVec3::Z, wo), 0.0);
        assert_eq!(s.eval_pdf(DVec3::Z, wo, &mut w), 0.0);
        assert_eq!(w, [0.0; 3]);
        assert_eq!(s.selection_probabilities(wo), vec![0.0; n]);
    }
}

#[test]
fn pair_sampler_agrees_with_the_general_one() {
    // For two RGB terms `sample` takes the pair path; `sample_n` is the general one. Both
    // choose with the same probabilities, so for every u they give the same direction, pdf
    // and weight, up to the rounding of the rescaled u.x (a multiplication by a reciprocal
    // against a division: one unit in the last place, which the warps amplify to ≲ 10⁻¹³).
    let s = plastic();
    let mut rng = Pcg32::new(77);
    for _ in 0..20_000 {
        let wo = geometry::cosine_hemisphere(rng.next_dvec2());
        let u = rng.next_dvec2();
        let (mut a, mut b) = ([0.0f32; 3], [0.0f32; 3]);
        match (
            s.sample(wo, u, &mut a),
            s.sample_n::<4>(wo, u, &mut b, &mut (0, DVec2::ZERO)),
        ) {
            (Some(x), Some(y)) => {
                assert!((x.wi - y.wi).length() < 1e-12, "{x:?} vs {y:?}");
                assert!((x.pdf - y.pdf).abs() <= 1e-10 * x.pdf, "{x:?} vs {y:?}");
                for c in 0..3 {
                    assert!((a[c] - b[c]).abs() <= 1e-6 * a[c].abs(), "{a:?} vs {b:?}");
                }
            }
            (None, None) => {}
            other => panic!("{other:?}"),
        }
    }
}

#[test]
fn below_horizon_and_nan_give_zero() {
    check_invalid_inputs_give_zero(&plastic());
    check_invalid_inputs_give_zero(&three());
}

#[test]
fn spectral_parameters_follow_eval_wavelength() {
    let ch = Channels::linspace(400.0, 700.0, 4).unwrap();
    let s = Sum::new(
        vec![
            Box::new(Lambert::new(Value::Rgb([0.1, 0.2, 0.3]), &ch).unwrap()),
            Box::new(Ward::new(Value::Rgb([0.3, 0.2, 0.1]), 0.1, 0.2, &ch).unwrap()),
        ],
        Some(vec![0.5, 2.0]),
        &ch,
    )
    .unwrap();
    check_eval_wavelength_matches_channels(&s);
}

#[test]
fn albedo_is_the_weighted_sum() {
    let s = plastic();
    let wi = geometry::spherical(0.7, 0.1);
    let (mut a, mut q) = ([0.0; 3], [0.0; 3]);
    s.albedo(wi, &mut a);
    crate::analysis::albedo::quadrature(&s, wi, &mut q);
    for c in 0..3 {
        assert!((a[c] - q[c]).abs() < 1e-6, "{a:?} vs {q:?}");
    }
}

#[test]
fn sample_weight_and_pdf_are_consistent() {
    check_sampling_consistency(&plastic(), &test_wos(), 2000);
    check_sampling_consistency(&three(), &test_wos(), 2000);
}

#[test]
fn mixture_sampler_passes_chi_square_plastic() {
    chi2_models(&[&plastic()]);
}

#[test]
fn mixture_sampler_passes_chi_square_three_terms() {
    chi2_models(&[&*THREE]);
}

static THREE: std::sync::LazyLock<Sum> = std::sync::LazyLock::new(three);

proptest! {
    #[test]
    fn reciprocal(a in dir_strategy(), b in dir_strategy()) {
        check_reciprocity(&*THREE, a, b)?;
    }
}
