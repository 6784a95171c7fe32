//! A source read at wavelengths rather than at its channels: the channel mix of the default
//! [`Brdf::eval_wavelength`](super::Brdf::eval_wavelength), and f_r at many wavelengths for a
//! batch of pairs.

use glam::DVec3;

use super::{Brdf, check_batch};
use crate::spectrum::{Channels, MAX_CHANNELS};

/// Per-channel values `v` read at the wavelengths `nm` into `out` as
/// [`Brdf::eval_wavelength`]'s default reads channels ([`Channels::mix_at`]): what a source whose
/// spectral values come from its channels gives at a wavelength.
pub fn mix_channels(channels: &Channels, v: &[f32], nm: &[f64], out: &mut [f32]) {
    match (channels, v) {
        // RGB (the common case: a pbrt-v4 renderer's four wavelengths on an RGB table): the
        // basis read in line — the same arithmetic as `mix_at(x).apply`, bit for bit.
        (Channels::Rgb, &[r, g, b, ..]) => {
            let v = [r as f64, g as f64, b as f64];
            for (o, &x) in out.iter_mut().zip(nm) {
                let m = crate::spectrum::ChannelMix {
                    index: [0, 1, 2],
                    weight: crate::colour::rgb_basis_at(x),
                };
                *o = m.apply(|i| v[i]) as f32;
            }
        }
        _ => {
            for (o, &x) in out.iter_mut().zip(nm) {
                *o = channels.mix_at(x).apply(|i| v[i] as f64) as f32;
            }
        }
    }
}

/// [`Brdf::eval_at_wavelengths`] of a source whose [`Brdf::eval_wavelength`] is the default
/// (its channels mixed at each wavelength): one [`Brdf::eval`], then [`mix_channels`].
pub fn channels_at_wavelengths<B: Brdf + ?Sized>(
    brdf: &B,
    wi: DVec3,
    wo: DVec3,
    nm: &[f64],
    out: &mut [f32],
) {
    let mut buf = [0.0f32; MAX_CHANNELS];
    let c = brdf.channels().len().min(MAX_CHANNELS);
    brdf.eval(wi, wo, &mut buf[..c]);
    mix_channels(brdf.channels(), &buf[..c], nm, out);
}

/// f_r at the wavelengths `nm` for every pair: `out[p * k .. (p + 1) * k]` receives
/// [`Brdf::eval_at_wavelengths`] of pair `p` at the `k = nm.len()` wavelengths, on the
/// library's pool from [`crate::batch::PARALLEL`] pairs on.
///
/// # Panics
///
/// If the lengths do not match `wi.len()` pairs of `nm.len()` values ([`check_batch`]).
#[track_caller]
pub fn eval_wavelengths<B: Brdf + ?Sized>(
    brdf: &B,
    wi: &[DVec3],
    wo: &[DVec3],
    nm: &[f64],
    out: &mut [f32],
) {
    let k = nm.len();
    check_batch(wi, wo, out, k);
    if k == 0 {
        return;
    }
    crate::batch::blocks(out, k, |s, o| {
        for (r, o) in o.chunks_exact_mut(k).enumerate() {
            brdf.eval_at_wavelengths(wi[s + r], wo[s + r], nm, o);
        }
    });
}
