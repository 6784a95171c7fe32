//! The kernel's lookups against their references: the fast variables against the angles, the
//! kernel against the general lookup and `TabulatedBrdf`, the lane blends against the scalar
//! one, and the resampled fixed mappings.
//!
//! Why a file of its own: these tests bake tables and cover the kernel as a whole (variables,
//! blends, projection, calibration). The storage format's test is in `packed`, the eight-lane
//! path's in `x8`.

#[cfg(target_arch = "x86_64")]
use super::build::has_f16c;
use super::*;
use crate::brdf::Brdf;
use crate::rng::Pcg32;
use crate::spec::ModelSpec;
use crate::spectrum::Channels;
use crate::table::adaptive::adaptive_grid;
use crate::table::grid::Mapping;
use crate::table::symmetry::Symmetry;
use crate::table::warp::Warp;
use crate::table::{BakeOptions, TabulatedBrdf, bake, lookup::Interp, lookup::Lookup};

fn random_pair(r: &mut Pcg32) -> (DVec3, DVec3) {
    let d = |r: &mut Pcg32| {
        let (u, v) = (r.next_f64(), r.next_f64());
        let z = u.max(1e-9);
        let s = (1.0 - z * z).sqrt();
        let p = std::f64::consts::TAU * v;
        DVec3::new(s * p.cos(), s * p.sin(), z)
    };
    (d(r), d(r))
}

fn test_kernel(quarter: bool, h_quarter_power: bool) -> Kernel {
    let axes = std::array::from_fn(|_| Axis::new(&Warp::identity(WarpVar::HalfPower), 2, false));
    let per = |x: f32| F4::new(x, x, x, 0.0);
    Kernel {
        axes,
        quarter,
        h_quarter_power,
        channels: 1,
        row: 2,
        chunk: 4,
        lanes: [per(1.0), per(0.5), per(1.0), per(0.5)],
        #[cfg(target_arch = "x86_64")]
        f16c: false,
        cut: F4::splat(2.0),
        resampled: false,
        cuts: false,
        exact: false,
        quantity: Quantity::Fr,
        calibration: None,
        x8: false,
    }
}

#[test]
fn fast_variables_match_the_angles() {
    for (quarter, hq) in [(false, false), (true, false), (false, true), (true, true)] {
        let mut r = Pcg32::new(71);
        let k = test_kernel(quarter, hq);
        let h_var = if hq {
            WarpVar::QuarterPower
        } else {
            WarpVar::SqrtSine
        };
        for _ in 0..100_000 {
            let (wi, wo) = random_pair(&mut r);
            let f = k.vars(wi, wo).unwrap();
            let g = reference_vars(wi, wo, quarter, h_var).unwrap();
            // The lane version does the same IEEE operations.
            let l = k.vars_lanes(wi, wo).unwrap().0.to_array();
            assert_eq!(&l[..3], &f[..], "{wi} {wo}");
            // f32 arithmetic without cancellation: a few ulps of v ≤ 1. φd itself is
            // only as good as h = ωi + ωo in f32 relative to sin θh (it is undefined at
            // θh = 0, where an isotropic BRDF does not depend on it). v_h² ≤ sin θh for
            // both variables (√2 sin(θh/2) ≤ sin θh up to 90°).
            let sin_h = (g[0] * g[0]).max(1e-12);
            assert!((f[0] as f64 - g[0]).abs() < 1e-5, "{wi} {wo}: {f:?} {g:?}");
            assert!((f[1] as f64 - g[1]).abs() < 1e-5, "{wi} {wo}: {f:?} {g:?}");
            assert!(
                (f[2] as f64 - g[2]).abs() < 1e-5 + 1e-6 / sin_h,
                "{wi} {wo}: {f:?} {g:?}"
            );
        }
    }
}

/// `src` baked on the adaptive grid of one of [`TEST_CASES`] (isotropic, bilateral), and
/// its kernel.
fn test_table(
    src: &dyn Brdf,
    (reciprocal, quantity, h_var): (bool, Quantity, WarpVar),
) -> (crate::table::Table, Kernel) {
    let sym = Symmetry {
        isotropic: true,
        reciprocal,
        bilateral: true,
    };
    let opts = test_adaptive_options(quantity, h_var);
    let grid = adaptive_grid(src, sym, &opts).unwrap();
    let (t, _) = bake(src, &grid, &BakeOptions::default()).unwrap();
    let k = Kernel::new(t.grid()).expect("an adaptive grid has a kernel");
    (t, k)
}

