//! The eight-lane path's unit tests: its lanes bit-equal to the one-pair lookup on every kind of
//! pair and table (RGB and spectral, every quantity, calibrated, exact values), and directions
//! unit only in f32 evaluated as their normalized selves.

use super::*;
use crate::brdf::Brdf;
use crate::rng::Pcg32;
use crate::spec::ModelSpec;
use crate::spectrum::Channels;
use crate::table::adaptive::adaptive_grid;
use crate::table::calibration::Calibration;
use crate::table::grid::{Grid, Mapping, Param, Quantity};
use crate::table::symmetry::Symmetry;
use crate::table::{BakeOptions, Table, TabulatedBrdf, bake};

/// Pairs of every kind the lanes meet: random, near the normal and the horizon, mirror
/// pairs, exact normals, below the horizon, unit only to f32 precision, not unit length,
/// NaN.
fn pairs(n: usize, seed: u64) -> (Vec<DVec3>, Vec<DVec3>) {
    let mut r = Pcg32::new(seed);
    let dir = |r: &mut Pcg32, zmin: f64, zmax: f64| {
        let z = zmin + (zmax - zmin) * r.next_f64();
        let s = (1.0 - z * z).max(0.0).sqrt();
        let p = std::f64::consts::TAU * r.next_f64();
        DVec3::new(s * p.cos(), s * p.sin(), z)
    };
    (0..n)
        .map(|i| {
            let a = dir(&mut r, 0.0, 1.0);
            match i % 23 {
                0 => (dir(&mut r, 0.999_999, 1.0), a),
                1 => (a, dir(&mut r, 0.0, 1e-3)),
                2 => (a, DVec3::new(-a.x, -a.y, a.z)),
                3 => (DVec3::Z, DVec3::Z),
                4 => (a, DVec3::Z),
                5 => (dir(&mut r, -1.0, 0.0), a),
                6 if i % 7 == 0 => (2.0 * a, a),
                7 if i % 11 == 0 => (DVec3::new(f64::NAN, 0.0, 1.0), a),
                // As renderers pass them: unit in f32 (corrected in the lanes), one or both.
                8 => (a.as_vec3().normalize().as_dvec3(), dir(&mut r, 0.0, 1.0)),
                9 => (
                    a.as_vec3().as_dvec3(),
                    dir(&mut r, 0.0, 1.0).as_vec3().as_dvec3(),
                ),
                _ => (a, dir(&mut r, 0.0, 1.0)),
            }
        })
        .unzip()
}

/// RGB tables of every kind, and spectral ones (4, 5, 7 and 10 channels: whole and partial
/// runs of four) of the kinds that change the general path's end (quantity, calibration,
/// exact values).
fn tables() -> Vec<(String, Table)> {
    let mut out = rgb_tables();
    let spectral = [
        (
            7,
            (
                false,
                Quantity::FrCosOut,
                super::super::WarpVar::QuarterPower,
            ),
        ),
        (
            5,
            (true, Quantity::FrCosCos, super::super::WarpVar::SqrtSine),
        ),
        (4, (false, Quantity::Fr, super::super::WarpVar::SqrtSine)),
    ];
    let sym = |reciprocal| Symmetry {
        isotropic: true,
        reciprocal,
        bilateral: true,
    };
    let ggx_at = |c: usize| {
        let ch = Channels::linspace(420.0, 680.0, c).unwrap();
        let spec = r#"{"model": "ggx", "alpha": 0.05, "fresnel": {"conductor": "Au"}}"#;
        (ModelSpec::parse(spec).unwrap().build(&ch).unwrap(), ch)
    };
    for (c, (reciprocal, quantity, h_var)) in spectral {
        let (ggx, _) = ggx_at(c);
        let opts = super::super::test_adaptive_options(quantity, h_var);
        let grid = adaptive_grid(ggx.as_ref(), sym(reciprocal), &opts).unwrap();
        let (t, _) = bake(ggx.as_ref(), &grid, &BakeOptions::default()).unwrap();
        let name = format!("{c} channels, adaptive {quantity:?} {h_var:?}");
        if quantity == Quantity::FrCosOut {
            let f: Vec<f32> = (0..9 * c).map(|i| 0.9 + 0.02 * (i % 11) as f32).collect();
            let o: Vec<f32> = f.iter().rev().copied().collect();
            let cal = Calibration::new(f, Some(o), c, 0.95).unwrap();
            let (g, v, _) = t.clone().into_parts();
            let cal = Table::new(g.with_calibration(cal).unwrap(), v, "calibrated").unwrap();
            out.push((format!("{name}, calibrated"), cal));
        }
        out.push((name, t));
    }
    let (ggx, ch) = ggx_at(10);
    let grid = Grid::with_sizes(
        Param::HalfDiff,
        [16, 1, 16, 32],
        [Mapping::Sqrt, Mapping::Cos],
        ch,
        sym(true),
    )
    .unwrap();
    let (t, _) = bake(ggx.as_ref(), &grid, &BakeOptions::default()).unwrap();
    out.push(("10 channels, resampled θd Cos".into(), t));
    out
}

