//! Tests of GGX against the math: the NDF's normalization and closed-form peak, the
//! trigonometric formulas, symmetries and reciprocity, the white furnace, and chi-square tests
//! of its samplers.

use super::*;
use crate::analysis::albedo::gauss_legendre;
use crate::models::test_util::*;
use crate::rng::Pcg32;
use proptest::prelude::*;

fn iso(alpha: f64) -> Ggx {
    Ggx::isotropic(alpha, Value::Grey(1.0), FresnelSpec::None, &Channels::Rgb).unwrap()
}

fn aniso(ax: f64, ay: f64) -> Ggx {
    Ggx::new(ax, ay, Value::Grey(1.0), FresnelSpec::None, &Channels::Rgb).unwrap()
}

fn conductor() -> FresnelSpec {
    FresnelSpec::Complex {
        n: Value::Rgb([0.2, 0.9, 1.1]),
        k: Value::Rgb([3.9, 2.4, 2.2]),
    }
}

/// A lobe far narrower than the quadrature resolves, seen near the horizon: the albedo read
/// 2.81 (α = 1e-12, cos θi = 1e-5), 27.8 (1e-6) and ∞ (1e-9); its limit is k_s F(cos θi),
/// to (α tan θi)² ≤ 1e-6, which the sampler's mean weight confirms.
#[test]
fn albedo_of_a_near_mirror_at_grazing_is_its_limit() {
    let fresnel = conductor();
    let m = Ggx::new(
        1e-12,
        1e-12,
        Value::Grey(0.8),
        fresnel.clone(),
        &Channels::Rgb,
    )
    .unwrap();
    let f = Fresnel::new(&fresnel, &Channels::Rgb, "fresnel").unwrap();
    for cos in [1e-2f64, 1e-5, 1e-6, 1e-7, 1e-9] {
        let wi = DVec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
        let mut a = [0.0; 3];
        m.albedo(wi, &mut a);
        for (c, &x) in a.iter().enumerate() {
            let want = 0.8 * f.eval(cos, c);
            assert!(
                (x - want).abs() <= 1e-6 * want,
                "cos {cos:e} channel {c}: {x} vs {want}"
            );
        }
        let mut rng = Pcg32::new(7);
        let mut w = [0.0f32; 3];
        for _ in 0..64 {
            if m.sample(wi, rng.next_dvec2(), &mut w).is_some() {
                assert!((w[0] as f64 - 0.8 * f.eval(cos, 0)).abs() < 1e-6, "{w:?}");
            }
        }
    }
}

#[test]
fn ndf_is_normalized() {
    for (ax, ay) in [
        (0.01, 0.01),
        (0.1, 0.1),
        (0.5, 0.5),
        (1.0, 1.0),
        (0.05, 0.4),
        (0.8, 0.2),
    ] {
        let m = aniso(ax, ay);
        let nphi = if ax == ay { 1 } else { 256 };
        let width = ax.min(ay);
        let integral = integrate_hemisphere(|h| m.ndf(h) * h.z, width, nphi, 32);
        // The anisotropic φ integrand is smooth and periodic: the midpoint rule converges
        // geometrically, so both cases reach quadrature accuracy.
        assert!(
            (integral - 1.0).abs() < 1e-7,
            "α = ({ax}, {ay}): ∫ D cos = {integral}"
        );
    }
}