#[test]
fn kernel_agrees_with_the_general_lookup() {
    let src = ModelSpec::parse(r#"{"model": "ggx", "alpha": 0.05}"#)
        .unwrap()
        .build(&Channels::Rgb)
        .unwrap();
    // f_r tables (θh by SqrtSine and QuarterPower) and tables of the other quantities, whose
    // lookups divide by the cosines (and whose nodes beyond the horizon are extrapolated).
    for (reciprocal, quantity, h_var) in TEST_CASES {
        let (t, k) = test_table(src.as_ref(), (reciprocal, quantity, h_var));
        let general = Lookup::new(t.grid());
        let tb = TabulatedBrdf::from_table(t.clone());
        let packed = Packed::new(t.values());
        let mut r = Pcg32::new(32);
        let (mut a, mut b, mut c, mut d) = ([0f32; 3], [0f32; 3], [0f32; 3], [0f32; 3]);
        let mut soft = [0f32; 3];
        let peak = t.values().iter().fold(0f32, |m, &x| m.max(x.abs()));
        let mut worst = 0f32;
        for _ in 0..50_000 {
            let (wi, wo) = random_pair(&mut r);
            // What the lookup divides the interpolated quantity by.
            let s = match geometry::upper_pair(wi, wo) {
                Some((i, o)) => 1.0 / quantity.factor(i.z, o.z) as f32,
                None => 0.0,
            };
            k.eval(wi, wo, &mut a, &packed);
            // Without F16C (the integer expansion) exactly the same.
            k.rgb::<false, false, false>(wi, wo, &mut soft, &packed);
            assert_eq!(a, soft, "{wi} {wo}");
            general.eval(Interp::Linear, wi, wo, &mut b, |i| t.chunk(i));
            project_out(quantity, None, wi, wo, &mut b);
            tb.eval(wi, wo, &mut c);
            // The four-lane RGB path against its scalar reference, `blend::<3>`.
            if let Some(v) = k.vars(wi, wo) {
                k.blend::<3>(v, &mut d, &packed);
                project_out(quantity, None, wi, wo, &mut d);
                for ch in 0..3 {
                    assert!((a[ch] - d[ch]).abs() <= 1e-6 * d[ch].abs(), "{a:?} {d:?}");
                }
            }
            for ch in 0..3 {
                // Both interpolate the same nodes; they differ by the values' f16
                // rounding (≤ 2^-11 of each, so of the blend) and the f32 variables (a few
                // 1e-7) times the slope in node units: below 1e-3 of the value plus 1e-4 of
                // the table's peak (both divided by the quantity's factor).
                let e = (a[ch] - b[ch]).abs() / (b[ch].abs() * 1e-3 + peak * 1e-4 * s);
                worst = worst.max(e);
                assert_eq!(a[ch], c[ch], "TabulatedBrdf uses the kernel");
            }
        }
        assert!(worst <= 1.0, "worst scaled difference {worst}");
    }
}

/// Tables of other than three channels blend four channels at a time
/// (`Kernel::blend_lanes`): bit-equal to the one-value-at-a-time reference `blend::<0>`, for
/// f16 codes (F16C and integer expansion) and exact values, at channel counts that leave
/// every remainder of four, on tables of each quantity.
#[test]
fn blends_of_any_channel_count_equal_their_reference() {
    for nch in [1usize, 2, 5, 7, 12] {
        let nm: Vec<f64> = (0..nch)
            .map(|i| 400.0 + 300.0 * i as f64 / nch as f64)
            .collect();
        let channels = Channels::Wavelengths(nm);
        let src = ModelSpec::parse(
            r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2},
                {"model": "ggx", "alpha": 0.1, "fresnel": {"conductor": "Au"}}]}"#,
        )
        .unwrap()
        .build(&channels)
        .unwrap();
        for (reciprocal, quantity, h_var) in TEST_CASES {
            let (t, k) = test_table(src.as_ref(), (reciprocal, quantity, h_var));
            let (packed, exact) = (Packed::new(t.values()), Packed::exact(t.values()));
            // The same table calibrated (symmetric factors where it folds by reciprocity):
            // its `eval` (the lanes, the projection, the calibration found before the
            // blend) against the plain steps.
            let calibrated = {
                let k_in: Vec<f32> = (0..17 * nch).map(|i| 0.9 + 0.001 * i as f32).collect();
                let k_out: Vec<f32> = if reciprocal {
                    k_in.clone()
                } else {
                    (0..17 * nch).map(|i| 1.2 - 0.002 * i as f32).collect()
                };
                let cal = Calibration::new(k_in, Some(k_out), nch, 0.99).unwrap();
                let g = t.grid().clone().with_calibration(cal.clone()).unwrap();
                Some((Kernel::new(&g).expect("a kernel"), cal))
            };
            let mut r = Pcg32::new(7 + nch as u64);
            let (mut a, mut b) = (vec![0f32; nch], vec![0f32; nch]);
            for _ in 0..20_000 {
                let (wi, wo) = random_pair(&mut r);
                let Some(v) = k.vars(wi, wo) else { continue };
                if let Some((kc, cal)) = &calibrated {
                    kc.eval(wi, wo, &mut a, &packed);
                    kc.blend::<0>(v, &mut b, &packed);
                    let cos = [wi.z as f32, wo.z as f32];
                    project_f32(quantity, Some(cal), cos, &mut b);
                    assert_eq!(a, b, "{nch} channels, calibrated eval: {wi} {wo}");
                }
                for (values, exact) in [(&packed, false), (&exact, true)] {
                    k.blend::<0>(v, &mut b, values);
                    // The projection (quantity and clamp) four at a time, too.
                    let cos = [wi.z as f32, wo.z as f32];
                    let (mut p, mut q) = (b.clone(), b.clone());
                    project_f32(quantity, None, cos, &mut p);
                    project_f32_lanes(quantity, None, cos, &mut q);
                    assert_eq!(p, q, "{nch} channels, projection: {wi} {wo}");
                    if exact {
                        k.blend_lanes::<false, true>(v, &mut a, values);
                        assert_eq!(a, b, "{nch} channels, exact: {wi} {wo}");
                        continue;
                    }
                    k.blend_lanes::<false, false>(v, &mut a, values);
                    assert_eq!(a, b, "{nch} channels, integer expansion: {wi} {wo}");
                    #[cfg(target_arch = "x86_64")]
                    if has_f16c() {
                        // SAFETY: the CPU has F16C.
                        unsafe { k.blend_lanes_f16c(v, &mut a, values) };
                        assert_eq!(a, b, "{nch} channels, F16C: {wi} {wo}");
                    }
                }
            }
        }
    }
}

