//! [`FitSettings`] and [`fit()`]: a model fit to any SOURCE, as every host asks for it.

use serde::{Deserialize, Serialize};

use super::values::{Names, Wavelengths};
use crate::error::{Error, Result};
use crate::fit::{self, ColorMode, FitOptions, FitResult, ParamRequest};
use crate::fresnel::FresnelSpec;
use crate::progress::Progress;
use crate::source::OpenOptions;
use crate::spectrum::Value;

/// The settings of a fit (`brdftab fit`, Python's `fit` keywords, the C ABI's JSON); `None`
/// keeps [`FitOptions::default`]'s value.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct FitSettings {
    /// Parameters to fit, paths into the spec with optional bounds:
    /// `terms[1].m,terms[0].kd=0:0.3,n=2:500:log` (or a list). Default: every numeric parameter,
    /// within physical bounds (kd ≤ 1.2/π, ks ≤ 1.5 — the Phong family's 1e-3–10⁴ —, m and α
    /// 0.01–1.5, n 1–10⁴, σ ≤ 1.5).
    #[cfg_attr(feature = "clap", arg(long))]
    pub params: Option<Names>,
    /// Residuals in log space, ln(1 + f cos θi) (compresses specular peaks).
    #[cfg_attr(feature = "clap", arg(long))]
    pub log: bool,
    /// Number of starts (default 8; the first is the model's own values, the rest spread over
    /// the bounds).
    #[cfg_attr(feature = "clap", arg(long))]
    pub starts: Option<usize>,
    /// Number of direction pairs (default 4000).
    #[cfg_attr(feature = "clap", arg(long))]
    pub pairs: Option<usize>,
    /// Largest polar angle of the pairs' directions, in degrees (default 80: grazing data
    /// excluded).
    #[cfg_attr(feature = "clap", arg(long))]
    pub max_theta_deg: Option<f64>,
    /// Seed of the pairs and starts (default 1).
    #[cfg_attr(feature = "clap", arg(long))]
    pub seed: Option<u64>,
    /// Give every microfacet lobe (cook_torrance, ggx) a Fresnel term whose parameter is fit
    /// too: `schlick` (F0, start 0.04), `dielectric` (eta, start 1.5) or `none` (default: ks
    /// absorbs it).
    #[cfg_attr(feature = "clap", arg(long))]
    pub fresnel: Option<String>,
    /// Fit kd/ks as one grey value instead of one per channel.
    #[cfg_attr(feature = "clap", arg(long))]
    pub grey: bool,
    /// Wavelengths in nm for a spec SOURCE instead of RGB.
    #[cfg_attr(feature = "clap", arg(long))]
    pub wavelengths: Option<Wavelengths>,
    /// Fraction of pairs drawn near the mirror direction (default 0.3).
    #[cfg_attr(feature = "clap", arg(long))]
    pub specular_fraction: Option<f64>,
    /// At most this many Levenberg-Marquardt iterations per start (default 100).
    #[cfg_attr(feature = "clap", arg(long))]
    pub max_iterations: Option<usize>,
}

impl FitSettings {
    /// The fit's options; every check of a fit's settings is here.
    ///
    /// # Errors
    /// [`Error::InvalidArgument`] naming the field.
    pub fn options(&self) -> Result<FitOptions> {
        let d = FitOptions::default();
        let params = match &self.params {
            None => Vec::new(),
            Some(n) => {
                n.0.iter()
                    .map(|p| p.parse::<ParamRequest>())
                    .collect::<Result<_>>()?
            }
        };
        let at_least_one = |v: Option<usize>, name: &str, default: usize| match v {
            Some(0) => Err(Error::arg(name, "must be at least 1")),
            v => Ok(v.unwrap_or(default)),
        };
        let max_theta = match self.max_theta_deg {
            Some(t) if !(t > 0.0 && t <= 90.0) => {
                return Err(Error::arg(
                    "max_theta_deg",
                    format!("{t}: expected 0 < θ ≤ 90"),
                ));
            }
            Some(t) => t.to_radians(),
            None => d.max_theta,
        };
        let specular_fraction = match self.specular_fraction {
            Some(f) if !(0.0..=1.0).contains(&f) => {
                return Err(Error::arg(
                    "specular_fraction",
                    format!("{f}: expected 0..=1"),
                ));
            }
            f => f.unwrap_or(d.specular_fraction),
        };
        Ok(FitOptions {
            params,
            pairs: at_least_one(self.pairs, "pairs", d.pairs)?,
            specular_fraction,
            max_theta,
            log: self.log,
            starts: at_least_one(self.starts, "starts", d.starts)?,
            seed: self.seed.unwrap_or(d.seed),
            color: if self.grey {
                ColorMode::Grey
            } else {
                ColorMode::PerChannel
            },
            max_iterations: at_least_one(self.max_iterations, "max_iterations", d.max_iterations)?,
        })
    }

    /// The Fresnel term the fit gives microfacet lobes, with its start (`None`: the model's).
    pub fn fresnel(&self) -> Result<Option<FresnelSpec>> {
        Ok(match self.fresnel.as_deref().map(str::trim) {
            None => None,
            Some("schlick") => Some(FresnelSpec::Schlick(Value::Grey(0.04))),
            Some("dielectric") => Some(FresnelSpec::Dielectric(Value::Grey(1.5))),
            Some("none") => Some(FresnelSpec::None),
            Some(o) => {
                return Err(Error::arg(
                    "fresnel",
                    format!("`{o}`: expected none, schlick or dielectric"),
                ));
            }
        })
    }
}

/// Fits `model` (a name such as `ggx`, a sum `lambert+ggx`, or a JSON spec: [`fit::preset`]) to
/// SOURCE as `settings` say.
///
/// # Errors
/// Invalid settings or model, and whatever opening the source fails with.
pub fn fit(
    source: impl AsRef<std::ffi::OsStr>,
    model: &str,
    settings: &FitSettings,
    progress: &dyn Progress,
) -> Result<FitResult> {
    let opts = settings.options()?;
    let mut init = fit::preset(model)?;
    if let Some(f) = settings.fresnel()? {
        init = fit::with_fresnel(&init, &f)?;
    }
    let open = OpenOptions {
        channels: settings
            .wavelengths
            .as_ref()
            .map(|w| w.channels())
            .transpose()?,
        ..OpenOptions::default()
    };
    let brdf = crate::source::open_with(source, &open)?;
    fit::fit_with_progress(brdf.as_ref(), &init, &opts, progress)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_fits_defaults_and_bad_values_name_their_field() {
        assert_eq!(
            FitSettings::default().options().unwrap(),
            FitOptions::default()
        );
        for (json, field) in [
            (r#"{"starts": 0}"#, "starts"),
            (r#"{"pairs": 0}"#, "pairs"),
            (r#"{"max_theta_deg": 95}"#, "max_theta_deg"),
            (r#"{"specular_fraction": 2}"#, "specular_fraction"),
            (r#"{"params": "n=100:2"}"#, "n"),
            (r#"{"fresnel": "metal"}"#, "fresnel"),
        ] {
            let s: FitSettings = super::super::from_json(json).unwrap();
            let e = s.options().and_then(|_| s.fresnel()).unwrap_err();
            assert!(
                matches!(e, Error::InvalidArgument { ref name, .. } if name.contains(field)),
                "{json}: {e}"
            );
        }
    }
}