/// ∫ g(h) dω_h over the half vectors visible from `wo` (wo·h > 0): for each θh the arc of
/// φh where wo·h > 0 is integrated by composite Gauss-Legendre (16 panels × 16 nodes), so
/// the kink of max(0, wo·h) falls on panel ends and does not spoil the quadrature.
fn integrate_visible(m: &Ggx, wo: DVec3, g: impl Fn(DVec3) -> f64) -> f64 {
    let (theta_o, phi_o) = geometry::to_spherical(wo);
    let (xt, wt_) = gauss_legendre(48);
    let (xp, wp) = gauss_legendre(16);
    let panels = 16;
    let (ax, ay) = m.alpha();
    let mut breaks = vec![0.0];
    let mut t = ax.min(ay) / 16.0;
    while t < std::f64::consts::FRAC_PI_2 {
        breaks.push(t);
        t *= 2.0;
    }
    breaks.push(std::f64::consts::FRAC_PI_2);
    let mut sum = 0.0;
    for seg in breaks.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        for (xi, wi) in xt.iter().zip(&wt_) {
            let th = 0.5 * (a + b) + 0.5 * (b - a) * xi;
            let wt = 0.5 * (b - a) * wi * th.sin();
            // wo·h = sin θo sin θh cos(φ − φo) + cos θo cos θh > 0 on φo ± half.
            let c = -theta_o.cos() * th.cos() / (theta_o.sin() * th.sin()).max(1e-300);
            let half = if c <= -1.0 {
                PI
            } else if c >= 1.0 {
                0.0
            } else {
                c.acos()
            };
            let width = 2.0 * half / panels as f64;
            for p in 0..panels {
                let p0 = phi_o - half + p as f64 * width;
                for (xj, wj) in xp.iter().zip(&wp) {
                    let phi = p0 + 0.5 * width * (xj + 1.0);
                    sum += wt * 0.5 * width * wj * g(geometry::spherical(th, phi));
                }
            }
        }
    }
    sum
}

#[test]
fn visible_normals_project_to_cos_theta_o() {
    // ∫ G1(wo) max(0, wo·h) D(h) dω_h = cos θo: the projected area of the visible microfacets
    // equals that of the geometric surface (Heitz 2014, eq. 2 with Smith's G1).
    for (ax, ay) in [(0.1, 0.1), (0.5, 0.5), (1.0, 1.0), (0.05, 0.4), (0.9, 0.3)] {
        let m = aniso(ax, ay);
        for wo in test_wos() {
            let lhs = integrate_visible(&m, wo, |h| m.g1(wo) * wo.dot(h).max(0.0) * m.ndf(h));
            assert!(
                (lhs - wo.z).abs() < 1e-6 * wo.z.max(0.01),
                "α = ({ax}, {ay}), wo = {wo}: {lhs} vs cos θo = {}",
                wo.z
            );
        }
    }
}

#[test]
fn matches_the_trigonometric_formulas() {
    // D and Λ as the papers write them, with θ and φ from atan2/acos.
    let (ax, ay) = (0.15, 0.45);
    let m = Ggx::new(ax, ay, Value::Grey(0.7), FresnelSpec::None, &Channels::Rgb).unwrap();
    let mut rng = Pcg32::new(12);
    for _ in 0..2000 {
        let wi = geometry::uniform_hemisphere(rng.next_dvec2());
        let wo = geometry::uniform_hemisphere(rng.next_dvec2());
        let h = (wi + wo).normalize();
        let (th, ph) = geometry::to_spherical(h);
        let d = 1.0
            / (PI
                * ax
                * ay
                * th.cos().powi(4)
                * (1.0
                    + th.tan().powi(2)
                        * (ph.cos().powi(2) / (ax * ax) + ph.sin().powi(2) / (ay * ay)))
                    .powi(2));
        let lambda = |w: DVec3| {
            let (t, p) = geometry::to_spherical(w);
            let a2 = p.cos().powi(2) * ax * ax + p.sin().powi(2) * ay * ay;
            0.5 * (-1.0 + (1.0 + a2 * t.tan().powi(2)).sqrt())
        };
        let g2 = 1.0 / (1.0 + lambda(wi) + lambda(wo));
        let expect = 0.7 * d * g2 / (4.0 * wi.z * wo.z);
        let mut f = [0.0f32; 3];
        m.eval(wi, wo, &mut f);
        assert!(
            (f[0] as f64 - expect).abs() <= 1e-6 * expect + 1e-12,
            "{wi} {wo}: {} vs {expect}",
            f[0]
        );
    }
}

