//! Where a written file's incident elevations go: placed where the file's own reader is
//! farthest from the source.
//!
//! A `.bsdf` reader interpolates the stored values linearly in θi between two incident slices,
//! at the same point of their warps' input squares. How far apart the slices may be depends on
//! the source: a Lambertian's interpolation error is largest near normal incidence, a rough
//! conductor's near grazing, where its lobe runs into the horizon. One spacing for every
//! source cannot serve both (16 elevations even in cos θi: Cook-Torrance gold's albedo 4.5 % off
//! at 89°; even in θi: its grazing band 10 %, BENCHMARKS.md "Written files placed where they
//! are wrong").
//!
//! [`place`] starts from [`START`] elevations even in cos θi (the count written before) and,
//! one step at a time, writes the file in memory, reads it back with brdftab's RGL reader and
//! measures it against the source on each interval between elevations and at each elevation —
//! the figures of [`analysis::fidelity`](crate::analysis::fidelity): the cos θi cos θo-weighted
//! relative RMSE within 80°, over the whole hemisphere and over the grazing band (pairs uniform
//! in solid angle, half of them drawn near the mirror direction and weighted back), and the
//! directional albedo at the whole degrees inside the interval. Of the figures past
//! [`MARGIN`] × their bar ([`BARS`]) whose error is not mostly what the slices themselves give
//! (more elevations cannot lower that part; [`IMPROVABLE`]), the one farthest past its bar
//! decides: the interval whose error there exceeds its slices' the most is split in the middle
//! (in θi). It stops when no figure qualifies or at the most elevations allowed. A split
//! changes the reader only between the two slices around it, so only the two new intervals and
//! the new elevation are measured, and every slice is encoded once.

use std::collections::HashMap;
use std::f64::consts::{PI, TAU};

use super::ndf::Ndf;
use super::{Layout, Progress, values, warps};
use crate::analysis::pair_rule::mirror_rule;
use crate::brdf::Brdf;
use crate::error::Result;
use crate::geometry;
use crate::measured::RglBrdf;
use crate::measured::tensor::TensorFile;
use crate::progress::Quiet;
use crate::quadrature::gauss_legendre;
use crate::rng::Pcg32;
use crate::spectrum::MAX_CHANNELS;

/// Elevations placement starts from (even in cos θi).
pub const START: usize = 16;

/// The most elevations [`place`] uses by default.
pub const MAX: usize = 32;

/// The bars, relative: within 80°, whole hemisphere, grazing band (cos θi cos θo-weighted
/// relative RMSEs) and directional albedo (a channel darker than [`DARK_FLOOR`] judged
/// against it) — those of the measured tables (issue 22).
pub const BARS: [f64; 4] = [0.01, 0.015, 0.03, 0.01];

/// Placement stops when every figure is within this fraction of its bar (the per-interval
/// estimates are noisier than the final report's).
pub const MARGIN: f64 = 0.7;

/// Albedos darker than this are judged against it.
pub const DARK_FLOOR: f64 = 0.02;

/// A figure is worth splitting for while more than this fraction of it lies above what its
/// slices alone give.
pub const IMPROVABLE: f64 = 0.1;

/// The closest two elevations may be (radians): a reader's slices 0.25° apart already
/// interpolate the last degree before the horizon in four steps.
pub const MIN_STEP: f64 = 0.25 * PI / 180.0;

/// Pairs drawn per interval and step.
pub(super) const PAIRS: usize = 3000;

/// Angle of the cone about the mirror direction that half the pairs are drawn in (radians):
/// a sharp lobe is then seen on every step, not by lottery.
const CONE: f64 = 20.0 * PI / 180.0;

/// What one interval between elevations measured: squared errors and squared references of
/// f_r cos θi cos θo (within 80°, whole, grazing band), integrated over the interval's
/// incidences, and the worst albedo error at the whole degrees inside it (its middle when
/// there are none). For one elevation alone (θi exactly there) the same per unit solid angle.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Errors {
    pub(super) err: [f64; 3],
    pub(super) reference: [f64; 3],
    pub(super) albedo: f64,
}

/// The four figures divided by their bars, and the part of each that splitting cannot lower:
/// what the slices themselves give.
pub(super) fn figures(iv: &[Errors], floors: &[Errors]) -> ([f64; 4], [f64; 4]) {
    let (mut fig, mut floor) = ([0.0; 4], [0.0; 4]);
    for (k, bar) in BARS.iter().enumerate().take(3) {
        let e: f64 = iv.iter().map(|i| i.err[k]).sum();
        let f: f64 = floors.iter().map(|i| i.err[k]).sum();
        let r: f64 = iv.iter().map(|i| i.reference[k]).sum();
        if r > 0.0 {
            fig[k] = (e / r).sqrt() / bar;
            floor[k] = (f.min(e) / r).sqrt() / bar;
        }
    }
    fig[3] = iv.iter().map(|i| i.albedo).fold(0.0, f64::max) / BARS[3];
    floor[3] = floors.iter().map(|i| i.albedo).fold(0.0, f64::max) / BARS[3];
    (fig, floor)
}

