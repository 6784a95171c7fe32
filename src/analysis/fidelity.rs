//! How faithful a table is to its source over the whole domain, not only inside a cap.
//!
//! A renderer looks at a material from every angle. An error judged within 80° of the normal
//! (the usual measured-data metric) cannot see a table that is too bright at grazing angles, nor
//! an albedo that is off at normal incidence; [`measure`] reports, beside that cap figure,
//!
//! - the relative RMSE of f_r cos θi cos θo over the **whole hemisphere** of both directions;
//! - the same over the **grazing band**, the pairs with a direction farther than 80° from the
//!   normal ([`Region::Band`]);
//! - the worst **directional albedo** error over θ′ = 1°, 2°, …, 89° and every channel, both
//!   albedos computed with one quadrature on the same points (so the difference is the
//!   table's, not the quadrature's), a channel darker than [`FidelityOptions::dark_floor`]
//!   judged against the floor (a 10 % error of an albedo of 0.003 is invisible); for an
//!   anisotropic source, optionally the mean over several azimuths of the light
//!   ([`FidelityOptions::albedo_azimuths`]).
//!
//! The three relative RMSEs are those of pairs uniform in solid angle, estimated from pairs half
//! of which are drawn near the mirror direction and weighted back to uniform
//! ([`compare_region`](crate::analysis::accuracy::compare_region)): with uniform pairs alone a
//! near-mirror peak made the figure a lottery (`cg_sunflower`'s grazing band 1.5–5.0 % over
//! five seeds of 100 000 pairs; now 1.75–1.94 %).
//!
//! The albedo quadrature is a fixed product rule in polar coordinates about the mirror direction
//! (geometric α segments down to 0.25°, Gauss-Legendre in each, the horizon as the last
//! segment's end): a near-mirror peak 0.4° wide falls between the nodes of any affordable rule
//! uniform over the hemisphere — a 128 × 256 rule stratified in sin²θo put the same material's
//! albedo at 87° anywhere from 0.019 to 0.028.

use rayon::prelude::*;
use serde::Serialize;

use crate::analysis::accuracy::{Region, Weight, compare_region_with};
use crate::analysis::pair_rule::{PairRule, PairRuleOptions, RuleError, mirror_rule};
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::progress::{Progress, Silent};
use crate::quadrature::gauss_legendre;
use crate::spectrum::MAX_CHANNELS;

/// How [`measure`] samples.
#[derive(Debug, Clone, PartialEq)]
pub struct FidelityOptions {
    /// Random pairs of each relative RMSE.
    pub pairs: usize,
    /// Seed of the pairs and of the albedo quadrature's jitter.
    pub seed: u64,
    /// Incidence angles of the albedo comparison (degrees).
    pub albedo_thetas_deg: Vec<f64>,
    /// Azimuths about the mirror direction of the albedo quadrature.
    pub albedo_phi: usize,
    /// Gauss-Legendre nodes per α segment of the albedo quadrature.
    pub albedo_order: usize,
    /// Azimuths of the light, equally spaced from φ′ = 0, over which each directional albedo
    /// is averaged. 1 (the default) looks at φ′ = 0 alone, which an isotropic source's albedo
    /// does not depend on; an anisotropic source's varies with φ′, and so does its table's
    /// bias, so its figure is the mean over several (8 is what an albedo calibration pins,
    /// `table::calibration::ANISOTROPIC_AZIMUTHS`: equally spaced, exact for the cos 2φ′ of an
    /// elliptical lobe).
    pub albedo_azimuths: usize,
    /// An albedo darker than this is judged against it.
    pub dark_floor: f64,
    /// The cap of the in-cap error and the start of the grazing band (degrees).
    pub cap_deg: f64,
}

impl Default for FidelityOptions {
    fn default() -> Self {
        FidelityOptions {
            pairs: 200_000,
            seed: 1,
            albedo_thetas_deg: (1..=89).map(f64::from).collect(),
            albedo_phi: 128,
            albedo_order: 8,
            albedo_azimuths: 1,
            dark_floor: 0.02,
            cap_deg: 80.0,
        }
    }
}