#[test]
fn anisotropic_with_equal_alphas_equals_isotropic() {
    let a = Ggx::isotropic(0.3, Value::Grey(0.8), conductor(), &Channels::Rgb).unwrap();
    // Through the spec, as a user would write it.
    let spec = crate::spec::ModelSpec::parse(
        r#"{"model": "ggx", "alpha_x": 0.3, "alpha_y": 0.3, "ks": 0.8,
            "fresnel": {"n": [0.2, 0.9, 1.1], "k": [3.9, 2.4, 2.2]}}"#,
    )
    .unwrap();
    let b = spec.build(&Channels::Rgb).unwrap();
    assert!(a.flags().isotropic && b.flags().isotropic);
    assert!(!aniso(0.3, 0.31).flags().isotropic);
    let mut rng = Pcg32::new(9);
    for _ in 0..1000 {
        let wi = geometry::uniform_hemisphere(rng.next_dvec2());
        let wo = geometry::uniform_hemisphere(rng.next_dvec2());
        let (mut f, mut g) = ([0.0f32; 3], [0.0f32; 3]);
        a.eval(wi, wo, &mut f);
        b.eval(wi, wo, &mut g);
        assert_eq!(f, g);
    }
}

#[test]
fn isotropic_model_is_invariant_under_rotation() {
    let m = iso(0.25);
    let mut rng = Pcg32::new(3);
    for _ in 0..500 {
        let wi = geometry::uniform_hemisphere(rng.next_dvec2());
        let wo = geometry::uniform_hemisphere(rng.next_dvec2());
        let rot = glam::DQuat::from_rotation_z(rng.next_f64() * 6.0);
        let (mut f, mut g) = ([0.0f32; 3], [0.0f32; 3]);
        m.eval(wi, wo, &mut f);
        m.eval(rot * wi, rot * wo, &mut g);
        assert!((f[0] - g[0]).abs() <= 1e-5 * f[0].abs());
    }
}

#[test]
fn bilateral_symmetry_holds_for_anisotropic() {
    let m = aniso(0.1, 0.5);
    let mut rng = Pcg32::new(4);
    let flip = |v: DVec3| DVec3::new(v.x, -v.y, v.z);
    for _ in 0..500 {
        let wi = geometry::uniform_hemisphere(rng.next_dvec2());
        let wo = geometry::uniform_hemisphere(rng.next_dvec2());
        let (mut f, mut g) = ([0.0f32; 3], [0.0f32; 3]);
        m.eval(wi, wo, &mut f);
        m.eval(flip(wi), flip(wo), &mut g);
        assert!((f[0] - g[0]).abs() <= 1e-5 * f[0].abs());
    }
}

#[test]
fn peak_value_in_closed_form() {
    // wi = wo = z: h = z, D = 1/(π α²), Λ = 0, f = k_s F(1) / (4 π α²).
    let m = Ggx::isotropic(0.2, Value::Grey(0.5), conductor(), &Channels::Rgb).unwrap();
    let mut f = [0.0f32; 3];
    m.eval(DVec3::Z, DVec3::Z, &mut f);
    for (c, (&n, &k)) in [0.2, 0.9, 1.1].iter().zip(&[3.9, 2.4, 2.2]).enumerate() {
        let f0 = ((n - 1.0f64).powi(2) + k * k) / ((n + 1.0f64).powi(2) + k * k);
        let expect = 0.5 * f0 / (4.0 * PI * 0.04);
        assert!(
            (f[c] as f64 - expect).abs() < 1e-6 * expect,
            "{c}: {} vs {expect}",
            f[c]
        );
    }
}

