//! The albedo side of the fidelity figures: the albedo curve on the quadrature about the mirror
//! direction, and its worst error against the source's.

use rayon::prelude::*;

use super::{AlbedoError, FidelityOptions};
use crate::analysis::pair_rule::mirror_rule;
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::progress::{Progress, Silent};
use crate::quadrature::gauss_legendre;
use crate::spectrum::MAX_CHANNELS;

/// The albedo curve of `brdf` at [`FidelityOptions::albedo_thetas_deg`] ([`mirror_albedo`],
/// the mean over [`FidelityOptions::albedo_azimuths`]).
pub fn albedo_curve(brdf: &dyn Brdf, opts: &FidelityOptions) -> Result<AlbedoCurve> {
    albedo_curve_with(brdf, opts, &Silent)
}

/// [`albedo_curve`], asking `progress` to stop before each angle.
pub fn albedo_curve_with(
    brdf: &dyn Brdf,
    opts: &FidelityOptions,
    progress: &dyn Progress,
) -> Result<AlbedoCurve> {
    let c = brdf.channels().len();
    if c > MAX_CHANNELS {
        return Err(Error::arg("channels", format!("{c} channels")));
    }
    check_rule(opts)?;
    let turns = light_azimuths(opts.albedo_azimuths);
    let share = 1.0 / turns.len() as f64;
    opts.albedo_thetas_deg
        .par_iter()
        .map(|&t| {
            crate::progress::check(progress)?;
            let mut a = vec![0.0; c];
            for &phi in &turns {
                let s = mirror_albedo(
                    &Turned(brdf, phi),
                    t.to_radians(),
                    opts.albedo_phi,
                    opts.albedo_order,
                );
                for (a, s) in a.iter_mut().zip(s) {
                    *a += share * s;
                }
            }
            Ok(a)
        })
        .collect()
}

/// Refuses an albedo rule without nodes.
fn check_rule(opts: &FidelityOptions) -> Result<()> {
    if opts.albedo_phi == 0 || opts.albedo_order == 0 {
        return Err(Error::arg("albedo_phi", "needs at least one node"));
    }
    if opts.albedo_azimuths == 0 {
        return Err(Error::arg("albedo_azimuths", "needs at least one azimuth"));
    }
    // As `albedo::incidence`: the light above the horizon (at 90° Ward's albedo has no finite
    // limit, and a cosine of 6e-17 still counts as above).
    if let Some(t) = (opts.albedo_thetas_deg.iter()).find(|t| !(0.0..90.0).contains(*t)) {
        return Err(Error::arg(
            "albedo_thetas_deg",
            format!("{t}° is outside [0°, 90°): the albedo is defined for light above the horizon"),
        ));
    }
    Ok(())
}

/// `n` azimuths of the light equally spaced from 0 (radians).
pub(crate) fn light_azimuths(n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| std::f64::consts::TAU * k as f64 / n as f64)
        .collect()
}

/// `brdf` with both directions turned by `phi` (radians) about the normal: its albedo at the
/// light's azimuth 0 is `brdf`'s at azimuth `phi`.
pub(crate) struct Turned<'a>(pub &'a dyn Brdf, pub f64);

impl Brdf for Turned<'_> {
    fn channels(&self) -> &crate::spectrum::Channels {
        self.0.channels()
    }
    fn eval(&self, wi: glam::DVec3, wo: glam::DVec3, out: &mut [f32]) {
        if self.1 == 0.0 {
            return self.0.eval(wi, wo, out);
        }
        let (s, c) = self.1.sin_cos();
        let turn = |v: glam::DVec3| glam::DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z);
        self.0.eval(turn(wi), turn(wo), out)
    }
    fn flags(&self) -> crate::brdf::Flags {
        self.0.flags()
    }
    fn describe(&self) -> String {
        format!("{} (turned by {} rad)", self.0.describe(), self.1)
    }
}

/// Directional albedo per θ′ of [`FidelityOptions::albedo_thetas_deg`], per channel.
pub type AlbedoCurve = Vec<Vec<f64>>;

/// The albedo curves of `a` and `b` on one quadrature: `(a[θ][channel], b[θ][channel])`, each
/// the mean over [`FidelityOptions::albedo_azimuths`].
pub fn albedo_pair(
    a: &dyn Brdf,
    b: &dyn Brdf,
    opts: &FidelityOptions,
) -> Result<(AlbedoCurve, AlbedoCurve)> {
    let c = b.channels().len();
    if a.channels().len() != c || c > MAX_CHANNELS {
        return Err(Error::arg(
            "channels",
            format!("{} vs {} channels", a.channels().len(), c),
        ));
    }
    check_rule(opts)?;
    let (gx, gw) = gauss_legendre(opts.albedo_order);
    let turns = light_azimuths(opts.albedo_azimuths);
    let share = 1.0 / turns.len() as f64;
    let curves: Vec<(Vec<f64>, Vec<f64>)> = opts
        .albedo_thetas_deg
        .par_iter()
        .map(|&t| {
            let (mut ma, mut mb) = (vec![0.0; c], vec![0.0; c]);
            for &phi in &turns {
                let (sa, sb) = mirror_quadrature(
                    &Turned(a, phi),
                    &Turned(b, phi),
                    t.to_radians(),
                    opts.albedo_phi,
                    &gx,
                    &gw,
                );
                for ch in 0..c {
                    ma[ch] += share * sa[ch];
                    mb[ch] += share * sb[ch];
                }
            }
            (ma, mb)
        })
        .collect();
    Ok(curves.into_iter().unzip())
}