/// The worst albedo difference of [`measure`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AlbedoError {
    /// |a_table − a_source| / max(a_source, floor), the worst over angles and channels.
    pub worst: f64,
    /// The incidence angle of the worst error (degrees).
    pub theta_deg: f64,
    /// Its channel.
    pub channel: usize,
    /// The table's albedo there.
    pub approx: f64,
    /// The source's albedo there.
    pub reference: f64,
}

/// The figures of [`measure`] (relative RMSEs of f_r cos θi cos θo).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Fidelity {
    /// Both directions within the cap.
    pub cap: f64,
    /// The whole hemisphere of both directions.
    pub whole: f64,
    /// At least one direction beyond the cap.
    pub grazing: f64,
    /// The worst directional albedo error.
    pub albedo: AlbedoError,
    /// The three relative RMSEs on the deterministic product rule of [`PairRule`] (no heavy
    /// tail on near-mirror materials).
    pub rule: RuleError,
}

impl Fidelity {
    /// One line: `within 80° 0.41 %, whole hemisphere 0.62 %, grazing band 1.3 % (rule 0.40 /
    /// 0.60 / 1.5 %), albedo 0.55 % (worst at 34°, channel 2)`.
    pub fn summary(&self) -> String {
        let [
            cap,
            whole,
            grazing,
            rule_cap,
            rule_whole,
            rule_grazing,
            albedo,
        ] = self.percents();
        format!(
            "within 80° {cap:.2} %, whole hemisphere {whole:.2} %, grazing band {grazing:.2} % (rule {rule_cap:.2} / {rule_whole:.2} / {rule_grazing:.2} %), albedo {albedo:.2} % (worst at {}°, channel {})",
            self.albedo.theta_deg, self.albedo.channel
        )
    }

    /// The errors in percent, in the order every report prints them: within the cap, whole
    /// hemisphere, grazing band (random pairs), the same three on the rule, worst albedo.
    pub fn percents(&self) -> [f64; 7] {
        [
            self.cap,
            self.whole,
            self.grazing,
            self.rule.cap,
            self.rule.whole,
            self.rule.grazing,
            self.albedo.worst,
        ]
        .map(|x| x * 100.0)
    }
}

/// Measures `approx` (a table) against `reference` (its source) over the whole domain.
pub fn measure(
    approx: &dyn Brdf,
    reference: &dyn Brdf,
    opts: &FidelityOptions,
) -> Result<Fidelity> {
    measure_with(approx, reference, opts, &Silent)
}

/// [`measure`], asking `progress` to stop between blocks of pairs and albedo angles
/// ([`Progress::cancelled`]: [`Error::Cancelled`]).
pub fn measure_with(
    approx: &dyn Brdf,
    reference: &dyn Brdf,
    opts: &FidelityOptions,
    progress: &dyn Progress,
) -> Result<Fidelity> {
    FidelityReference::new_with(reference, opts, progress)?.measure_with(approx, progress)
}

/// What [`measure`] needs of the source, computed once for several tables of it (the accuracy
/// suite measures every preset and codec against one source): its values on the product rule
/// and its albedo curve.
pub struct FidelityReference<'a> {
    reference: &'a dyn Brdf,
    opts: FidelityOptions,
    rule: PairRule,
    albedo: AlbedoCurve,
}

impl<'a> FidelityReference<'a> {
    /// The source's side of the figures of `opts`.
    pub fn new(reference: &'a dyn Brdf, opts: &FidelityOptions) -> Result<FidelityReference<'a>> {
        Self::new_with(reference, opts, &Silent)
    }

    /// [`new`](Self::new), asking `progress` to stop between blocks of the work.
    pub fn new_with(
        reference: &'a dyn Brdf,
        opts: &FidelityOptions,
        progress: &dyn Progress,
    ) -> Result<FidelityReference<'a>> {
        let cap = opts.cap_deg.to_radians();
        Ok(FidelityReference {
            reference,
            rule: PairRule::new_with(reference, cap, &PairRuleOptions::default(), progress)?,
            albedo: albedo_curve_with(reference, opts, progress)?,
            opts: opts.clone(),
        })
    }

