//! The placement of elevations' unit tests: the albedo walk gives `mirror_albedo`'s figures to
//! the bit.

use super::readback::albedos;
use super::*;
use crate::quadrature::gauss_legendre;

#[test]
fn albedos_are_mirror_albedos_of_the_turned_brdfs_to_the_bit() {
    // Placement's figures, hence the file's bytes, must not change with how the albedos
    // are walked: one walk for both BRDFs gives each what `mirror_albedo` of `Turned`
    // gives, with the light at 0 (no turn) and elsewhere.
    use crate::analysis::fidelity::{Turned, mirror_albedo};
    let path = &crate::measured::rgl_write::tests::rgl_files()[0];
    let file = RglBrdf::open(path).unwrap();
    let src = crate::open(
        r#"{"model": "ggx", "alpha_x": 0.1, "alpha_y": 0.4, "fresnel": {"conductor": "Cu"}}"#,
    )
    .unwrap();
    let (gx, gw) = gauss_legendre(4);
    for light in [0.0, 1.3, -2.9] {
        for deg in [1.0f64, 37.0, 89.0] {
            let (x, y) = albedos(&file, &*src, light, deg.to_radians(), 64, (&gx, &gw));
            let x0 = mirror_albedo(&Turned(&file, light), deg.to_radians(), 64, 4);
            let y0 = mirror_albedo(&Turned(&*src, light), deg.to_radians(), 64, 4);
            assert!(x[0] > 0.0 && y[0] > 0.0, "{light} {deg}: {x:?} {y:?}");
            for ch in 0..3 {
                assert_eq!(x[ch].to_bits(), x0[ch].to_bits(), "{light} {deg} {ch}");
                assert_eq!(y[ch].to_bits(), y0[ch].to_bits(), "{light} {deg} {ch}");
            }
        }
    }
}

#[test]
fn figures_divide_by_the_bars_and_floors_cap_at_the_error() {
    let iv = [Errors {
        err: [1e-4, 2.25e-4, 9e-4],
        reference: [1.0, 1.0, 1.0],
        albedo: 0.005,
    }];
    let floors = [Errors {
        err: [0.25e-4, 1.0, 0.0],
        reference: [1.0; 3],
        albedo: 0.001,
    }];
    let (f, floor) = figures(&iv, &floors);
    for (k, want) in [1.0, 1.0, 1.0, 0.5].iter().enumerate() {
        assert!((f[k] - want).abs() < 1e-12, "{k}: {}", f[k]);
    }
    for (k, want) in [0.5, 1.0, 0.0, 0.1].iter().enumerate() {
        assert!((floor[k] - want).abs() < 1e-12, "{k}: {}", floor[k]);
    }
}