/// The slice-limited errors of the interval between elevations `ta` and `tb`: the mean of the
/// two slices' densities over the interval's solid angle, the larger albedo error.
fn floor_of(a: &Errors, b: &Errors, ta: f64, tb: f64) -> Errors {
    floor_over(a, b, TAU * (ta.cos() - tb.cos()))
}

/// The slice-limited errors of a cell of solid angle `measure` between two slices (or rows of
/// slices) whose densities are `a` and `b`.
pub(super) fn floor_over(a: &Errors, b: &Errors, measure: f64) -> Errors {
    let mut out = Errors::default();
    for k in 0..3 {
        out.err[k] = measure * 0.5 * (a.err[k] + b.err[k]);
        out.reference[k] = measure * 0.5 * (a.reference[k] + b.reference[k]);
    }
    out.albedo = a.albedo.max(b.albedo);
    out
}

/// One elevation's encoded slices (every azimuth): VNDF densities, values and validity.
pub(super) struct Slice {
    pub(super) vndf: Vec<f32>,
    pub(super) values: Vec<f32>,
    pub(super) valid: Vec<bool>,
}

/// What [`place`] chose and measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// The elevations in increasing order (radians), the first 0 and the last 90°.
    pub theta_i: Vec<f32>,
    /// Its estimates of the four figures (within 80°, whole, grazing band, albedo), each
    /// divided by its bar ([`BARS`]).
    pub figures: [f64; 4],
    /// The part of each that the slices themselves give (more elevations cannot lower it; a
    /// finer table can).
    pub floors: [f64; 4],
}

impl Placement {
    /// Whether a figure stays past its bar: the slices alone keep it there, or the most
    /// elevations allowed did not bring it down.
    pub fn past_bar(&self) -> bool {
        self.worst() > 1.0
    }

    /// The largest of the four figures (each divided by its bar).
    pub fn worst(&self) -> f64 {
        self.figures.iter().fold(0.0, |m, &f| m.max(f))
    }
}

/// Chooses the incident elevations for `brdf` (at most `max`, at least [`START`]), with `base`
/// giving every other part of the layout.
pub fn place(
    brdf: &dyn Brdf,
    ndf: &Ndf,
    base: &Layout,
    max: usize,
    progress: &dyn Progress,
) -> Result<Placement> {
    let start = START.min(max).max(2);
    let mut theta: Vec<f64> = (0..start)
        .map(|k| (1.0 - k as f64 / (start - 1) as f64).clamp(0.0, 1.0).acos())
        .collect();
    let mut cache: HashMap<u64, Slice> = HashMap::new();
    let _stage = crate::progress::Stage::begin(progress, "placing elevations", max as u64);
    let mut file = reader(brdf, ndf, base, &theta, &mut cache, progress)?;
    let check = || crate::progress::check(progress);
    let mut at: Vec<Errors> = (0..theta.len())
        .map(|k| {
            check()?;
            Ok(measure(
                &file,
                brdf,
                theta[k],
                theta[k],
                &WHOLE_CIRCLE,
                k as u64,
            ))
        })
        .collect::<Result<_>>()?;
    let mut iv: Vec<Errors> = (0..theta.len() - 1)
        .map(|k| {
            check()?;
            Ok(measure(
                &file,
                brdf,
                theta[k],
                theta[k + 1],
                &WHOLE_CIRCLE,
                100 + k as u64,
            ))
        })
        .collect::<Result<_>>()?;
    let floors = |theta: &[f64], at: &[Errors]| -> Vec<Errors> {
        (0..theta.len() - 1)
            .map(|k| floor_of(&at[k], &at[k + 1], theta[k], theta[k + 1]))
            .collect()
    };
    loop {
        progress.set(theta.len() as u64);
        crate::progress::check(progress)?;
        let fl = floors(&theta, &at);
        let (fig, floor) = figures(&iv, &fl);
        let done = Placement {
            theta_i: theta.iter().map(|&t| t as f32).collect(),
            figures: fig,
            floors: floor,
        };
        if theta.len() >= max {
            return Ok(done);
        }
        // The figure farthest past its bar among those that splitting can still lower.
        let Some(worst) = (0..4)
            .filter(|&k| fig[k] > MARGIN && fig[k] - floor[k] > IMPROVABLE * fig[k])
            .max_by(|&a, &b| fig[a].total_cmp(&fig[b]))
        else {
            return Ok(done);
        };
        let gain = |j: usize| match worst {
            3 => iv[j].albedo - fl[j].albedo,
            k => iv[j].err[k] - fl[j].err[k],
        };
        let Some(j) = (0..iv.len())
            .filter(|&k| theta[k + 1] - theta[k] > 2.0 * MIN_STEP)
            .max_by(|&a, &b| gain(a).total_cmp(&gain(b)))
        else {
            return Ok(done);
        };
        let mid = 0.5 * (theta[j] + theta[j + 1]);
        theta.insert(j + 1, mid);
        file = reader(brdf, ndf, base, &theta, &mut cache, progress)?;
        let seed = theta.len() as u64 * 1000;
        check()?;
        at.insert(j + 1, measure(&file, brdf, mid, mid, &WHOLE_CIRCLE, seed));
        check()?;
        let left = measure(&file, brdf, theta[j], mid, &WHOLE_CIRCLE, seed + 1);
        check()?;
        let right = measure(&file, brdf, mid, theta[j + 2], &WHOLE_CIRCLE, seed + 2);
        iv.splice(j..=j, [left, right]);
    }
}

