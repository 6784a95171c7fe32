//! The Fresnel term a model evaluates ([`Fresnel`]): a spec resolved for a channel set, per
//! channel and at any wavelength.

use super::{
    FresnelSpec, conductor, conductor_lanes_c2, conductor_lanes_scaled, dielectric, schlick,
};
use crate::error::{Error, Result};
use crate::spectrum::{Channels, Value};

/// A Fresnel term resolved for a channel set: per-channel constants, ready to evaluate without
/// allocation, plus the spectral data for evaluation at arbitrary wavelengths.
#[derive(Debug, Clone)]
pub enum Fresnel {
    /// F = 1.
    None,
    /// Complex index per channel.
    Conductor {
        /// n per channel.
        n: Vec<f64>,
        /// k per channel.
        k: Vec<f64>,
        /// n as a spectrum.
        n_spec: Value,
        /// k as a spectrum.
        k_spec: Value,
    },
    /// Relative index per channel.
    Dielectric {
        /// eta per channel.
        eta: Vec<f64>,
        /// eta as a spectrum.
        eta_spec: Value,
    },
    /// Schlick's approximation, F0 per channel.
    Schlick {
        /// F0 per channel.
        f0: Vec<f64>,
        /// F0 as a spectrum.
        f0_spec: Value,
    },
}

impl Fresnel {
    /// Resolves a spec for `channels`, validating it; `field` names the spec field in errors.
    pub fn new(spec: &FresnelSpec, channels: &Channels, field: &str) -> Result<Self> {
        Ok(match spec {
            FresnelSpec::None => Fresnel::None,
            FresnelSpec::Conductor(name) => {
                let (n, k) = crate::metals::metal(name).ok_or_else(|| {
                    Error::spec(
                        format!("{field}.conductor"),
                        format!(
                            "unknown metal `{name}` (known: {})",
                            crate::metals::NAMES.join(", ")
                        ),
                    )
                })?;
                Fresnel::Conductor {
                    n: n.resolve(channels),
                    k: k.resolve(channels),
                    n_spec: n,
                    k_spec: k,
                }
            }
            FresnelSpec::Complex { n, k } => {
                n.validate(&format!("{field}.n"), 0.0)?;
                k.validate(&format!("{field}.k"), 0.0)?;
                if n.numbers().iter().any(|&x| x <= 0.0) {
                    return Err(Error::spec(format!("{field}.n"), "must be positive"));
                }
                Fresnel::Conductor {
                    n: n.resolve(channels),
                    k: k.resolve(channels),
                    n_spec: n.clone(),
                    k_spec: k.clone(),
                }
            }
            FresnelSpec::Dielectric(eta) => {
                eta.validate(&format!("{field}.eta"), 0.0)?;
                if eta.numbers().iter().any(|&x| x <= 0.0) {
                    return Err(Error::spec(format!("{field}.eta"), "must be positive"));
                }
                Fresnel::Dielectric {
                    eta: eta.resolve(channels),
                    eta_spec: eta.clone(),
                }
            }
            FresnelSpec::Schlick(f0) => {
                f0.validate(&format!("{field}.schlick"), 0.0)?;
                if f0.numbers().iter().any(|&x| x > 1.0) {
                    return Err(Error::spec(format!("{field}.schlick"), "F0 must be ≤ 1"));
                }
                Fresnel::Schlick {
                    f0: f0.resolve(channels),
                    f0_spec: f0.clone(),
                }
            }
        })
    }

    /// F for channel `c` at incidence cosine `cos_i` (the lecture's L·H or N·V).
    #[inline]
    pub fn eval(&self, cos_i: f64, c: usize) -> f64 {
        match self {
            Fresnel::None => 1.0,
            Fresnel::Conductor { n, k, .. } => conductor(cos_i, n[c], k[c]),
            Fresnel::Dielectric { eta, .. } => dielectric(cos_i, eta[c]),
            Fresnel::Schlick { f0, .. } => schlick(cos_i, f0[c]),
        }
    }

    /// Writes `scale[c] · s · F_c(cos_i)` as `f32` into `out[c]` for every channel: the last step
    /// of a microfacet model's `eval`. The variant is matched once, outside the channel loop, so
    /// the loop is straight-line arithmetic the compiler can vectorize.
    #[inline(always)]
    pub fn eval_scaled(&self, cos_i: f64, scale: &[f64], s: f64, out: &mut [f32]) {
        // No Fresnel term with RGB (the common case of plain microfacet lobes): three stores,
        // inline, rather than a call.
        if let (Fresnel::None, [o0, o1, o2, ..], [k0, k1, k2]) = (self, &mut *out, scale) {
            (*o0, *o1, *o2) = ((k0 * s) as f32, (k1 * s) as f32, (k2 * s) as f32);
            return;
        }
        self.eval_scaled_c2(cos_i, cos_i * cos_i, scale, s, out)
    }

