//! Physical plausibility of any BRDF: positivity, reciprocity and energy conservation.
//!
//! The lecture calls a BRDF *physically plausible* when it is positive, symmetric (Helmholtz
//! reciprocity) and energy conserving (albedo < 1 for every incident direction) — exactly the
//! conditions under which the light-transport operator is a contraction and a global illumination
//! solver converges. [`check`] measures all three on any `&dyn Brdf` — an analytic model, a baked
//! table, a measurement — and reports them next to what the source *declares* about itself
//! ([`Flags`]), so a model that claims reciprocity but is not (or a table whose interpolation
//! breaks it) shows up at once.
//!
//! - **Positivity**: the smallest value over many direction pairs and channels (non-finite values
//!   are counted separately and make the source non-positive).
//! - **Reciprocity**: the largest relative difference |f(a, b) − f(b, a)| / max(|f(a, b)|,
//!   |f(b, a)|, floor) over the same pairs. The pairs are random but deterministic (PCG32 with a
//!   fixed seed): half uniform on the hemisphere, a quarter near the mirror configuration (where
//!   sharp lobes live) and a quarter near grazing.
//! - **Energy conservation**: the directional albedo ([`Brdf::albedo`], i.e. the model's closed
//!   form or the adaptive quadrature of [`super::albedo`]) for incidence angles 0..89°; for
//!   sources not declared isotropic at several azimuths.
//!
//! ```
//! use brdftab::{analysis::plausibility, spec::ModelSpec, spectrum::Channels};
//! let brdf = ModelSpec::parse(r#"{"model": "lambert", "kd": 0.5}"#)?.build(&Channels::Rgb)?;
//! let report = plausibility::check(&*brdf, &plausibility::Options::default())?;
//! assert!(report.positive && report.reciprocal);
//! assert!(!report.energy_conserving); // k_d > 1/π
//! assert!((report.max_albedo - 0.5 * std::f64::consts::PI).abs() < 1e-6);
//! # Ok::<(), brdftab::Error>(())
//! ```

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::Serialize;

use crate::brdf::{Brdf, Flags};
use crate::error::{Error, Result};
use crate::geometry;
use crate::rng::Pcg32;
use crate::spectrum::MAX_CHANNELS;

mod display;
mod lecture;
#[cfg(test)]
mod tests;

pub use lecture::{LECTURE_MODELS, lecture_table};

/// The angles past 89° the default check looks at. The lecture's albedo argument for the
/// original Phong (θ′ ≈ θ in the lobe) gives ≈ 2π k_s/(n+1), but its exact albedo grows like
/// 1/cos θ′ and Ward's like 1/√cos θ′: both stay below 1 up to 89° for k_s = 0.5 (0.79 and
/// 0.50) and pass 1 only beyond (Phong n = 20: 7.3 at 89.9°; Ward α = 0.5: 1.48 at 89.9°, 4.66
/// at 89.99°). Checked on every degree alone, both were called energy conserving.
pub const NEAR_HORIZON_DEG: [f64; 2] = [89.9, 89.99];

/// Settings of [`check`].
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Number of random direction pairs for positivity and reciprocity.
    pub pairs: usize,
    /// Seed of the pair generator (the report is deterministic for a given seed).
    pub seed: u64,
    /// Incidence angles in degrees at which the albedo is computed, each in [0°, 90°): light at
    /// the horizon has an albedo only as a limit, and not always a finite one (Ward's grows
    /// like 1/√cos θ′, the original Phong's like 1/cos θ′), so [`check`] refuses 90° as the
    /// `albedo` command does. The default is every degree 0..89 and then [`NEAR_HORIZON_DEG`].
    pub thetas_deg: Vec<f64>,
    /// Largest relative reciprocity error still called reciprocal.
    pub reciprocity_tolerance: f64,
    /// Absolute floor (1/sr) of the denominator of the relative reciprocity error, so values
    /// that are both essentially zero do not count.
    pub reciprocity_floor: f64,
    /// Largest albedo excess over 1 still called energy conserving (quadrature slack).
    pub albedo_tolerance: f64,
    /// How the albedo is computed: `None` asks the BRDF ([`Brdf::albedo`]: a closed form, the
    /// default quadrature, or for tables and measured data the bounded
    /// [`Options::DATA`](super::albedo::Options::DATA)); `Some` integrates every source with
    /// these settings.
    pub albedo: Option<super::albedo::Options>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            pairs: 20_000,
            seed: 0x5eed_b7df,
            thetas_deg: (0..90).map(f64::from).chain(NEAR_HORIZON_DEG).collect(),
            reciprocity_tolerance: 1e-3,
            reciprocity_floor: 1e-6,
            albedo_tolerance: 1e-3,
            albedo: None,
        }
    }
}