    /// The figures of `approx` against the source.
    pub fn measure(&self, approx: &dyn Brdf) -> Result<Fidelity> {
        self.measure_with(approx, &Silent)
    }

    /// [`measure`](Self::measure), asking `progress` to stop between blocks of the work.
    pub fn measure_with(&self, approx: &dyn Brdf, progress: &dyn Progress) -> Result<Fidelity> {
        let opts = &self.opts;
        let cap = opts.cap_deg.to_radians();
        let w = Weight::CosInCosOut;
        let (n, seed) = (opts.pairs, opts.seed);
        let rmse = |r: Region| -> Result<f64> {
            Ok(compare_region_with(approx, self.reference, n, seed, r, w, progress)?.rel_rmse)
        };
        let in_cap = rmse(Region::Cap(cap))?;
        let whole = rmse(Region::Cap(std::f64::consts::FRAC_PI_2))?;
        let grazing = rmse(Region::Band(cap))?;
        let curve = albedo_curve_with(approx, opts, progress)?;
        let albedo = worst_albedo(&curve, &self.albedo, opts);
        Ok(Fidelity {
            cap: in_cap,
            whole,
            grazing,
            albedo,
            rule: self.rule.error_with(approx, progress)?,
        })
    }
}

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
/// `theta` (radians, azimuth 0), on the mirror-centred product rule of [`measure`] with `nphi`
/// azimuths and `order` Gauss-Legendre nodes per segment. Two BRDFs integrated with the same
/// arguments share every node, so their ratio carries little of the rule's own error.
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

#[cfg(test)]
mod tests {
    #[test]
    fn albedo_angles_outside_the_upper_hemisphere_are_refused() {
        let l = crate::models::lambert::Lambert::new(
            crate::spectrum::Value::Grey(0.3),
            &crate::spectrum::Channels::Rgb,
        )
        .unwrap();
        for bad in [90.0, 95.0, -1.0, f64::NAN] {
            let opts = FidelityOptions {
                albedo_thetas_deg: vec![10.0, bad],
                ..Default::default()
            };
            match albedo_error(&l, &l, &opts) {
                Err(Error::InvalidArgument { name, .. }) => assert_eq!(name, "albedo_thetas_deg"),
                r => panic!("{bad}: {r:?}"),
            }
        }
    }

    use super::*;
    use crate::models::lambert::Lambert;
    use crate::spec::ModelSpec;
    use crate::spectrum::{Channels, Value};

    #[test]
    fn the_quadrature_integrates_lambert_and_a_sharp_lobe() {
        // f = kd: ∫ kd cos θo dω = π kd at every θ′.
        let l = Lambert::new(Value::Rgb([0.1, 0.2, 0.3]), &Channels::Rgb).unwrap();
        let (a, b) = albedo_pair(&l, &l, &FidelityOptions::default()).unwrap();
        for (x, y) in a.iter().zip(&b) {
            for (ch, kd) in [0.1f32, 0.2, 0.3].iter().enumerate() {
                let want = std::f64::consts::PI * *kd as f64;
                // The product rule is exact for the cosine except on the segments the horizon
                // cuts, whose boundary is not polynomial (worst at θ′ = 89°): 1e-4 is 100×
                // below the 1 % the albedo is judged to, and the table and its source are
                // integrated by the same rule.
                assert!((x[ch] - want).abs() < 1e-4 * want, "{} {want}", x[ch]);
                assert_eq!(x[ch], y[ch]);
            }
        }
        // Reciprocal Phong n = 1000 (about 2° wide): 2π ks/(n + 2) at normal incidence.
        let p = ModelSpec::parse(r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 1000}"#)
            .unwrap()
            .build(&Channels::Rgb)
            .unwrap();
        let opts = FidelityOptions {
            albedo_thetas_deg: vec![0.0],
            ..Default::default()
        };
        let (a, _) = albedo_pair(p.as_ref(), p.as_ref(), &opts).unwrap();
        let want = std::f64::consts::TAU * 0.5 / 1002.0;
        assert!((a[0][0] - want).abs() < 1e-4 * want, "{} {want}", a[0][0]);
    }