fn rgb_tables() -> Vec<(String, Table)> {
    let ggx = ModelSpec::parse(r#"{"model": "ggx", "alpha": 0.05}"#)
        .unwrap()
        .build(&Channels::Rgb)
        .unwrap();
    let mut out = Vec::new();
    for (reciprocal, quantity, h_var) in super::super::TEST_CASES {
        let sym = Symmetry {
            isotropic: true,
            reciprocal,
            bilateral: true,
        };
        let opts = super::super::test_adaptive_options(quantity, h_var);
        let grid = adaptive_grid(ggx.as_ref(), sym, &opts).unwrap();
        let (t, _) = bake(ggx.as_ref(), &grid, &BakeOptions::default()).unwrap();
        let name = format!("adaptive {quantity:?} {h_var:?} reciprocal {reciprocal}");
        if quantity == Quantity::FrCosOut {
            // Calibrated on both sides, as measured tables are.
            let f: Vec<f32> = (0..27).map(|i| 0.9 + 0.02 * (i % 11) as f32).collect();
            let o: Vec<f32> = f.iter().rev().copied().collect();
            let cal = Calibration::new(f, Some(o), 3, 0.95).unwrap();
            let (g, v, _) = t.clone().into_parts();
            let c = Table::new(g.with_calibration(cal).unwrap(), v, "calibrated").unwrap();
            out.push((format!("{name}, calibrated"), c));
        }
        out.push((name, t));
    }
    // Fixed mappings, resampled (exact values, no cut): MERL-style (uniform θd) and the
    // presets' (cos θd).
    let fixed = [
        ([16, 1, 16, 32], Mapping::Uniform),
        ([90, 1, 90, 180], Mapping::Uniform),
        ([16, 1, 16, 32], Mapping::Cos),
    ];
    for (sizes, theta_d) in fixed {
        let sym = Symmetry {
            isotropic: true,
            reciprocal: true,
            bilateral: true,
        };
        let grid = Grid::with_sizes(
            Param::HalfDiff,
            sizes,
            [Mapping::Sqrt, theta_d.clone()],
            Channels::Rgb,
            sym,
        )
        .unwrap();
        let (t, _) = bake(ggx.as_ref(), &grid, &BakeOptions::default()).unwrap();
        out.push((format!("resampled {sizes:?} θd {theta_d:?}"), t));
    }
    out
}

/// A renderer's f32 directions (unit only to f32 rounding) take the kernel's paths —
/// corrected by `geometry::near_unit`, not left to the general path — and evaluate as the
/// same directions normalized in f64 do: to f32 rounding of the kernel's variables.
#[test]
fn directions_unit_in_f32_evaluate_as_their_normalized_selves() {
    let mut r = Pcg32::new(3);
    for (name, t) in tables() {
        let k = Kernel::new(t.grid()).expect("every case has a kernel");
        let packed = Packed::for_kernel(&k, t.values());
        let peak = t.values().iter().fold(0f32, |m, &x| m.max(x.abs()));
        let c = t.grid().channels().len();
        let (mut a, mut b) = ([0f32; 16], [0f32; 16]);
        let (a, b) = (&mut a[..c], &mut b[..c]);
        let mut rounded = 0;
        for _ in 0..5000 {
            let wi = crate::geometry::uniform_hemisphere(r.next_dvec2());
            let wo = crate::geometry::uniform_hemisphere(r.next_dvec2());
            let (fi, fo) = (
                wi.as_vec3().normalize().as_dvec3(),
                wo.as_vec3().normalize().as_dvec3(),
            );
            rounded += usize::from(!crate::geometry::is_unit_l2(fi.length_squared()));
            let fast = k.eval(fi, fo, a, &packed);
            let reference = k.eval(fi.normalize(), fo.normalize(), b, &packed);
            assert_eq!(fast, reference, "{name}: {fi} {fo}");
            for c in 0..c {
                assert!(
                    (a[c] - b[c]).abs() <= 1e-6 * b[c].abs() + 1e-7 * peak,
                    "{name}: {fi} {fo}: {a:?} against {b:?}"
                );
            }
        }
        assert!(
            rounded > 1000,
            "{name}: {rounded} rounded directions off unit"
        );
        if available() {
            // The eight-lane path takes them (it used to leave every such group to the
            // one-pair path, whose general path normalized each: 4.5–5.5× slower batches).
            let (mut left, mut lanes) = (0u32, vec![0f32; c * LANES]);
            for _ in 0..500 {
                let gi: Vec<DVec3> = (0..LANES)
                    .map(|_| crate::geometry::uniform_hemisphere(r.next_dvec2()))
                    .map(|w| w.as_vec3().normalize().as_dvec3())
                    .collect();
                let go: Vec<DVec3> = (0..LANES)
                    .map(|_| crate::geometry::uniform_hemisphere(r.next_dvec2()))
                    .map(|w| w.as_vec3().as_dvec3())
                    .collect();
                left += k.eval_x8(&gi, &go, &mut lanes, &packed).count_ones();
            }
            assert!(
                left < 200,
                "{name}: {left} of 4000 f32 pairs left to the one-pair path"
            );
        }
    }
}

#[test]
fn eight_lanes_are_bit_equal_to_one_pair_at_a_time() {
    let (wi, wo) = pairs(40_000, 17);
    for (name, t) in tables() {
        let k = Kernel::new(t.grid()).expect("every case has a kernel");
        let packed = Packed::for_kernel(&k, t.values());
        assert_eq!(k.has_x8(), available(), "{name}");
        let c = t.grid().channels().len();
        let (mut taken, mut left) = (0usize, 0usize);
        let mut lanes = vec![0f32; c * LANES];
        let mut one = vec![0f32; c];
        for (gi, go) in wi.chunks_exact(LANES).zip(wo.chunks_exact(LANES)) {
            let mask = k.eval_x8(gi, go, &mut lanes, &packed);
            for j in 0..LANES {
                let fast = k.eval(gi[j], go[j], &mut one, &packed);
                if mask & (1 << j) != 0 {
                    left += 1;
                    continue;
                }
                taken += 1;
                assert!(fast, "{name}: a pair the one-pair path leaves was taken");
                let got = &lanes[c * j..c * (j + 1)];
                assert_eq!(
                    got.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                    one.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                    "{name}: {} {}: {got:?} vs {one:?}",
                    gi[j],
                    go[j]
                );
            }
        }
        if available() {
            // Left: the non-unit and NaN directions (pairs 6 and 7 of 23, on every 7th
            // and 11th cycle).
            assert!(taken > 3 * left, "{name}: {taken} taken, {left} left");
            assert!(left > 0, "{name}: leaving a lane was never exercised");
        } else {
            eprintln!("{name}: no AVX2/F16C here, the eight-lane path is not taken");
        }
        // The batch call (eight lanes where they apply, the rest one pair at a time) gives
        // the one-pair values, remainder included.
        let tb = TabulatedBrdf::from_table(t);
        let n = wi.len() - 5;
        let mut batch = vec![0f32; c * n];
        tb.eval_batch(&wi[..n], &wo[..n], &mut batch);
        for j in 0..n {
            tb.eval(wi[j], wo[j], &mut one);
            let got = &batch[c * j..c * (j + 1)];
            assert_eq!(
                got.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                one.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                "{name}: pair {j}"
            );
        }
    }
}