/// A direction given by its spherical angles in degrees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AnglesDeg {
    /// Polar angle from the normal.
    pub theta: f64,
    /// Azimuth from +x.
    pub phi: f64,
}

impl AnglesDeg {
    fn of(w: DVec3) -> Self {
        let (t, p) = geometry::to_spherical(w);
        AnglesDeg {
            theta: t.to_degrees(),
            phi: p.to_degrees(),
        }
    }
}

/// One point of the albedo curve.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AlbedoPoint {
    /// Incidence angle θ′ in degrees (azimuth 0).
    pub theta_deg: f64,
    /// The albedo per channel.
    pub albedo: Vec<f64>,
}

/// The plausibility of a BRDF, measured, next to what it declares. Serializes to one JSON object.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// The source's own description.
    pub source: String,
    /// Channel names (`R`, `G`, `B` or wavelengths).
    pub channels: Vec<String>,
    /// What the source declares about itself.
    pub declared: Flags,
    /// Number of direction pairs evaluated (each in both orders).
    pub pairs: usize,
    /// No negative or non-finite value was seen.
    pub positive: bool,
    /// The smallest finite value seen (1/sr).
    pub min_value: f64,
    /// The number of non-finite (NaN, ±∞) values seen.
    pub non_finite: usize,
    /// `max_reciprocity_error` ≤ the tolerance.
    pub reciprocal: bool,
    /// The largest relative |f(a, b) − f(b, a)| seen.
    pub max_reciprocity_error: f64,
    /// Where the largest reciprocity error was seen (`[wi, wo]`), if any was nonzero.
    pub max_reciprocity_at: Option<[AnglesDeg; 2]>,
    /// The tolerance applied to `max_reciprocity_error`.
    pub reciprocity_tolerance: f64,
    /// `max_albedo` ≤ 1 + the tolerance.
    pub energy_conserving: bool,
    /// The largest albedo over every angle and channel.
    pub max_albedo: f64,
    /// The incidence angle at which it occurs (degrees).
    pub max_albedo_theta_deg: f64,
    /// The incidence azimuth at which it occurs (degrees; 0 for isotropic sources).
    pub max_albedo_phi_deg: f64,
    /// The channel in which it occurs.
    pub max_albedo_channel: String,
    /// The tolerance applied to `max_albedo − 1`.
    pub albedo_tolerance: f64,
    /// The albedo at every checked incidence angle (azimuth 0).
    pub albedo_curve: Vec<AlbedoPoint>,
}

impl Report {
    /// The three lecture properties at once: positive, reciprocal and energy conserving.
    pub fn plausible(&self) -> bool {
        self.positive && self.reciprocal && self.energy_conserving
    }
}