#[test]
fn fixed_mappings_are_resampled_without_a_cut_and_agree_with_the_general_lookup() {
    use crate::table::grid::Grid;
    use crate::table::presets::Preset;
    let src = ModelSpec::parse(r#"{"model": "cook_torrance", "m": 0.3}"#)
        .unwrap()
        .build(&Channels::Rgb)
        .unwrap();
    for reciprocal in [false, true] {
        let sym = Symmetry {
            isotropic: true,
            reciprocal,
            bilateral: true,
        };
        // The MERL-size grid of `--grid 90x1x90x180 --param halfdiff` (sqrt θh, uniform θd)
        // and the small preset's (sqrt θh, cos θd).
        let merl = Grid::with_sizes(
            crate::table::Param::HalfDiff,
            [90, 1, 90, 180],
            [Mapping::Sqrt, Mapping::Uniform],
            Channels::Rgb,
            sym,
        )
        .unwrap();
        let preset = Preset::Small.grid(None, sym, Channels::Rgb).unwrap();
        assert_eq!(preset.axes()[2].mapping, Mapping::Cos);
        let k = Kernel::new(&merl).expect("sqrt/uniform axes are resampled");
        // Exact values, also beyond L2 (1.1 M values here).
        assert!(k.resampled() && k.exact_values());
        let kp = Kernel::new(&preset).expect("sqrt/cos axes are resampled");
        assert!(kp.resampled() && kp.exact_values());
        for (grid, k) in [(&merl, &k), (&preset, &kp)] {
            // θh read as (1 − cos θh)^¼, in which sqrt θh is smooth up to 90°: no cut.
            assert_eq!(k.h_var(), WarpVar::QuarterPower);
            assert!(!k.has_cut(), "{:?}", k.cut.to_array());
            let (t, _) = bake(src.as_ref(), grid, &BakeOptions::default()).unwrap();
            let general = Lookup::new(t.grid());
            let packed = Packed::for_kernel(k, t.values());
            let tb = TabulatedBrdf::from_table(t.clone());
            let peak = t.values().iter().fold(0f32, |m, &x| m.max(x));
            let (mut a, mut b, mut c) = ([0f32; 3], [0f32; 3], [0f32; 3]);
            let mut worst = 0f32;
            let mut r = Pcg32::new(8);
            for i in 0..60_000 {
                let (mut wi, mut wo) = random_pair(&mut r);
                if i % 10 == 0 {
                    // Near-grazing opposite pairs: θh near 90°, where v_h = √sin θh
                    // needed a cut.
                    wi = DVec3::new(0.999, 0.0, 0.0447).normalize();
                    wo = DVec3::new(-0.9, -0.4, 0.02 + 0.01 * r.next_f64()).normalize();
                }
                general.eval(Interp::Linear, wi, wo, &mut b, |i| t.chunk(i));
                tb.eval(wi, wo, &mut c);
                assert!(k.eval(wi, wo, &mut a, &packed), "no pair leaves the kernel");
                assert_eq!(a, c, "TabulatedBrdf uses the kernel");
                if !k.exact_values() {
                    // Without F16C (the integer expansion) exactly the same.
                    let mut soft = [0f32; 3];
                    assert!(k.rgb::<false, false, true>(wi, wo, &mut soft, &packed));
                    assert_eq!(a, soft, "{wi} {wo}");
                }
                for ch in 0..3 {
                    // The same nodes; the kernel's f16 codes (≤ 2^-11 of each value, so of
                    // the blend), f32 variables and knot lines (≤ 1e-4 node units from the
                    // mapping) against the general lookup's f32 values and f64
                    // coordinates.
                    let e = (a[ch] - b[ch]).abs() / (b[ch].abs() * 1e-3 + peak * 1e-5);
                    worst = worst.max(e);
                }
            }
            assert!(worst <= 1.0, "worst scaled difference {worst}");
        }
    }
}
