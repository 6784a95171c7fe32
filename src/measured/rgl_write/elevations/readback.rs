//! Measuring a file read back against its source over a range of incidences: the errors and
//! the albedos the placement of elevations and azimuths decides on.

use std::f64::consts::TAU;

use super::{CONE, DARK_FLOOR, Errors, PAIRS};
use crate::analysis::pair_rule::mirror_rule;
use crate::brdf::Brdf;
use crate::geometry;
use crate::measured::RglBrdf;
use crate::quadrature::gauss_legendre;
use crate::rng::Pcg32;
use crate::spectrum::MAX_CHANNELS;

/// Which incident azimuths a measurement draws and where it turns the light for the albedo.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Azimuths {
    /// Incident azimuths are drawn uniformly in [`from`, `to`] (radians); `from == to`: that
    /// azimuth alone.
    pub(crate) from: f64,
    /// The end of the range.
    pub(crate) to: f64,
    /// The light's azimuth of the albedo (radians).
    pub(crate) light: f64,
    /// The albedo quadrature's azimuths about the mirror direction and Gauss-Legendre nodes
    /// per segment ([`mirror_albedo`](crate::analysis::fidelity::mirror_albedo)).
    pub(crate) rule: [usize; 2],
}

/// Every incident azimuth, the albedo at the light's azimuth 0 (an isotropic source's).
pub(super) const WHOLE_CIRCLE: Azimuths = Azimuths {
    from: 0.0,
    to: TAU,
    light: 0.0,
    rule: [128, 8],
};

/// Measures the file against the source for incident elevations in (`a`, `b`) (radians) and
/// azimuths `az`: error and reference integrated over that range of incidences, or per unit
/// solid angle where the range is a single elevation or azimuth.
pub(crate) fn measure(
    file: &RglBrdf,
    src: &dyn Brdf,
    a: f64,
    b: f64,
    az: &Azimuths,
    seed: u64,
) -> Errors {
    let c = src.channels().len().min(MAX_CHANNELS);
    let cap = super::report::MAX_THETA.cos();
    let (ca, cb) = (a.cos(), b.cos());
    // One elevation or one azimuth alone: densities per unit solid angle of incidences.
    let measure = if a == b || az.from == az.to {
        1.0
    } else {
        (az.to - az.from) * (ca - cb)
    };
    let cone_pdf = 1.0 / (TAU * (1.0 - CONE.cos()));
    let mut rng = Pcg32::with_stream(seed, 0x0e1e);
    let mut out = Errors::default();
    let (mut fa, mut fb) = ([0.0f32; MAX_CHANNELS], [0.0f32; MAX_CHANNELS]);
    for s in 0..PAIRS {
        let ci = ca - (ca - cb) * (s as f64 + rng.next_f64()) / PAIRS as f64;
        let phi = az.from + (az.to - az.from) * rng.next_f64();
        let wi = geometry::spherical(ci.clamp(0.0, 1.0).acos(), phi);
        let wo = if s % 2 == 0 {
            let z = rng.next_f64();
            geometry::spherical(z.acos(), TAU * rng.next_f64())
        } else {
            let z = 1.0 - (1.0 - CONE.cos()) * rng.next_f64();
            let local = geometry::spherical(z.acos(), TAU * rng.next_f64());
            geometry::Frame::from_normal(geometry::reflect_z(wi)).to_world(local)
        };
        if wo.z <= 0.0 || wi.z <= 0.0 {
            continue;
        }
        let in_cone = wo.dot(geometry::reflect_z(wi)) >= CONE.cos();
        let pdf = 0.5 / TAU + if in_cone { 0.5 * cone_pdf } else { 0.0 };
        // Pairs uniform in solid angle over the interval's incidences and the hemisphere.
        let w = measure / (TAU * pdf) / PAIRS as f64;
        file.eval(wi, wo, &mut fa[..c]);
        src.eval(wi, wo, &mut fb[..c]);
        let cc = wi.z * wo.z;
        let (mut e, mut r) = (0.0, 0.0);
        for ch in 0..c {
            let (x, y) = (fa[ch] as f64 * cc, fb[ch] as f64 * cc);
            if x.is_finite() && y.is_finite() {
                e += (x - y) * (x - y);
                r += y * y;
            }
        }
        let band = wi.z < cap || wo.z < cap;
        let k = if band { 2 } else { 0 };
        out.err[k] += w * e;
        out.reference[k] += w * r;
        out.err[1] += w * e;
        out.reference[1] += w * r;
    }
    // The albedo at the whole degrees of the fidelity report inside the interval (its middle
    // when there are none; the elevation itself for one).
    let (lo, hi) = (a.to_degrees(), b.to_degrees());
    let mut degrees: Vec<f64> = ((lo.floor() as i64)..=(hi.ceil() as i64))
        .map(|d| d as f64)
        .filter(|&d| d > lo && d < hi)
        .collect();
    if degrees.is_empty() {
        degrees.push(0.5 * (lo + hi));
    }
    let (gx, gw) = gauss_legendre(az.rule[1].max(1));
    for deg in degrees.into_iter().filter(|d| (0.0..=89.0).contains(d)) {
        let (x, y) = albedos(
            file,
            src,
            az.light,
            deg.to_radians(),
            az.rule[0],
            (&gx, &gw),
        );
        for ch in 0..c {
            out.albedo = out
                .albedo
                .max((x[ch] - y[ch]).abs() / y[ch].max(DARK_FLOOR));
        }
    }
    out
}

/// The directional albedos of `file` and `src` with the light at azimuth `light` (each turned by
/// it, as [`Turned`](crate::analysis::fidelity::Turned) turns them) and at elevation `theta`: what
/// [`mirror_albedo`](crate::analysis::fidelity::mirror_albedo) gives for each,
/// to the bit (the same nodes, turned the same way, summed in the same order), from one walk of
/// the rule and one turn of each node (session 42: this walk, and `Turned`'s sine and cosine
/// of the light at every evaluation, were a fifth of an anisotropic file's placement).
pub(super) fn albedos(
    file: &RglBrdf,
    src: &dyn Brdf,
    light: f64,
    theta: f64,
    nphi: usize,
    (gx, gw): (&[f64], &[f64]),
) -> ([f64; MAX_CHANNELS], [f64; MAX_CHANNELS]) {
    let c = src.channels().len().min(MAX_CHANNELS);
    let (s, co) = light.sin_cos();
    let turn = |v: glam::DVec3| {
        if light == 0.0 {
            v
        } else {
            glam::DVec3::new(co * v.x - s * v.y, s * v.x + co * v.y, v.z)
        }
    };
    let (mut x, mut y) = ([0.0f64; MAX_CHANNELS], [0.0f64; MAX_CHANNELS]);
    let (mut fa, mut fb) = ([0.0f32; MAX_CHANNELS], [0.0f32; MAX_CHANNELS]);
    // mirror_rule's incident direction, as it makes it.
    let (st, ct) = theta.sin_cos();
    let at = file.at_incidence(turn(glam::DVec3::new(st, 0.0, ct)));
    mirror_rule(theta, nphi.max(1), gx, gw, None, |wi, wo, w| {
        let weight = w * wo.z;
        let (ti, to) = (turn(wi), turn(wo));
        at.eval(to, &mut fa[..c]);
        src.eval(ti, to, &mut fb[..c]);
        for ch in 0..c {
            x[ch] += weight * fa[ch] as f64;
            y[ch] += weight * fb[ch] as f64;
        }
    });
    (x, y)
}