/// ∫ f cos θo dωo of `a` and `b` for wi at polar angle `theta` (azimuth 0), on the same nodes
/// ([`mirror_rule`] with Gauss-Legendre nodes `gx`, `gw`).
fn mirror_quadrature(
    a: &dyn Brdf,
    b: &dyn Brdf,
    theta: f64,
    nphi: usize,
    gx: &[f64],
    gw: &[f64],
) -> ([f64; MAX_CHANNELS], [f64; MAX_CHANNELS]) {
    let c = b.channels().len();
    let (mut sa, mut sb) = ([0.0f64; MAX_CHANNELS], [0.0f64; MAX_CHANNELS]);
    let (mut fa, mut fb) = ([0.0f32; MAX_CHANNELS], [0.0f32; MAX_CHANNELS]);
    mirror_rule(theta, nphi, gx, gw, None, |wi, wo, w| {
        let weight = w * wo.z;
        a.eval(wi, wo, &mut fa[..c]);
        b.eval(wi, wo, &mut fb[..c]);
        for ch in 0..c {
            sa[ch] += weight * fa[ch] as f64;
            sb[ch] += weight * fb[ch] as f64;
        }
    });
    (sa, sb)
}

/// The directional albedo a(θ′) = ∫ f_r cos θo dωo of `brdf` per channel, wi at polar angle
/// `theta` (radians, azimuth 0), on the mirror-centred product rule of
/// [`measure`](super::measure) with `nphi` azimuths and `order` Gauss-Legendre nodes per
/// segment. Two BRDFs integrated with the same arguments share every node, so their ratio
/// carries little of the rule's own error.
pub fn mirror_albedo(
    brdf: &dyn Brdf,
    theta: f64,
    nphi: usize,
    order: usize,
) -> [f64; MAX_CHANNELS] {
    let c = brdf.channels().len().min(MAX_CHANNELS);
    let (gx, gw) = gauss_legendre(order.max(1));
    let mut s = [0.0f64; MAX_CHANNELS];
    let mut f = [0.0f32; MAX_CHANNELS];
    mirror_rule(theta, nphi.max(1), &gx, &gw, None, |wi, wo, w| {
        let weight = w * wo.z;
        brdf.eval(wi, wo, &mut f[..c]);
        for ch in 0..c {
            s[ch] += weight * f[ch] as f64;
        }
    });
    s
}

/// `brdf` with its directions swapped: its directional albedo ([`mirror_albedo`]) is the
/// viewer's albedo of `brdf`, ∫ f_r(wi, wo) cos θi dωi for a view wo — what a white furnace
/// shows at that view. For a reciprocal BRDF the two albedos agree; measured data are not.
pub struct Reversed<'a>(pub &'a dyn Brdf);

impl Brdf for Reversed<'_> {
    fn channels(&self) -> &crate::spectrum::Channels {
        self.0.channels()
    }
    fn eval(&self, wi: glam::DVec3, wo: glam::DVec3, out: &mut [f32]) {
        self.0.eval(wo, wi, out)
    }
    fn flags(&self) -> crate::brdf::Flags {
        self.0.flags()
    }
    fn describe(&self) -> String {
        format!("{} (directions swapped)", self.0.describe())
    }
}

/// The worst albedo error of `approx` against `reference` (see the module docs).
pub fn albedo_error(
    approx: &dyn Brdf,
    reference: &dyn Brdf,
    opts: &FidelityOptions,
) -> Result<AlbedoError> {
    let (a, r) = albedo_pair(approx, reference, opts)?;
    Ok(worst_albedo(&a, &r, opts))
}

/// The worst relative difference of albedo curve `a` from `r` (a channel darker than
/// [`FidelityOptions::dark_floor`] judged against the floor).
pub fn worst_albedo(a: &AlbedoCurve, r: &AlbedoCurve, opts: &FidelityOptions) -> AlbedoError {
    let mut worst = AlbedoError {
        worst: 0.0,
        theta_deg: opts.albedo_thetas_deg.first().copied().unwrap_or(0.0),
        channel: 0,
        approx: 0.0,
        reference: 0.0,
    };
    for (k, (ak, rk)) in a.iter().zip(r).enumerate() {
        for (ch, (&x, &y)) in ak.iter().zip(rk).enumerate() {
            let e = (x - y).abs() / y.abs().max(opts.dark_floor);
            if e > worst.worst || e.is_nan() {
                worst = AlbedoError {
                    worst: e,
                    theta_deg: opts.albedo_thetas_deg[k],
                    channel: ch,
                    approx: x,
                    reference: y,
                };
            }
        }
    }
    worst
}
