//! The contract's input checks: below the horizon, NaN, infinite and zero directions and `u`
//! outside [0, 1)² give nothing, and directions of any finite nonzero length act as unit ones.

use glam::{DVec2, DVec3};

use super::{Contract, Log, close, eval, views};
use crate::brdf::Brdf;
use crate::spectrum::MAX_CHANNELS;

/// Below the horizon, NaN, infinite and zero directions: f = 0, pdf = 0, no sample; no sample
/// for a `u` outside [0, 1)² either (beyond an edge, infinite or NaN).
pub(super) fn bad_input<B: Brdf + ?Sized>(brdf: &B, log: &mut Log) {
    let c = brdf.channels().len();
    let up = DVec3::new(0.2, 0.1, 1.0);
    let bad = [
        DVec3::new(0.0, 0.3, -1.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(f64::NAN, 0.0, 1.0),
        DVec3::new(0.0, f64::INFINITY, 1.0),
        DVec3::ZERO,
    ];
    let transmits = brdf.flags().transmission;
    for b in bad {
        // A refractor is non-zero across the horizon; the non-finite and zero ones still give 0.
        if transmits && b.is_finite() && b != DVec3::ZERO && b.z != 0.0 {
            continue;
        }
        for (wi, wo) in [(b, up), (up, b), (b, b)] {
            let mut f = [1.0f32; MAX_CHANNELS];
            brdf.eval(wi, wo, &mut f[..c]);
            if f[..c].iter().any(|&x| x != 0.0) {
                log.fail("horizon", || format!("eval({wi}, {wo}) = {:?}", &f[..c]));
            }
            let nm = brdf.channels().wavelength(0);
            if brdf.eval_wavelength(wi, wo, nm) != 0.0 {
                log.fail("horizon", || format!("eval_wavelength({wi}, {wo}) ≠ 0"));
            }
            if brdf.pdf(wi, wo) != 0.0 {
                log.fail("horizon", || format!("pdf({wi}, {wo}) ≠ 0"));
            }
        }
        let mut w = [0.0f32; MAX_CHANNELS];
        if let Some(s) = brdf.sample(b, DVec2::new(0.3, 0.6), &mut w[..c]) {
            log.fail("horizon", || format!("sample(wo = {b}) gave {s:?}"));
        }
    }
    // A hair above the horizon (cosines a renderer's f64 directions can carry, down to the
    // smallest subnormal, 5e-324): values may overflow (f_r grows like 1/cos θ there for many
    // lobes) but are never NaN or negative — an underflowed product must not turn into 0/0,
    // nor an overflowed one times a zero factor (a Fresnel term or k_s of 0) into 0·∞.
    for z in [1e-20f64, 1e-100, 1e-200, 1e-300, f64::from_bits(1)] {
        let r = (1.0 - z * z).sqrt();
        let g = |x: f64, y: f64| DVec3::new(x * r, y * r, z);
        let pairs = [
            (g(0.0, 1.0), g(0.0, -1.0)),
            (g(0.0, 1.0), g(-0.6, -0.8)),
            (g(0.6, 0.8), g(0.6, 0.8)),
            (g(1.0, 0.0), up),
            (up, g(1.0, 0.0)),
        ];
        for (k, (wi, wo)) in pairs.into_iter().enumerate() {
            let mut f = [0.0f32; MAX_CHANNELS];
            brdf.eval(wi, wo, &mut f[..c]);
            let nm = brdf.channels().wavelength(0);
            let (fw, p) = (brdf.eval_wavelength(wi, wo, nm), brdf.pdf(wi, wo));
            if !(f[..c].iter().all(|&x| x >= 0.0) && fw >= 0.0 && p >= 0.0) {
                log.fail("horizon", || {
                    format!(
                        "a hair above it, cos {z:e}, pair {k}: eval = {:?}, at {nm} nm {fw}, pdf {p}",
                        &f[..c]
                    )
                });
            }
        }
        let mut w = [0.0f32; MAX_CHANNELS];
        if let Some(s) = brdf.sample(g(0.6, 0.8), DVec2::new(0.3, 0.6), &mut w[..c])
            && !(s.pdf > 0.0 && w[..c].iter().all(|&x| x >= 0.0))
        {
            log.fail("horizon", || {
                format!(
                    "a hair above it, cos {z:e}: sample gave {s:?} {:?}",
                    &w[..c]
                )
            });
        }
    }
    // A u outside [0, 1)² has no sample, as in `sample_batch` (a sampler that ignores u
    // included): beyond it the samplers' maps leave the unit sphere or their densities.
    for u in [
        DVec2::new(f64::NAN, 0.6),
        DVec2::new(0.3, f64::NAN),
        DVec2::new(f64::INFINITY, 0.6),
        DVec2::new(0.3, f64::NEG_INFINITY),
        DVec2::new(1.0, 0.5),
        DVec2::new(0.5, 1.0),
        DVec2::new(1.5, -0.2),
        DVec2::new(-1e-300, 0.6),
        DVec2::new(0.3, 1.0 + f64::EPSILON),
    ] {
        let mut w = [0.0f32; MAX_CHANNELS];
        if let Some(s) = brdf.sample(up, u, &mut w[..c]) {
            log.fail("horizon", || {
                format!("sample(wo = {up}, u = {u}) gave {s:?}")
            });
        }
    }
}

/// Directions of any finite nonzero length are directions: scaled by 1e-300 … 1e300 (squared
/// lengths that underflow to 0 or overflow to ∞; they gave 0 in `eval` and `pdf` while the
/// samplers that look only at the sign of cos θo drew), every output equals the unit pair's.
pub(super) fn lengths<B: Brdf + ?Sized>(
    brdf: &B,
    opts: &Contract,
    pairs: &[(DVec3, DVec3)],
    log: &mut Log,
) {
    let c = brdf.channels().len();
    let nm = brdf.channels().wavelength(0);
    // Scaling and normalizing again moves each component by a few ulps: the tolerances of two
    // computations of the same coordinates.
    let (rel, prel) = (opts.symmetry_tolerance, opts.symmetry_tolerance);
    for &(wi, wo) in pairs.iter().take(40) {
        let (f, p, fw) = (
            eval(brdf, wi, wo),
            brdf.pdf(wi, wo),
            brdf.eval_wavelength(wi, wo, nm),
        );
        for k in [1e-300, 1e-160, 3.0, 1e160, 1e300] {
            for (a, b) in [(wi * k, wo), (wi, wo * k), (wi * k, wo * k)] {
                let g = eval(brdf, a, b);
                let (q, gw) = (brdf.pdf(a, b), brdf.eval_wavelength(a, b, nm));
                let same = (0..c).all(|ch| close(f[ch] as f64, g[ch] as f64, rel))
                    && close(p, q, prel)
                    && close(fw, gw, rel);
                if !same {
                    log.fail("lengths", || {
                        format!(
                            "({}, {}): f {:?}, pdf {q}, at {nm} nm {gw}; unit: {:?}, {p}, {fw}",
                            sci(a),
                            sci(b),
                            &g[..c],
                            &f[..c]
                        )
                    });
                }
            }
        }
    }
    let u = DVec2::new(0.3, 0.6);
    for wo in views() {
        let mut w = [0.0f32; MAX_CHANNELS];
        let s = brdf.sample(wo, u, &mut w[..c]);
        for k in [1e-300, 1e-160, 1e160, 1e300] {
            let mut v = [0.0f32; MAX_CHANNELS];
            let t = brdf.sample(wo * k, u, &mut v[..c]);
            let same = match (s, t) {
                (None, None) => true,
                (Some(s), Some(t)) => {
                    (s.wi - t.wi).length() < 1e-9
                        && close(s.pdf, t.pdf, prel)
                        && (0..c).all(|ch| close(w[ch] as f64, v[ch] as f64, rel))
                }
                _ => false,
            };
            if !same {
                log.fail("lengths", || {
                    format!("sample(wo {wo} × {k:e}) = {t:?} {:?}; unit: {s:?}", &v[..c])
                });
            }
        }
    }
}

/// A vector in scientific notation (the lengths check's are far from 1).
fn sci(v: DVec3) -> String {
    format!("[{:e}, {:e}, {:e}]", v.x, v.y, v.z)
}