    /// A diffuse lobe whose brightness follows the light's azimuth: (1 + ½ cos 2φ′)/π.
    struct Azimuthal(Channels);

    impl Brdf for Azimuthal {
        fn channels(&self) -> &Channels {
            &self.0
        }
        fn eval(&self, wi: glam::DVec3, wo: glam::DVec3, out: &mut [f32]) {
            let c2 = (wi.x * wi.x - wi.y * wi.y) / (wi.x * wi.x + wi.y * wi.y).max(1e-300);
            let f = if wi.z > 0.0 && wo.z > 0.0 {
                (1.0 + 0.5 * c2) / std::f64::consts::PI
            } else {
                0.0
            };
            out.iter_mut().for_each(|o| *o = f as f32);
        }
        fn flags(&self) -> crate::brdf::Flags {
            crate::brdf::Flags {
                isotropic: false,
                reciprocal: false,
                ..Lambert::new(Value::Rgb([0.5; 3]), &self.0).unwrap().flags()
            }
        }
        fn describe(&self) -> String {
            "azimuthal".into()
        }
    }

    #[test]
    fn an_anisotropic_albedo_is_averaged_over_the_lights_azimuths() {
        // Its albedo is 1 + ½ cos 2φ′ at every θ′: 1.5 at φ′ = 0, and the mean over four or
        // more equally spaced azimuths is 1 (they sum cos 2φ′ to 0).
        let b = Azimuthal(Channels::Rgb);
        let l = Lambert::new(Value::Rgb([std::f64::consts::FRAC_1_PI; 3]), &Channels::Rgb).unwrap();
        for (n, want) in [(1, 1.5), (4, 1.0), (8, 1.0)] {
            let opts = FidelityOptions {
                albedo_thetas_deg: vec![10.0, 60.0, 89.0],
                albedo_azimuths: n,
                ..Default::default()
            };
            let curve = albedo_curve(&b, &opts).unwrap();
            let (a, _) = albedo_pair(&b, &l, &opts).unwrap();
            // The rule's own error on a cosine lobe (the Lambert test above): 1e-4.
            for (x, y) in curve.iter().zip(&a) {
                assert!((x[0] - want).abs() < 1e-4 * want, "{n}: {x:?}");
                assert_eq!(x, y);
            }
            // Against a Lambert lobe of albedo 1: the mean's error is the lobe's own.
            let e = albedo_error(&b, &l, &opts).unwrap();
            assert!((e.worst - (want - 1.0)).abs() < 2e-4, "{n}: {e:?}");
        }
        let none = FidelityOptions {
            albedo_azimuths: 0,
            ..Default::default()
        };
        assert!(albedo_curve(&b, &none).is_err());
    }

    #[test]
    fn a_darker_table_shows_its_error_everywhere_and_dark_channels_are_floored() {
        let src = Lambert::new(Value::Rgb([0.5, 0.5, 0.005]), &Channels::Rgb).unwrap();
        let dim = Lambert::new(Value::Rgb([0.49, 0.5, 0.0025]), &Channels::Rgb).unwrap();
        // The default φ rule (128 nodes): it integrates Lambert within 1e-4 (above).
        let opts = FidelityOptions {
            pairs: 4096,
            ..Default::default()
        };
        let f = measure(&dim, &src, &opts).unwrap();
        // Red: 2 % low; blue: 0.0025π·… against the floor 0.02: |0.0025π − 0.005π| / 0.02.
        let blue = 0.0025 * std::f64::consts::PI / 0.02;
        // Both albedos within 1e-4 of their value (the rule's error, above).
        assert!((f.albedo.worst - blue).abs() < 2e-4 * blue, "{f:?}");
        assert_eq!(f.albedo.channel, 2);
        for e in [f.cap, f.whole, f.grazing] {
            // Relative RMSE of a per-channel scale error, weighted by the channels' energy.
            assert!(e > 0.01 && e < 0.02, "{f:?}");
        }
    }
}
