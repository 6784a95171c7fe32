//! `fit`: least-squares fit of a model's parameters to any SOURCE (see `brdftab::fit`).

use brdftab::fit::{self, ColorMode, FitOptions, ParamRequest};
use brdftab::fresnel::FresnelSpec;
use brdftab::{Error, Result, Value};
use clap::Args;

use crate::source;

/// Arguments of `brdftab fit`.
#[derive(Args)]
pub struct FitArgs {
    /// The data to fit: a spec, table, MERL `.binary` or RGL `.bsdf` file.
    source: String,
    /// The model: a name (`ggx`, `reciprocal_phong`, ...), a sum of names
    /// (`lambert+cook_torrance`, `lambert+ggx`, `lambert+blinn_phong`, `lambert+ward`), or a JSON
    /// spec used as the first start.
    #[arg(long)]
    model: String,
    /// Parameters to fit, comma separated paths into the spec with optional bounds:
    /// `terms[1].m,terms[0].kd=0:0.3,n=2:500:log`. Default: every numeric parameter.
    #[arg(long)]
    params: Option<String>,
    /// Residuals in log space, ln(1 + f cos θi) (compresses specular peaks).
    #[arg(long)]
    log: bool,
    /// Number of starts (the first is the model's own values, the rest spread over the bounds).
    #[arg(long, default_value_t = 8)]
    starts: usize,
    /// Number of direction pairs.
    #[arg(long, default_value_t = 4000)]
    pairs: usize,
    /// Largest polar angle of the fitting pairs' directions, in degrees (grazing data excluded).
    #[arg(long, default_value_t = 80.0)]
    max_theta_deg: f64,
    /// Seed of the pairs and starts.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Give every microfacet lobe (cook_torrance, ggx) a Fresnel term whose parameter is fit too:
    /// `schlick` (F0, start 0.04), `dielectric` (eta, start 1.5) or `none` (default: ks absorbs it).
    #[arg(long, value_parser = ["none", "schlick", "dielectric"])]
    fresnel: Option<String>,
    /// Fit kd/ks as one grey value instead of one per channel.
    #[arg(long)]
    grey: bool,
    /// Wavelengths in nm (comma separated) for a spec SOURCE instead of RGB.
    #[arg(long)]
    wavelengths: Option<String>,
    /// Print the whole result as JSON: {"spec": .., "rmse": .., "iterations": .., "starts": [..]}.
    #[arg(long)]
    json: bool,
}

/// Runs the fit and prints the fitted spec (or the whole result with `--json`).
pub fn fit(a: FitArgs) -> Result<()> {
    let channels = source::channels(a.wavelengths.as_deref())?;
    let brdf = source::open(&a.source, &channels)?;
    let mut init = fit::preset(&a.model)?;
    let fresnel = match a.fresnel.as_deref() {
        Some("schlick") => Some(FresnelSpec::Schlick(Value::Grey(0.04))),
        Some("dielectric") => Some(FresnelSpec::Dielectric(Value::Grey(1.5))),
        Some("none") => Some(FresnelSpec::None),
        _ => None,
    };
    if let Some(f) = fresnel {
        init = fit::with_fresnel(&init, &f)?;
    }
    let params = match &a.params {
        None => Vec::new(),
        Some(s) => s
            .split(',')
            .filter(|x| !x.trim().is_empty())
            .map(ParamRequest::parse)
            .collect::<Result<Vec<_>>>()?,
    };
    let opts = FitOptions {
        params,
        pairs: a.pairs,
        log: a.log,
        starts: a.starts,
        seed: a.seed,
        max_theta: a.max_theta_deg.to_radians(),
        color: if a.grey {
            ColorMode::Grey
        } else {
            ColorMode::PerChannel
        },
        ..Default::default()
    };
    let bar = crate::progress::Bar::new("fit {bar:30} {pos}/{len} starts {elapsed}");
    let result = fit::fit_with_progress(brdf.as_ref(), &init, &opts, &bar)?;
    let text = if a.json {
        serde_json::to_string(&result).map_err(|e| Error::Json {
            context: "fit result".into(),
            source: e,
        })?
    } else {
        result.spec.to_json()
    };
    println!("{text}");
    Ok(())
}