#[test]
fn white_furnace_loses_only_multiple_scattering() {
    // With F = 1 and k_s = 1, single-scattering GGX loses the energy of multiple bounces but
    // never gains: ∫ f cos θi dωi = ∫_{visible h, wi above} D G2 (wo·h) / cos θo dω_h ≤ 1
    // (in h, as dωi = 4 (wo·h) dωh), and the loss vanishes for smooth surfaces at normal
    // incidence.
    for (ax, ay) in [(0.02, 0.02), (0.3, 0.3), (1.0, 1.0), (0.05, 0.5)] {
        let m = aniso(ax, ay);
        for wo in test_wos() {
            let a = integrate_visible(&m, wo, |h| {
                let wi = 2.0 * wo.dot(h) * h - wo;
                if wi.z <= 0.0 {
                    return 0.0;
                }
                m.ndf(h) * m.g2(wi, wo) * wo.dot(h) / wo.z
            });
            assert!(
                a <= 1.0 + 1e-6 && a > 0.2,
                "α = ({ax}, {ay}), wo = {wo}: albedo {a}"
            );
            if ax == 0.02 && wo.z > 0.9 {
                assert!(a > 0.999, "{a}");
            }
            if ax == 0.3 {
                // The default quadrature resolves a lobe this wide.
                let mut q = [0.0; 3];
                m.albedo(wo, &mut q);
                assert!((q[0] - a).abs() < 2e-3, "wo = {wo}: {} vs {a}", q[0]);
            }
        }
    }
}

#[test]
fn below_horizon_and_nan_give_zero() {
    check_invalid_inputs_give_zero(&aniso(0.2, 0.4));
    let _ = Ggx::isotropic(0.2, Value::Grey(1.0), conductor(), &Channels::Rgb).unwrap();
}

#[test]
fn invalid_parameters_are_errors() {
    for a in [0.0, -0.1, f64::NAN, f64::INFINITY] {
        assert!(Ggx::isotropic(a, Value::Grey(1.0), FresnelSpec::None, &Channels::Rgb).is_err());
    }
}

#[test]
fn spectral_parameters_follow_eval_wavelength() {
    let ch = Channels::linspace(400.0, 700.0, 5).unwrap();
    let fresnel = FresnelSpec::Complex {
        n: Value::Spectral {
            wavelengths: vec![400.0, 700.0],
            values: vec![1.2, 0.2],
        },
        k: Value::Spectral {
            wavelengths: vec![400.0, 700.0],
            values: vec![2.0, 4.0],
        },
    };
    let m = Ggx::new(0.2, 0.3, Value::Grey(0.9), fresnel, &ch).unwrap();
    check_eval_wavelength_matches_channels(&m);
}

#[test]
fn sample_weight_and_pdf_are_consistent() {
    for (ax, ay) in [(0.01, 0.01), (0.2, 0.2), (1.0, 1.0), (0.05, 0.5)] {
        let m = Ggx::new(ax, ay, Value::Grey(0.9), conductor(), &Channels::Rgb).unwrap();
        check_sampling_consistency(&m, &test_wos(), 2000);
    }
}

#[test]
fn visible_normal_sampler_passes_chi_square_isotropic() {
    chi2_models(&[&aniso(0.05, 0.05), &aniso(0.3, 0.3), &aniso(1.0, 1.0)]);
}

#[test]
fn visible_normal_sampler_passes_chi_square_anisotropic() {
    chi2_models(&[&aniso(0.1, 0.6), &aniso(0.7, 0.15)]);
}

#[test]
fn half_vector_sampler_passes_chi_square() {
    let models: Vec<Ggx> = [(0.05, 0.05), (0.5, 0.5), (0.1, 0.6)]
        .iter()
        .map(|&(ax, ay)| aniso(ax, ay))
        .collect();
    let samplers: Vec<_> = models
        .iter()
        .map(|m| FnSampler {
            sample: move |u| Some(m.sample_half_vector(u)),
            pdf: move |h: DVec3| m.pdf_half_vector(h),
            name: format!("GGX D·cos half vectors, {}", m.describe()),
        })
        .collect();
    let cases: Vec<(&dyn Brdf, DVec3)> = samplers
        .iter()
        .map(|s| (s as &dyn Brdf, DVec3::Z))
        .collect();
    chi2_cases(&cases);
}

