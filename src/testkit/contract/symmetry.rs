//! The contract's positivity and declared-symmetry checks: f_r finite and ≥ 0, and what the
//! flags declare (reciprocity, isotropy, bilateral symmetry) holding.

use glam::DVec3;

use super::{Contract, Log, close_abs, eval};
use crate::brdf::Brdf;
use crate::spectrum::MAX_CHANNELS;

/// Positivity, and the symmetries the flags declare.
pub(super) fn values_and_symmetry(
    brdf: &dyn Brdf,
    opts: &Contract,
    pairs: &[(DVec3, DVec3)],
    log: &mut Log,
) {
    let c = brdf.channels().len();
    let flags = brdf.flags();
    let tol = opts.symmetry_tolerance;
    let mirror = |v: DVec3| DVec3::new(v.x, -v.y, v.z);
    let mut scale = [0.0f64; MAX_CHANNELS];
    for &(wi, wo) in pairs {
        let f = eval(brdf, wi, wo);
        for ch in 0..c {
            if f[ch].is_finite() {
                scale[ch] = scale[ch].max(f[ch] as f64 * opts.symmetry_floor);
            }
        }
    }
    for (k, &(wi, wo)) in pairs.iter().enumerate() {
        let f = eval(brdf, wi, wo);
        if let Some(x) = f[..c].iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
            log.fail("positive", || format!("f({wi}, {wo}) = {x}"));
        }
        let mut same = |check: &'static str, a: DVec3, b: DVec3| {
            let g = eval(brdf, a, b);
            for ch in 0..c {
                let slack = scale[ch] + 1e-30;
                if !close_abs(f[ch] as f64, g[ch] as f64, tol, slack)
                    && !close_abs(
                        f[ch] as f64,
                        g[ch] as f64,
                        tol,
                        slack + sensitivity(brdf, wi, wo, ch, opts.symmetry_angle),
                    )
                {
                    log.fail(check, || {
                        format!(
                            "channel {ch}: f({wi}, {wo}) = {} but f({a}, {b}) = {}",
                            f[ch], g[ch]
                        )
                    });
                    break;
                }
            }
        };
        if flags.reciprocal {
            same("reciprocal", wo, wi);
        }
        if flags.isotropic {
            // A rotation about the normal by an angle drawn from the pair's index.
            let a = 0.7 + k as f64 * 2.399963;
            let rot = |v: DVec3| {
                let (s, co) = a.sin_cos();
                DVec3::new(co * v.x - s * v.y, s * v.x + co * v.y, v.z)
            };
            same("isotropic", rot(wi), rot(wo));
        }
        if flags.bilateral {
            same("bilateral", mirror(wi), mirror(wo));
        }
    }
}

/// How much f's channel `ch` changes when either direction turns by ±`angle` about the normal.
fn sensitivity(brdf: &dyn Brdf, wi: DVec3, wo: DVec3, ch: usize, angle: f64) -> f64 {
    let f = eval(brdf, wi, wo)[ch] as f64;
    let turn = |v: DVec3, a: f64| {
        let (s, c) = a.sin_cos();
        DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
    };
    [
        (turn(wi, angle), wo),
        (turn(wi, -angle), wo),
        (wi, turn(wo, angle)),
        (wi, turn(wo, -angle)),
    ]
    .iter()
    .map(|&(a, b)| (eval(brdf, a, b)[ch] as f64 - f).abs())
    .fold(0.0, f64::max)
}
