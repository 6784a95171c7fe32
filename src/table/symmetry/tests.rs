//! The symmetry maps' and checks' unit tests: the fast coordinates against the exact ones, the
//! polynomial trigonometry's error, a sharp anisotropic lobe not detected isotropic.

use glam::DVec3;
use std::f64::consts::{PI, TAU};

use super::*;
use crate::brdf::Brdf;
use crate::geometry;
use crate::rng::Pcg32;
use crate::table::param::Param;

/// The fast coordinates (polynomial trig, division-free half/diff angles, no renormalization
/// of unit inputs) agree with the exact ones for every parameterization and symmetry: θ to
/// the polynomials' error, φ the same up to the period of a periodic axis (a value on one
/// side of 0 may land on the other side of the period).
#[test]
fn fast_coordinates_match_the_exact_ones() {
    let mut rng = Pcg32::new(11);
    let syms = [
        Symmetry::NONE,
        Symmetry::ALL,
        Symmetry {
            isotropic: true,
            reciprocal: true,
            bilateral: false,
        },
        Symmetry {
            isotropic: true,
            reciprocal: false,
            bilateral: true,
        },
        Symmetry {
            isotropic: false,
            reciprocal: true,
            bilateral: true,
        },
    ];
    let mut worst: f64 = 0.0;
    for k in 0..40_000 {
        let mut wi = geometry::uniform_hemisphere(rng.next_dvec2());
        let mut wo = geometry::uniform_hemisphere(rng.next_dvec2());
        match k % 4 {
            // Near the pole of the half vector (wo ≈ mirror of wi).
            1 => wo = (geometry::reflect_z(wi) + 1e-7 * wo).normalize(),
            // Non-unit inputs.
            2 => {
                wi *= 3.0;
                wo *= 0.25;
            }
            _ => {}
        }
        if k % 7 == 0 {
            wi = DVec3::new(wi.x, wi.y, wi.z.abs().max(1e-9));
        }
        for param in [Param::InOut, Param::HalfDiff] {
            for sym in syms {
                let (Some(a), Some(b)) = (
                    canonical_coords(param, sym, wi, wo),
                    canonical_coords_fast(param, sym, wi, wo),
                ) else {
                    panic!("{param:?} {sym}: {wi} {wo} valid for one path only");
                };
                for ax in 0..4 {
                    let mut d = (a[ax] - b[ax]).abs();
                    if ax % 2 == 1 {
                        d = d.min((d - PI).abs()).min((d - TAU).abs());
                    }
                    // fast_atan2 ≤ 2e-7, fast_acos ≤ 5e-8 (see fast_trig_is_accurate), and
                    // rounding well below both.
                    assert!(
                        d < 3e-7,
                        "{param:?} {sym} axis {ax}: exact {a:?} fast {b:?} ({wi}, {wo})"
                    );
                    worst = worst.max(d);
                }
            }
        }
    }
    assert!(worst > 0.0, "the paths should differ by rounding somewhere");
}

/// A lobe narrower than random pairs ever hit — Ward α = (1e-4, 4e-4), whose f_r is 0 to
/// f32 outside θh ≲ 0.1° — is anisotropic where it is not 0: random pairs see 0 = 0 on
/// every rotation and took it for isotropic, and its table was baked isotropic (at 4e-4
/// of the half vector off the mirror towards y the source is 2.5e5, the table 3.4e4). A
/// symmetry the source does not declare must also hold on pairs where the source is
/// large (drawn by its own sampler); declared ones, and sources that have the symmetry,
/// are detected as before.
#[test]
fn a_sharp_anisotropic_lobe_is_not_detected_isotropic() {
    use crate::models::ward::Ward;
    use crate::spectrum::{Channels, Value};
    let ward = Ward::new(Value::Grey(0.3), 1e-4, 4e-4, &Channels::Rgb).unwrap();
    assert!(!ward.flags().isotropic);
    let d = detect(&ward, DEFAULT_TOLERANCE);
    assert!(!d.isotropic, "detected {d}");
    assert!(d.reciprocal && d.bilateral, "detected {d}");
    let iso = Symmetry {
        isotropic: true,
        ..Symmetry::NONE
    };
    assert!(matches!(
        verify(&ward, iso, DEFAULT_TOLERANCE),
        Err(Error::Symmetry {
            symmetry: SymmetryKind::Isotropic,
            ..
        })
    ));
    // The same lobe, isotropic: detected so.
    let round = Ward::new(Value::Grey(0.3), 2e-4, 2e-4, &Channels::Rgb).unwrap();
    assert_eq!(detect(&round, DEFAULT_TOLERANCE), Symmetry::ALL);
    // A symmetric source that declares nothing: still detected symmetric.
    struct Undeclared(crate::models::lambert::Lambert);
    impl Brdf for Undeclared {
        fn channels(&self) -> &crate::spectrum::Channels {
            self.0.channels()
        }
        fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
            self.0.eval(wi, wo, out)
        }
        fn flags(&self) -> crate::Flags {
            crate::Flags::default()
        }
        fn describe(&self) -> String {
            "undeclared".into()
        }
    }
    let lambert = crate::models::lambert::Lambert::new(Value::Grey(0.3), &Channels::Rgb).unwrap();
    assert_eq!(
        detect(&Undeclared(lambert), DEFAULT_TOLERANCE),
        Symmetry::ALL
    );
}

#[test]
fn fast_trig_is_accurate() {
    let mut rng = Pcg32::new(1);
    let mut worst: f64 = 0.0;
    for _ in 0..200_000 {
        let x = rng.next_f64() * 2.0 - 1.0;
        worst = worst.max((fast_acos(x) - x.acos()).abs());
    }
    for x in [-1.0, 0.0, 1.0, 1.0 - 1e-12, -1.0 + 1e-12] {
        worst = worst.max((fast_acos(x) - x.acos()).abs());
    }
    assert!(worst < 5e-8, "acos {worst}");
    let mut worst: f64 = 0.0;
    for _ in 0..200_000 {
        let (y, x) = (rng.next_f64() * 2.0 - 1.0, rng.next_f64() * 2.0 - 1.0);
        worst = worst.max((fast_atan2(y, x) - y.atan2(x)).abs());
    }
    for (y, x) in [
        (0.0, 1.0),
        (1.0, 0.0),
        (0.0, -1.0),
        (-1.0, 0.0),
        (0.0, 0.0),
        (1e-300, 1.0),
    ] {
        worst = worst.max((fast_atan2(y, x) - f64::atan2(y, x)).abs());
    }
    assert!(worst < 2e-7, "atan2 {worst}");
}