/// The file of `base` with elevations `theta`, read back by brdftab's RGL reader; slices
/// not in `cache` are encoded and kept there (`progress` asked to stop as each is sampled).
fn reader(
    brdf: &dyn Brdf,
    ndf: &Ndf,
    base: &Layout,
    theta: &[f64],
    cache: &mut HashMap<u64, Slice>,
    progress: &dyn Progress,
) -> Result<RglBrdf> {
    let nch = brdf.channels().len();
    let (np, n) = (base.phi_i.len(), base.n);
    let plane = n * n;
    let vplane = base.vndf[0] * base.vndf[1];
    for &t in theta {
        if cache.contains_key(&t.to_bits()) {
            continue;
        }
        let layout = Layout {
            theta_i: vec![t as f32],
            ..base.clone()
        };
        let w = warps::vndf(ndf, &layout)?;
        let v = values::sample(brdf, ndf, &w, &layout, None, &Quiet(progress))?;
        let valid = super::container::unpack_bits(&v.valid, np * plane);
        cache.insert(
            t.to_bits(),
            Slice {
                vndf: w.data,
                values: v.data,
                valid,
            },
        );
    }
    let nt = theta.len();
    let mut vndf = Vec::with_capacity(np * nt * vplane);
    let mut data = Vec::with_capacity(np * nt * nch * plane);
    let mut valid = Vec::with_capacity(np * nt * plane);
    for p in 0..np {
        for &t in theta {
            let s = &cache[&t.to_bits()];
            vndf.extend_from_slice(&s.vndf[p * vplane..(p + 1) * vplane]);
            data.extend_from_slice(&s.values[p * nch * plane..(p + 1) * nch * plane]);
            valid.extend_from_slice(&s.valid[p * plane..(p + 1) * plane]);
        }
    }
    let layout = Layout {
        theta_i: theta.iter().map(|&t| t as f32).collect(),
        ..base.clone()
    };
    let values = super::Values {
        data,
        valid: super::container::pack_bits(&valid),
    };
    let fields = super::fields_of(String::new(), &layout, ndf, vndf, values, brdf.channels());
    let tf = TensorFile::from_bytes("(placing elevations)", fields.to_bytes())?;
    RglBrdf::from_tensor_unhashed(&tf)
}

/// Which incident azimuths a measurement draws and where it turns the light for the albedo.
#[derive(Debug, Clone, Copy)]
pub(super) struct Azimuths {
    /// Incident azimuths are drawn uniformly in [`from`, `to`] (radians); `from == to`: that
    /// azimuth alone.
    pub(super) from: f64,
    /// The end of the range.
    pub(super) to: f64,
    /// The light's azimuth of the albedo (radians).
    pub(super) light: f64,
    /// The albedo quadrature's azimuths about the mirror direction and Gauss-Legendre nodes
    /// per segment ([`mirror_albedo`](crate::analysis::fidelity::mirror_albedo)).
    pub(super) rule: [usize; 2],
}

/// Every incident azimuth, the albedo at the light's azimuth 0 (an isotropic source's).
const WHOLE_CIRCLE: Azimuths = Azimuths {
    from: 0.0,
    to: TAU,
    light: 0.0,
    rule: [128, 8],
};

/// Measures the file against the source for incident elevations in (`a`, `b`) (radians) and
/// azimuths `az`: error and reference integrated over that range of incidences, or per unit
/// solid angle where the range is a single elevation or azimuth.
pub(super) fn measure(
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
fn albedos(
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
