//! The contract's sampling checks: a sample's pdf and weight against `pdf` and `eval`, the fused
//! `eval_pdf`, and `sample_wavelengths` against `sample`.

use glam::{DVec2, DVec3};

use super::{Contract, Log, close, close_abs, eval};
use crate::brdf::Brdf;
use crate::rng::Pcg32;
use crate::spectrum::{Channels, MAX_CHANNELS};

/// Samples against pdf and eval at each of [`views`].
pub(super) fn sampling<B: Brdf + ?Sized>(
    brdf: &B,
    opts: &Contract,
    wos: &[DVec3],
    rng: &mut Pcg32,
    log: &mut Log,
) {
    let c = brdf.channels().len();
    let delta = brdf.flags().delta;
    for &wo in wos {
        let mut got = 0;
        for _ in 0..opts.samples {
            let mut w = [0.0f32; MAX_CHANNELS];
            let u = rng.next_dvec2();
            let Some(s) = brdf.sample(wo, u, &mut w[..c]) else {
                continue;
            };
            got += 1;
            spectral_sample(brdf, wo, u, &s, &w[..c], log);
            if !((s.wi.length() - 1.0).abs() < 1e-9 && s.wi.is_finite()) {
                log.fail("sample", || format!("wo {wo}: wi {} not unit", s.wi));
                continue;
            }
            if w[..c].iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                log.fail("sample", || format!("wo {wo}: weight {:?}", &w[..c]));
            }
            if s.delta || delta {
                if !s.delta {
                    log.fail("sample", || {
                        format!("wo {wo}: a delta BRDF's sample not delta")
                    });
                }
                continue;
            }
            if !brdf.flags().transmission && s.wi.z <= 0.0 {
                log.fail("sample", || {
                    format!("wo {wo}: wi {} below the horizon", s.wi)
                });
            }
            let pdf = brdf.pdf(s.wi, wo);
            if !close(s.pdf, pdf, opts.pdf_tolerance) || !(pdf > 0.0) {
                log.fail("pdf", || {
                    format!(
                        "wo {wo}, wi {}: sample's pdf {} vs pdf() {pdf}",
                        s.wi, s.pdf
                    )
                });
            }
            let f = eval(brdf, s.wi, wo);
            let mut f2 = [0.0f32; MAX_CHANNELS];
            let p2 = brdf.eval_pdf(s.wi, wo, &mut f2[..c]);
            if !close(p2, pdf, 1e-12) || (0..c).any(|k| !close(f2[k] as f64, f[k] as f64, 1e-6)) {
                log.fail("eval_pdf", || {
                    format!(
                        "wo {wo}, wi {}: eval_pdf ({p2}, {:?}) vs pdf {pdf}, eval {:?}",
                        s.wi,
                        &f2[..c],
                        &f[..c]
                    )
                });
            }
            for k in 0..c {
                let want = f[k] as f64 * s.wi.z.abs() / s.pdf;
                if !close(w[k] as f64, want, 1e-5) {
                    log.fail("weight", || {
                        format!(
                            "wo {wo}, wi {}: channel {k} weight {} vs f cos θi / pdf {want}",
                            s.wi, w[k]
                        )
                    });
                }
            }
        }
        if got * 4 < opts.samples {
            log.fail("sample", || {
                format!("wo {wo}: only {got} of {} samples drawn", opts.samples)
            });
        }
    }
}

/// `sample_wavelengths` makes `sample`'s draw, weighs a smooth draw by `eval_wavelength`, and at
/// the channels' own wavelengths (sources of wavelength channels) gives `sample`'s weights.
fn spectral_sample<B: Brdf + ?Sized>(
    brdf: &B,
    wo: DVec3,
    u: DVec2,
    s: &crate::brdf::BrdfSample,
    w: &[f32],
    log: &mut Log,
) {
    let nm = match brdf.channels() {
        Channels::Wavelengths(nm) => nm.clone(),
        Channels::Rgb => vec![450.0, 550.0, 650.0],
    };
    let mut ws = [0.0f32; MAX_CHANNELS];
    let got = brdf.sample_wavelengths(wo, u, &nm, &mut ws[..nm.len()]);
    if got != Some(*s) {
        log.fail("sample_wavelengths", || {
            format!("wo {wo}, u {u}: draw {got:?} vs sample's {s:?}")
        });
        return;
    }
    if !s.delta {
        // A smooth draw: f_r at each wavelength, cos θi / pdf.
        for (k, &x) in nm.iter().enumerate() {
            let want = brdf.eval_wavelength(s.wi, wo, x) * s.wi.z.abs() / s.pdf;
            if !close_abs(ws[k] as f64, want, 1e-5, 1e-7) {
                log.fail("sample_wavelengths", || {
                    format!(
                        "wo {wo}, u {u}: weight {} at {x} nm vs f cos θi / pdf {want}",
                        ws[k]
                    )
                });
            }
        }
    }
    if let Channels::Wavelengths(_) = brdf.channels() {
        for (k, (&a, &b)) in ws.iter().zip(w).enumerate() {
            if !close_abs(a as f64, b as f64, 1e-5, 1e-7) {
                log.fail("sample_wavelengths", || {
                    format!("wo {wo}, u {u}: weight {a} at {} nm vs sample's {b}", nm[k])
                });
            }
        }
    }
}