#[test]
fn chi_square_detects_a_slightly_wrong_density() {
    // The tests above can fail: half vectors of α = 0.3 against the density of α = 0.33.
    use crate::analysis::chi2::{Chi2Options, test};
    let (a, b) = (aniso(0.3, 0.3), aniso(0.33, 0.33));
    let wrong = FnSampler {
        sample: |u| Some(a.sample_half_vector(u)),
        pdf: |h: DVec3| b.pdf_half_vector(h),
        name: "mismatched".into(),
    };
    let o = Chi2Options {
        samples: 200_000,
        ..Default::default()
    };
    let r = test(&wrong, DVec3::Z, &o);
    assert!(!r.passes(0.01), "{r:?}");
}

#[test]
fn pairs_a_hair_above_the_horizon_keep_their_limit() {
    // At grazing G2 ~ cos θ / α and f_r ~ 1/cos θ (height-correlated Smith), so f_r cos θ and
    // the density G1(wo) D / (4 cos θo) have finite limits as both cosines go to 0, which a
    // pair at cos 1e-300 must reproduce (the quadratic terms are below 1e-20 of them there).
    let m = Ggx::new(0.1, 0.3, Value::Grey(0.9), conductor(), &Channels::Rgb).unwrap();
    let pair = |z: f64, o: DVec3| {
        let r = (1.0 - z * z).sqrt();
        (DVec3::new(0.0, r, z), DVec3::new(o.x * r, o.y * r, z))
    };
    for o in [DVec3::new(0.0, -1.0, 0.0), DVec3::new(-0.6, -0.8, 0.0)] {
        let (wi, wo) = pair(1e-20, o);
        let (f_ref, p_ref) = (m.eval_wavelength(wi, wo, 550.0) * 1e-20, m.pdf(wi, wo));
        assert!(f_ref > 0.0 && f_ref.is_finite() && p_ref > 0.0 && p_ref.is_finite());
        for z in [1e-60, 1e-100, 1e-160, 1e-200, 1e-300] {
            let (wi, wo) = pair(z, o);
            let (f, p) = (m.eval_wavelength(wi, wo, 550.0) * z, m.pdf(wi, wo));
            assert!(
                (f / f_ref - 1.0).abs() < 1e-12,
                "{o} z={z:e}: f cos {f:e} vs {f_ref:e}"
            );
            assert!(
                (p / p_ref - 1.0).abs() < 1e-12,
                "{o} z={z:e}: pdf {p:e} vs {p_ref:e}"
            );
            // The f32 value overflows (f_r really is beyond f32 there), but is never NaN.
            let mut out = [0f32; 3];
            m.eval(wi, wo, &mut out);
            assert!(out.iter().all(|x| *x > 0.0), "{o} z={z:e}: {out:?}");
        }
    }
}

#[test]
fn a_sample_at_a_grazing_view_has_the_density_pdf_gives() {
    // The sampler's closed-form pdf left |h|⁴ · 4 cos θo in its denominator, subnormal at
    // cos θo = 1e-300 for α ≤ 1e-3 (50 % off pdf(wi, wo) at α = 1e-4) and at the subnormal
    // cosine 5e-324 for any α (2.1× at α = 1). What it must agree with is pdf(), which
    // `pairs_a_hair_above_the_horizon_keep_their_limit` holds to its limit.
    for (ax, ay) in [
        (1e-4, 1e-4),
        (1e-3, 1e-3),
        (1e-3, 0.5),
        (1.0, 1.0),
        (10.0, 0.3),
    ] {
        let m = aniso(ax, ay);
        let wos: Vec<DVec3> = [1e-100, 1e-300, f64::from_bits(1)]
            .into_iter()
            .flat_map(|z| [DVec3::new(1.0, 0.0, z), DVec3::new(0.6, -0.8, z)])
            .collect();
        check_sampling_consistency(&m, &wos, 2000);
    }
}

proptest! {
    #[test]
    fn reciprocal(a in dir_strategy(), b in dir_strategy(), ax in 0.01f64..1.5, ay in 0.01f64..1.5) {
        let m = Ggx::new(ax, ay, Value::Grey(0.9), conductor(), &Channels::Rgb).unwrap();
        check_reciprocity(&m, a, b)?;
    }
}
