//! Least-squares fitting of model parameters to any source.
//!
//! The lecture's recipe ("Fitting to measurement data"): measurements F_k = f_r(ω′_k, ω_k) cos θ′_k
//! at direction pairs, a model w(ω′, ω, p_1..p_m) = f̂_r cos θ′, and the least-squares estimate
//! that minimizes E(p) = Σ_k (w(ω′_k, ω_k, p) − F_k)². Here the "measurements" come from any
//! `&dyn Brdf` — an analytic model, a baked table, MERL or RGL data — and the model is any
//! [`ModelSpec`], so a fitted result is again a spec usable as a SOURCE.
//!
//! - **Parameters** are paths into the spec (`kd`, `terms[1].m`; see [`params`]), by default every
//!   numeric parameter outside Fresnel terms and sum weights. `kd`/`ks` are fit per channel of the
//!   source ([`ColorMode::PerChannel`], an RGB triple or a spectrum on the source's wavelengths)
//!   or as one grey value ([`ColorMode::Grey`]); shape parameters (m, n, α, σ) are shared by all
//!   channels. Bounds are enforced by a logistic reparameterization (in log space for exponents
//!   and roughness), so Levenberg-Marquardt runs unconstrained.
//! - **Pairs** are deterministic: cosine-distributed plus a fraction near the mirror direction,
//!   both directions within 80° of the normal by default (see [`pairs`]).
//! - **Residuals** are r_kc = f̂_c cos θi − f_c cos θi per pair k and channel c, or with
//!   [`FitOptions::log`] r_kc = ln(1 + f̂_c cos θi) − ln(1 + f_c cos θi) (Ngan et al. 2005 style:
//!   compresses specular peaks so the diffuse part and lobe shape count).
//! - **Multi-start**: start 0 is the given spec's values; starts 1.. are a Latin hypercube over the
//!   bounds (positions 5%–95%, the channels of one field sharing a start). The start with the
//!   smallest objective wins.
//! - **Jacobian** by central differences (step 10⁻³ in the free variable): models return f32, so
//!   forward differences with tiny steps would see only rounding. The channels of a per-channel
//!   value are differenced together (each affects only its own channel), so an RGB `kd` costs
//!   one pair of model evaluations per iteration, not three.
//! - **Error**: `rmse` is the cosine-weighted relative RMSE of
//!   [`analysis::accuracy`](crate::analysis::accuracy), sqrt(Σ ((f̂ − f) cos θi)² / Σ (f cos θi)²)
//!   over every channel, on a *held-out* set of pairs drawn like the fitting pairs (another seed),
//!   so within `max_theta`; `rmse_fit` is the same on the fitting pairs. `rmse_uniform` /
//!   `max_rel_uniform` are `analysis::accuracy::compare` itself ([`ACCURACY_PAIRS`] pairs uniform
//!   on the whole hemisphere, grazing included) — the crate's yardstick for tables, but for
//!   measured data a handful of extreme-grazing values can dominate it.
//!
//! ```
//! use brdftab::{fit::{self, FitOptions}, spec::ModelSpec, spectrum::Channels};
//! let source = ModelSpec::parse(r#"{"model": "lambert", "kd": [0.1, 0.2, 0.05]}"#)?
//!     .build(&Channels::Rgb)?;
//! let start = fit::preset("lambert")?;
//! let r = fit::fit(source.as_ref(), &start, &FitOptions { pairs: 200, starts: 2, ..Default::default() })?;
//! assert!(r.rmse < 1e-4);
//! # Ok::<(), brdftab::Error>(())
//! ```

pub mod pairs;
pub mod params;
mod problem;
mod report;
mod rmse;
mod start;
#[cfg(test)]
mod tests;

use std::cell::Cell;
use std::time::Instant;

use levenberg_marquardt::LevenbergMarquardt;
use nalgebra::DVector;

use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::spec::ModelSpec;

pub use pairs::Pairs;
pub use params::{Bounds, ColorMode, Param, ParamRequest, Scale};
use problem::{Problem, eval_cos, from_free, to_free, transform};
pub use report::{FitResult, FittedParam, StartResult};
pub use rmse::relative_rmse;
use start::StartPoints;
pub use start::{preset, with_fresnel};