/// Measures positivity, reciprocity and energy conservation of `brdf`.
///
/// # Errors
/// [`Error::InvalidArgument`] (`thetas_deg`) for an incidence angle outside [0°, 90°) or not a
/// number; the source's own error ([`Brdf::health`]) when it failed while it was read (a table
/// chunk that did not decode reads as zeros, and a report of those would be wrong).
pub fn check(brdf: &dyn Brdf, opts: &Options) -> Result<Report> {
    if let Some(t) = opts.thetas_deg.iter().find(|t| !(0.0..90.0).contains(*t)) {
        return Err(Error::arg(
            "thetas_deg",
            format!("{t}° is outside [0°, 90°): the albedo is defined for light above the horizon"),
        ));
    }
    let channels = brdf.channels();
    let c = channels.len().min(MAX_CHANNELS);
    let declared = brdf.flags();

    // Positivity and reciprocity over deterministic random pairs.
    let mut rng = Pcg32::new(opts.seed);
    let (mut fab, mut fba) = ([0.0f32; MAX_CHANNELS], [0.0f32; MAX_CHANNELS]);
    let mut min_value = f64::INFINITY;
    let mut non_finite = 0usize;
    let mut max_err = 0.0f64;
    let mut max_at = None;
    for k in 0..opts.pairs {
        let (a, b) = random_pair(&mut rng, k);
        brdf.eval(a, b, &mut fab[..c]);
        brdf.eval(b, a, &mut fba[..c]);
        for ch in 0..c {
            let (x, y) = (fab[ch] as f64, fba[ch] as f64);
            for v in [x, y] {
                if v.is_finite() {
                    min_value = min_value.min(v);
                } else {
                    non_finite += 1;
                }
            }
            if x.is_finite() && y.is_finite() {
                let err = (x - y).abs() / x.abs().max(y.abs()).max(opts.reciprocity_floor);
                if err > max_err {
                    max_err = err;
                    max_at = Some([AnglesDeg::of(a), AnglesDeg::of(b)]);
                }
            }
        }
    }
    if !min_value.is_finite() {
        min_value = 0.0;
    }

    // Energy: the albedo at every angle (and a few azimuths for anisotropic sources).
    let azimuths: &[f64] = if declared.isotropic {
        &[0.0]
    } else {
        &[0.0, 45.0, 90.0, 135.0]
    };
    let jobs: Vec<(f64, f64)> = opts
        .thetas_deg
        .iter()
        .flat_map(|&t| azimuths.iter().map(move |&p| (t, p)))
        .collect();
    let albedos: Vec<Vec<f64>> = crate::par::install(|| {
        jobs.par_iter()
            .map(|&(t, p)| {
                let wi = geometry::spherical(t.to_radians(), p.to_radians());
                match &opts.albedo {
                    Some(o) => super::albedo::integrate(brdf, wi, o).value,
                    None => {
                        let mut a = vec![0.0; c];
                        brdf.albedo(wi, &mut a);
                        a
                    }
                }
            })
            .collect()
    });
    let (mut max_albedo, mut max_t, mut max_p, mut max_ch) = (0.0f64, 0.0, 0.0, 0usize);
    let mut curve = Vec::with_capacity(opts.thetas_deg.len());
    for (&(t, p), a) in jobs.iter().zip(&albedos) {
        for (ch, &v) in a.iter().enumerate() {
            if v > max_albedo || v.is_nan() && !max_albedo.is_nan() {
                (max_albedo, max_t, max_p, max_ch) = (v, t, p, ch);
            }
        }
        if p == 0.0 {
            curve.push(AlbedoPoint {
                theta_deg: t,
                albedo: a.clone(),
            });
        }
    }
    brdf.health()?;
    let names = channels.names();
    Ok(Report {
        source: brdf.describe(),
        channels: names.clone(),
        declared,
        pairs: opts.pairs,
        positive: min_value >= 0.0 && non_finite == 0,
        min_value,
        non_finite,
        reciprocal: max_err <= opts.reciprocity_tolerance,
        max_reciprocity_error: max_err,
        max_reciprocity_at: max_at,
        reciprocity_tolerance: opts.reciprocity_tolerance,
        energy_conserving: max_albedo <= 1.0 + opts.albedo_tolerance,
        max_albedo,
        max_albedo_theta_deg: max_t,
        max_albedo_phi_deg: max_p,
        max_albedo_channel: names.get(max_ch).cloned().unwrap_or_default(),
        albedo_tolerance: opts.albedo_tolerance,
        albedo_curve: curve,
    })
}

/// The k-th random pair: uniform, near-mirror or near-grazing, in turn.
fn random_pair(rng: &mut Pcg32, k: usize) -> (DVec3, DVec3) {
    let a = geometry::uniform_hemisphere(rng.next_dvec2());
    match k % 4 {
        // Near the mirror configuration: the mirror direction of `a` tilted by a log-uniform
        // angle between 1e-4 and 0.3 rad, so sharp lobes are probed at every scale.
        1 => {
            let r = geometry::reflect_z(a);
            let frame = geometry::Frame::from_normal(r);
            let tilt = 1e-4 * (0.3f64 / 1e-4).powf(rng.next_f64());
            let phi = std::f64::consts::TAU * rng.next_f64();
            let local = geometry::spherical(tilt, phi);
            let b = frame.to_world(local);
            if b.z > 0.0 { (a, b) } else { (a, r) }
        }
        // Near grazing: one direction between 80° and 89.9°.
        2 => {
            let u = rng.next_dvec2();
            let t = (80.0 + 9.9 * u.x).to_radians();
            let g = geometry::spherical(t, std::f64::consts::TAU * u.y);
            (g, a)
        }
        _ => (
            a,
            geometry::uniform_hemisphere(DVec2::new(rng.next_f64(), rng.next_f64())),
        ),
    }
}