    /// [`Fresnel::eval_scaled`] at the cosine x / √gg of a direction and an unnormalized normal
    /// g (x = w·g, gg = |g|²): RGB conductors use [`conductor_lanes_scaled`], which needs
    /// neither 1/gg nor √gg; other variants normalize.
    #[inline]
    pub fn eval_scaled_dot(&self, x: f64, gg: f64, scale: &[f64], s: f64, out: &mut [f32]) {
        if let (Fresnel::Conductor { n, k, .. }, [o0, o1, o2, ..], [k0, k1, k2]) =
            (self, &mut *out, scale)
            && let (&[n0, n1, n2], &[c0, c1, c2]) = (n.as_slice(), k.as_slice())
        {
            let f = conductor_lanes_scaled(x, gg, [n0, n1, n2, n0], [c0, c1, c2, c0]);
            (*o0, *o1, *o2) = (
                (k0 * s * f[0]) as f32,
                (k1 * s * f[1]) as f32,
                (k2 * s * f[2]) as f32,
            );
            return;
        }
        self.eval_scaled(x / gg.sqrt(), scale, s, out)
    }

    /// [`Fresnel::eval_scaled`] with cos² θ′ supplied by the caller (see
    /// [`conductor_lanes_c2`]; other variants use `cos_i` alone).
    #[inline]
    pub fn eval_scaled_c2(&self, cos_i: f64, cos2_i: f64, scale: &[f64], s: f64, out: &mut [f32]) {
        match self {
            Fresnel::None => {
                if let ([o0, o1, o2, ..], [k0, k1, k2]) = (&mut *out, scale) {
                    (*o0, *o1, *o2) = ((k0 * s) as f32, (k1 * s) as f32, (k2 * s) as f32);
                    return;
                }
                for (o, &k) in out.iter_mut().zip(scale) {
                    *o = (k * s) as f32;
                }
            }
            Fresnel::Conductor { n, k, .. } => {
                if let (Ok(o), Ok(ks), Ok(n), Ok(k)) = (
                    <&mut [f32; 3]>::try_from(&mut *out),
                    <&[f64; 3]>::try_from(scale),
                    <&[f64; 3]>::try_from(n.as_slice()),
                    <&[f64; 3]>::try_from(k.as_slice()),
                ) {
                    // RGB: the three channels as lanes of one fixed-size computation, which the
                    // compiler turns into packed square roots and divisions.
                    let f = conductor_lanes_c2(
                        cos_i,
                        cos2_i,
                        [n[0], n[1], n[2], n[0]],
                        [k[0], k[1], k[2], k[0]],
                    );
                    for c in 0..3 {
                        o[c] = (ks[c] * s * f[c]) as f32;
                    }
                    return;
                }
                for (((o, &ks), &n), &k) in out.iter_mut().zip(scale).zip(n).zip(k) {
                    *o = (ks * s * conductor(cos_i, n, k)) as f32;
                }
            }
            Fresnel::Dielectric { eta, .. } => {
                for ((o, &ks), &e) in out.iter_mut().zip(scale).zip(eta) {
                    *o = (ks * s * dielectric(cos_i, e)) as f32;
                }
            }
            Fresnel::Schlick { f0, .. } => {
                for ((o, &ks), &f) in out.iter_mut().zip(scale).zip(f0) {
                    *o = (ks * s * schlick(cos_i, f)) as f32;
                }
            }
        }
    }

    /// F at wavelength `nm` from the spectral data; NaN at a non-wavelength
    /// ([`crate::spectrum::is_wavelength`]).
    pub fn eval_at(&self, cos_i: f64, nm: f64) -> f64 {
        if !crate::spectrum::is_wavelength(nm) {
            return f64::NAN;
        }
        match self {
            Fresnel::None => 1.0,
            Fresnel::Conductor { n_spec, k_spec, .. } => {
                conductor(cos_i, n_spec.at(nm), k_spec.at(nm))
            }
            Fresnel::Dielectric { eta_spec, .. } => dielectric(cos_i, eta_spec.at(nm)),
            Fresnel::Schlick { f0_spec, .. } => schlick(cos_i, f0_spec.at(nm)),
        }
    }

    /// True for F = 1.
    pub fn is_none(&self) -> bool {
        matches!(self, Fresnel::None)
    }
}