/// Number of uniform pairs on which the final `rmse` is measured.
pub const ACCURACY_PAIRS: usize = 20_000;

/// The most residuals (pairs × channels) a fit takes: 2^22, a Jacobian of a few hundred MB
/// for the models' parameter counts. The default 4000 pairs fit with every channel count
/// the library allows (64); more is an [`Error::InvalidArgument`] naming `pairs`, never an
/// allocation that aborts the process or overflows.
pub const MAX_RESIDUALS: usize = 1 << 22;

/// Options of a fit. `Default` gives 4000 pairs (30% specular), linear residuals, 8 starts,
/// every parameter with default bounds, per-channel colours.
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Parameters to fit; empty = every numeric parameter with default bounds.
    pub params: Vec<ParamRequest>,
    /// Number of direction pairs.
    pub pairs: usize,
    /// Fraction of pairs drawn near the mirror direction.
    pub specular_fraction: f64,
    /// Largest polar angle of either direction of a pair, radians (default 80°).
    pub max_theta: f64,
    /// Residuals in log space: ln(1 + f cos θi).
    pub log: bool,
    /// Number of starts (≥ 1).
    pub starts: usize,
    /// Seed of the pairs and the starts.
    pub seed: u64,
    /// Per-channel or grey `kd`/`ks`.
    pub color: ColorMode,
    /// At most this many LM iterations (Jacobians) per start.
    pub max_iterations: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            params: Vec::new(),
            pairs: 4000,
            specular_fraction: 0.3,
            max_theta: pairs::MAX_THETA,
            log: false,
            starts: 8,
            seed: 1,
            color: ColorMode::PerChannel,
            max_iterations: 100,
        }
    }
}

/// Fits the parameters of `init` to `source`; see the module docs.
pub fn fit(source: &dyn Brdf, init: &ModelSpec, opts: &FitOptions) -> Result<FitResult> {
    fit_with_progress(source, init, opts, &crate::progress::Silent)
}

