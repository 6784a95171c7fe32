//! [`DeviceLayout::eval`] against [`TabulatedBrdf`]'s lookup, for every table kind.

use super::*;
use crate::brdf::Brdf;
use crate::rng::Pcg32;
use crate::spec::ModelSpec;
use crate::spectrum::Channels;
use crate::table::adaptive::adaptive_grid;
use crate::table::grid::{Grid, Mapping};
use crate::table::{BakeOptions, TabulatedBrdf, bake};

fn sym(isotropic: bool, reciprocal: bool, bilateral: bool) -> Symmetry {
    Symmetry {
        isotropic,
        reciprocal,
        bilateral,
    }
}

fn source(spec: &str, channels: &Channels) -> Box<dyn Brdf> {
    ModelSpec::parse(spec).unwrap().build(channels).unwrap()
}

const GGX: &str = r#"{"model": "ggx", "alpha": 0.2}"#;
const WARD: &str = r#"{"model": "ward", "alpha_x": 0.2, "alpha_y": 0.4, "ks": 0.5}"#;

/// Random pairs (some below the horizon, some not unit), near-specular pairs and pairs
/// rounded to f32 (what a device's directions are).
fn pairs() -> Vec<(DVec3, DVec3)> {
    let mut r = Pcg32::new(11);
    let dir = |r: &mut Pcg32| {
        let z = r.next_f64() * 1.1 - 0.05;
        let s = (1.0 - z * z).max(0.0).sqrt();
        let p = std::f64::consts::TAU * r.next_f64();
        DVec3::new(s * p.cos(), s * p.sin(), z)
    };
    let mut out = Vec::new();
    for i in 0..40_000 {
        let wi = dir(&mut r);
        let mut wo = dir(&mut r);
        if i % 3 == 0 {
            let n = dir(&mut r) * 1e-3;
            wo = DVec3::new(-wi.x, -wi.y, wi.z) + n;
        }
        let f32_of = |v: DVec3| v.as_vec3().as_dvec3();
        match i % 4 {
            0 => out.push((f32_of(wi), f32_of(wo))),
            1 => out.push((wi * 2.5, wo)),
            _ => out.push((wi, wo)),
        }
    }
    out
}

/// Compares the device layout with the table's lookup for both interpolations; returns the
/// largest relative difference (exact equality is expected).
fn check(name: &str, table: Table, want_kind: DeviceKind) {
    let c = table.grid().channels().len();
    for interp in [Interp::Linear, Interp::Nearest] {
        let d = DeviceLayout::new(&table, interp).unwrap();
        let moved = DeviceLayout::from_table(table.clone(), interp).unwrap();
        let values = |d: &DeviceLayout| d.grid.as_ref().map(|g| g.values.clone());
        assert_eq!(values(&d), values(&moved), "{name}");
        assert_eq!(d.version, VERSION);
        let kind = if interp == Interp::Nearest {
            DeviceKind::Grid
        } else {
            want_kind
        };
        assert_eq!(d.kind, kind, "{name} {interp:?}");
        let tb = TabulatedBrdf::from_table(table.clone()).with_interp(interp);
        let (mut a, mut b) = (vec![0f32; c], vec![0f32; c]);
        let mut nonzero = 0;
        for (wi, wo) in pairs() {
            d.eval(wi, wo, &mut a);
            tb.eval(wi, wo, &mut b);
            assert_eq!(a, b, "{name} {interp:?}: {wi} {wo}");
            nonzero += (b[0] != 0.0) as usize;
        }
        assert!(nonzero > 10_000, "{name}: {nonzero}");
    }
}

fn baked(spec: &str, grid: Grid) -> Table {
    let src = source(spec, grid.channels());
    bake(src.as_ref(), &grid, &BakeOptions::default())
        .unwrap()
        .0
}

fn sized(param: Param, sizes: [usize; 4], m: [Mapping; 2], s: Symmetry) -> Grid {
    Grid::with_sizes(param, sizes, m, Channels::Rgb, s).unwrap()
}

#[test]
fn grid_layouts_evaluate_as_the_table() {
    use Mapping::{Sqrt, Uniform};
    use Param::{HalfDiff, InOut};
    let cases = [
        ("MERL grid", GGX, Grid::merl(Channels::Rgb)),
        (
            "inout isotropic",
            GGX,
            sized(
                InOut,
                [16, 1, 16, 32],
                [Uniform, Uniform],
                sym(true, false, false),
            ),
        ),
        (
            "inout isotropic bilateral",
            GGX,
            sized(
                InOut,
                [16, 1, 16, 32],
                [Uniform, Uniform],
                sym(true, false, true),
            ),
        ),
        (
            "inout packed reciprocal isotropic",
            GGX,
            sized(
                InOut,
                [16, 1, 16, 32],
                [Uniform, Uniform],
                sym(true, true, true),
            ),
        ),
        (
            "inout packed reciprocal anisotropic",
            WARD,
            sized(
                InOut,
                [8, 16, 8, 16],
                [Uniform, Uniform],
                sym(false, true, true),
            ),
        ),
        (
            "inout anisotropic bilateral",
            WARD,
            sized(
                InOut,
                [16, 16, 16, 16],
                [Uniform, Uniform],
                sym(false, false, true),
            ),
        ),
        (
            "halfdiff anisotropic",
            WARD,
            sized(
                HalfDiff,
                [16, 16, 12, 16],
                [Sqrt, Uniform],
                sym(false, true, true),
            ),
        ),
        (
            "halfdiff no symmetry",
            WARD,
            sized(
                HalfDiff,
                [12, 16, 8, 16],
                [Sqrt, Uniform],
                sym(false, false, false),
            ),
        ),
    ];
    for (name, spec, grid) in cases {
        let t = baked(spec, grid);
        if name == "halfdiff anisotropic" {
            // A model's default table where the preset misses the albedo: its own values
            // times one symmetric factor k(θi) k(θo) (it folds by reciprocity).
            let c = calibrated(t.clone(), true);
            check(&format!("{name}, calibrated"), c, DeviceKind::Grid);
        }
        check(name, t, DeviceKind::Grid);
    }
}

