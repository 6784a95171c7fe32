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

mod albedo;

pub use albedo::{
    AlbedoCurve, Reversed, albedo_curve, albedo_curve_with, albedo_error, albedo_pair,
    mirror_albedo, worst_albedo,
};
pub(crate) use albedo::{Turned, light_azimuths};

use serde::Serialize;

use crate::analysis::accuracy::{Region, Weight, compare_region_with};
use crate::analysis::pair_rule::{PairRule, PairRuleOptions, RuleError};
use crate::brdf::Brdf;
use crate::error::Result;
use crate::progress::{Progress, Silent};

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
/// ([`Progress::cancelled`]: [`Error::Cancelled`](crate::error::Error::Cancelled)).
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

#[cfg(test)]
mod tests;