/// [`fit`], reporting one stage, `"fitting"`, that counts the starts done.
pub fn fit_with_progress(
    source: &dyn Brdf,
    init: &ModelSpec,
    opts: &FitOptions,
    progress: &dyn crate::progress::Progress,
) -> Result<FitResult> {
    let clock = Instant::now();
    check(source, opts)?;
    let channels = source.channels().clone();
    let mut base = serde_json::to_value(init).map_err(|e| Error::Json {
        context: "spec".into(),
        source: e,
    })?;
    let params = params::resolve(&mut base, &opts.params, &channels, opts.color)?;
    // The starting spec must build for the source's channels (catches unimplemented models early).
    init.build(&channels)?;

    let pairs = Pairs::sample(
        opts.pairs,
        opts.specular_fraction,
        opts.max_theta,
        opts.seed,
    );
    let target_lin = eval_cos(source, &pairs);
    // A source that failed while it was read (a corrupt table chunk) gave zeros: fitting
    // them would return a black material.
    source.health()?;
    let cancel = || progress.cancelled();
    let problem = Problem {
        base: base.clone(),
        params: &params,
        channels: &channels,
        pairs: &pairs,
        target: target_lin.iter().map(|&y| transform(y, opts.log)).collect(),
        log: opts.log,
        scale: 1.0 / (target_lin.len() as f64).sqrt(),
        t: DVector::zeros(0),
        iterations: Cell::new(0),
        evaluations: Cell::new(0),
        cancel: &cancel,
    };

    // Start positions.
    let n_free: usize = params.iter().map(|p| p.width).sum();
    let mut first = Vec::with_capacity(n_free);
    for p in &params {
        first.extend(params::read(&mut base, p, &channels)?);
    }
    let start_points = StartPoints::new(&params, first, opts.starts, opts.seed);

    let lm = LevenbergMarquardt::new()
        .with_ftol(1e-10)
        .with_xtol(1e-9)
        .with_gtol(1e-10)
        .with_patience(opts.max_iterations.max(1));
    let mut starts = Vec::with_capacity(opts.starts);
    let mut best: Option<(usize, DVector<f64>)> = None;
    let mut problem = problem;
    let mut evaluations = 0;
    let _stage = crate::progress::Stage::begin(progress, "fitting", opts.starts as u64);
    for s in 0..opts.starts {
        let x0 = start_points.values(&params, s);
        let t0 = DVector::from_vec(to_free(&params, &x0));
        problem.t = t0;
        problem.iterations.set(0);
        problem.evaluations.set(0);
        let (p, report) = lm.minimize(problem);
        problem = p;
        crate::progress::check(progress)?;
        // The objective as LM reports it may belong to a rejected step; recompute at the end point.
        let (objective, rmse) = rmse::score(&problem, &problem.t, &target_lin);
        evaluations += problem.evaluations.get();
        starts.push(StartResult {
            initial: x0,
            fitted: from_free(&params, problem.t.as_slice()),
            objective,
            rmse,
            iterations: problem.iterations.get(),
            evaluations: problem.evaluations.get(),
            termination: format!("{:?}", report.termination),
        });
        if objective.is_finite()
            && best
                .as_ref()
                .is_none_or(|(b, _)| objective < starts[*b].objective)
        {
            best = Some((s, problem.t.clone()));
        }
        progress.set(s as u64 + 1);
    }
    let Some((best_start, t_best)) = best else {
        return Err(Error::Unsupported(
            "every start of the fit failed: the optimizer left the model's valid parameters \
             at every start (try other starts, bounds or a simpler model)"
                .into(),
        ));
    };
    let spec = problem.spec_at(&t_best)?;
    let model = spec.build(&channels)?;
    let held_out = Pairs::sample(
        opts.pairs,
        opts.specular_fraction,
        opts.max_theta,
        opts.seed ^ 0x9e37_79b9_7f4a_7c15,
    );
    let rmse = relative_rmse(source, model.as_ref(), &held_out)?;
    let acc =
        crate::analysis::accuracy::compare(model.as_ref(), source, ACCURACY_PAIRS, opts.seed)?;
    let fitted = FittedParam::all(&params, t_best.as_slice());
    let b = &starts[best_start];
    Ok(FitResult {
        spec,
        rmse,
        rmse_uniform: acc.rel_rmse,
        max_rel_uniform: acc.max_rel,
        rmse_fit: b.rmse,
        objective: b.objective,
        iterations: b.iterations,
        evaluations,
        best_start,
        params: fitted,
        pairs: pairs.len(),
        log: opts.log,
        seconds: clock.elapsed().as_secs_f64(),
        starts,
    })
}

/// The options and source a fit refuses, before any work.
fn check(source: &dyn Brdf, opts: &FitOptions) -> Result<()> {
    if opts.pairs == 0 {
        return Err(Error::arg("pairs", "at least one pair is needed"));
    }
    let c = source.channels().len();
    if opts.pairs.checked_mul(c).is_none_or(|n| n > MAX_RESIDUALS) {
        return Err(Error::arg(
            "pairs",
            format!(
                "{} pairs × {c} channels: at most {MAX_RESIDUALS} residuals ({} pairs of {c} \
                 channels)",
                opts.pairs,
                MAX_RESIDUALS / c.max(1)
            ),
        ));
    }
    if opts.starts == 0 {
        return Err(Error::arg("starts", "at least one start is needed"));
    }
    if !(0.0..=1.0).contains(&opts.specular_fraction) {
        return Err(Error::arg("specular_fraction", "must be in [0, 1]"));
    }
    if source.flags().delta {
        return Err(Error::Unsupported(
            "fitting a delta (mirror/refractor) source: eval is 0 everywhere".into(),
        ));
    }
    // A sum's delta term is invisible to eval: a fit would match the other terms only.
    if source.flags().lobes.delta {
        return Err(Error::Unsupported(
            "fitting a source with a delta term (mirror/refractor): eval does not see the delta, \
             so the fit would match the other terms only; fit those"
                .into(),
        ));
    }
    Ok(())
}