/// `t` times a calibration on 9 nodes, k_in = k_out where `symmetric`.
fn calibrated(t: Table, symmetric: bool) -> Table {
    let c = t.grid().channels().len();
    let f: Vec<f32> = (0..9 * c).map(|i| 0.9 + 0.02 * (i % 11) as f32).collect();
    let o: Vec<f32> = if symmetric {
        f.clone()
    } else {
        f.iter().rev().copied().collect()
    };
    let cal = Calibration::new(f, Some(o), c, 0.95).unwrap();
    let (g, v, _) = t.into_parts();
    Table::new(g.with_calibration(cal).unwrap(), v, "calibrated").unwrap()
}

#[test]
fn kernel_layouts_evaluate_as_the_table() {
    use crate::table::warp::WarpVar;
    let spectral = Channels::wavelengths(vec![450.0, 550.0, 650.0, 700.0]).unwrap();
    let cases = [
        (
            Quantity::Fr,
            WarpVar::SqrtSine,
            sym(true, true, true),
            Channels::Rgb,
        ),
        (
            Quantity::FrCosOut,
            WarpVar::QuarterPower,
            sym(true, false, true),
            Channels::Rgb,
        ),
        (
            Quantity::FrCosCos,
            WarpVar::SqrtSine,
            sym(true, true, true),
            spectral.clone(),
        ),
        (
            Quantity::Fr,
            WarpVar::QuarterPower,
            sym(true, false, true),
            spectral,
        ),
    ];
    for (quantity, h_var, s, channels) in cases {
        let opts = crate::table::kernel::test_adaptive_options(quantity, h_var);
        let src = source(GGX, &channels);
        let grid = adaptive_grid(src.as_ref(), s, &opts).unwrap();
        let t = baked(GGX, grid);
        let name = format!(
            "adaptive {quantity:?} {h_var:?} {} channels",
            channels.len()
        );
        check(&name, t.clone(), DeviceKind::Kernel);
        assert!(
            DeviceLayout::new(&t, Interp::Linear)
                .unwrap()
                .grid
                .is_none()
        );
        // Calibrated: k_in and k_out on 9 nodes (the same factors where the table folds by
        // reciprocity), on every quantity.
        let c = calibrated(t, s.reciprocal);
        check(&format!("{name}, calibrated"), c, DeviceKind::Kernel);
    }
    // Fixed mappings, resampled: MERL-style (sqrt θh, uniform θd) and the presets' (cos θd),
    // exact values (small) and f16 codes (MERL size). No axis has a cut, so no grid beside.
    let fixed = [
        ([16, 1, 16, 32], Mapping::Uniform),
        ([90, 1, 90, 180], Mapping::Uniform),
        ([16, 1, 16, 32], Mapping::Cos),
    ];
    for (sizes, theta_d) in fixed {
        let cos = theta_d == Mapping::Cos;
        let name = format!("resampled {sizes:?} θd {theta_d:?}");
        let g = sized(
            Param::HalfDiff,
            sizes,
            [Mapping::Sqrt, theta_d],
            sym(true, true, true),
        );
        let t = baked(GGX, g);
        assert!(
            DeviceLayout::new(&t, Interp::Linear)
                .unwrap()
                .grid
                .is_none()
        );
        if cos {
            // The presets' mapping, calibrated (a model's default table where the preset
            // misses the albedo and its adaptive table does not serve).
            let c = calibrated(t.clone(), true);
            check(&format!("{name}, calibrated"), c, DeviceKind::Kernel);
        }
        check(&name, t, DeviceKind::Kernel);
    }
}

#[test]
fn f_r_tables_read_negative_values_as_zero() {
    let g = sized(
        Param::InOut,
        [4, 1, 4, 8],
        [Mapping::Uniform, Mapping::Uniform],
        sym(true, false, true),
    );
    let mut t = baked(GGX, g);
    for (i, x) in t.values_mut().iter_mut().enumerate() {
        if i % 5 == 0 {
            *x = -1.0;
        }
    }
    check("unmeasured cells", t, DeviceKind::Grid);
}

#[test]
fn inconsistent_layouts_do_not_panic() {
    let g = sized(
        Param::HalfDiff,
        [16, 1, 16, 32],
        [Mapping::Sqrt, Mapping::Uniform],
        sym(true, true, true),
    );
    let mut d = DeviceLayout::new(&baked(GGX, g), Interp::Linear).unwrap();
    let mut out = [0f32; 8];
    if let Some(k) = &mut d.kernel {
        k.values.truncate(7);
        k.axes[1].c.clear();
    }
    if let Some(g) = &mut d.grid {
        g.values.clear();
    }
    for (wi, wo) in pairs().into_iter().take(2000) {
        d.eval(wi, wo, &mut out);
        d.eval(wi, wo, &mut out[..1]);
        assert!(out.iter().all(|x| x.is_finite()));
    }
}
