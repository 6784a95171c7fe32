//! The contract's batch and wavelength checks: `eval_batch` and `sample_batch` against the
//! one-pair calls, and `eval_at_wavelengths` against `eval_wavelength` (NaN at a non-wavelength).

use glam::{DVec2, DVec3};

use super::{Contract, Log, close, eval};
use crate::brdf::Brdf;
use crate::spectrum::MAX_CHANNELS;

/// `eval_at_wavelengths` is `eval_wavelength` at each wavelength (as f32), bit for bit, on
/// pairs of every kind: wavelengths inside, between and outside the channels, one and many.
fn at_wavelengths(brdf: &dyn Brdf, pairs: &[(DVec3, DVec3)], log: &mut Log) {
    let mut nm: Vec<f64> = vec![380.0, 450.0, 517.3, 550.0, 612.5, 700.0, 830.0];
    nm.extend((0..brdf.channels().len()).map(|i| brdf.channels().wavelength(i)));
    let mut out = vec![0.0f32; nm.len()];
    for (k, &(a, b)) in pairs.iter().enumerate().take(400) {
        let (wi, wo) = match k % 7 {
            0 => (a, DVec3::new(b.x, b.y, -b.z)),
            1 => (a * 3.5, b * 0.25),
            _ => (a, b),
        };
        let n = 1 + k % nm.len();
        brdf.eval_at_wavelengths(wi, wo, &nm[..n], &mut out[..n]);
        for (j, &x) in nm[..n].iter().enumerate() {
            let want = brdf.eval_wavelength(wi, wo, x) as f32;
            if out[j].to_bits() != want.to_bits() {
                log.fail("eval_at_wavelengths", || {
                    format!(
                        "({wi}, {wo}) at {x} nm: {} vs eval_wavelength's {want}",
                        out[j]
                    )
                });
            }
        }
    }
}

/// At a non-wavelength (NaN, ±∞, 0, < 0 nm) `eval_wavelength`, `eval_at_wavelengths` and the
/// weights of `sample_wavelengths` are NaN, on pairs of every kind ([`Brdf::eval_wavelength`]):
/// never a value a renderer could take for data.
fn at_non_wavelengths(brdf: &dyn Brdf, pairs: &[(DVec3, DVec3)], log: &mut Log) {
    let bad = [
        f64::NAN,
        0.0,
        -0.0,
        -550.0,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut out = [0.0f32; 7];
    for (k, &(a, b)) in pairs.iter().enumerate().take(50) {
        let (wi, wo) = match k % 5 {
            0 => (a, DVec3::new(b.x, b.y, -b.z)),
            _ => (a, b),
        };
        // One real wavelength among them keeps its value.
        let nm = [bad[0], bad[1], bad[2], 550.0, bad[3], bad[4], bad[5]];
        brdf.eval_at_wavelengths(wi, wo, &nm, &mut out);
        for (j, &x) in nm.iter().enumerate() {
            let f = brdf.eval_wavelength(wi, wo, x);
            if x == 550.0 {
                if out[j].to_bits() != (f as f32).to_bits() {
                    log.fail("non-wavelength", || {
                        format!("({wi}, {wo}) at 550 nm among non-wavelengths: {}", out[j])
                    });
                }
            } else if !f.is_nan() || !out[j].is_nan() {
                log.fail("non-wavelength", || {
                    format!(
                        "({wi}, {wo}) at {x} nm: eval_wavelength {f}, eval_at_wavelengths {} \
                         (NaN expected)",
                        out[j]
                    )
                });
            }
        }
        let u = DVec2::new((k as f64 + 0.5) / 50.0, 0.37);
        let mut w = [0.0f32; 6];
        if brdf.sample_wavelengths(b, u, &bad, &mut w).is_some() && w.iter().any(|v| !v.is_nan()) {
            log.fail("non-wavelength", || {
                format!("sample_wavelengths({b}, {u}) weights {w:?} at {bad:?} (NaN expected)")
            });
        }
    }
}

/// `eval_batch` against `eval` and `sample_batch` against `sample`, pair by pair
/// (unnormalized, below-horizon and, for sampling, non-finite views included), after the
/// wavelength checks above.
pub(super) fn batches(brdf: &dyn Brdf, opts: &Contract, pairs: &[(DVec3, DVec3)], log: &mut Log) {
    at_wavelengths(brdf, pairs, log);
    at_non_wavelengths(brdf, pairs, log);
    let c = brdf.channels().len();
    let (wi, wo): (Vec<DVec3>, Vec<DVec3>) = pairs
        .iter()
        .enumerate()
        .map(|(k, &(a, b))| match k % 13 {
            0 => (a, DVec3::new(b.x, b.y, -b.z)),
            1 => (a * 3.5, b * 0.25),
            _ => (a, b),
        })
        .unzip();
    let mut out = vec![0.0f32; wi.len() * c];
    brdf.eval_batch(&wi, &wo, &mut out);
    for (k, got) in out.chunks_exact(c).enumerate() {
        let want = eval(brdf, wi[k], wo[k]);
        if (0..c).any(|ch| !close(got[ch] as f64, want[ch] as f64, opts.batch_tolerance)) {
            log.fail("eval_batch", || {
                format!(
                    "pair ({}, {}): batch {got:?} vs eval {:?}",
                    wi[k],
                    wo[k],
                    &want[..c]
                )
            });
        }
    }
    // The same views drawn from in one batch and one by one (the `u` of pair k from its wi).
    let mut wo_s = wo.clone();
    wo_s[2] = DVec3::new(f64::NAN, 0.0, 1.0);
    let u: Vec<DVec2> = wi
        .iter()
        .map(|a| DVec2::new(a.x.abs().fract(), a.y.abs().fract()))
        .collect();
    let n = wo_s.len();
    let (mut swi, mut spdf, mut sw) = (vec![DVec3::ZERO; n], vec![0.0; n], vec![0.0f32; n * c]);
    let out = crate::batch::SampleOut {
        wi: &mut swi,
        pdf: &mut spdf,
        weight: &mut sw,
    };
    brdf.sample_batch(&wo_s, &u, out);
    let mut w = [0.0f32; MAX_CHANNELS];
    for k in 0..n {
        let one = match crate::batch::drawable(wo_s[k], u[k]) {
            true => brdf.sample(wo_s[k], u[k], &mut w[..c]),
            false => None,
        };
        let got = &sw[k * c..(k + 1) * c];
        let agrees = match one {
            Some(s) => {
                (swi[k] - s.wi).length() <= opts.batch_tolerance
                    && close(spdf[k], s.pdf, opts.batch_tolerance)
                    && (0..c).all(|ch| close(got[ch] as f64, w[ch] as f64, opts.batch_tolerance))
            }
            None => swi[k] == DVec3::ZERO && spdf[k] == 0.0 && got.iter().all(|&x| x == 0.0),
        };
        if !agrees {
            log.fail("sample_batch", || {
                format!(
                    "wo {}, u {}: batch ({}, {}, {got:?}) vs sample {one:?} {:?}",
                    wo_s[k],
                    u[k],
                    swi[k],
                    spdf[k],
                    &w[..c]
                )
            });
        }
    }
}
