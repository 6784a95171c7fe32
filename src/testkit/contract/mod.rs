//! [`check_contract`]: the `Brdf` contract, checked on one value (module docs of
//! [`crate::testkit`]).

use glam::DVec3;

use crate::brdf::Brdf;
use crate::geometry;
use crate::rng::Pcg32;
use crate::spectrum::MAX_CHANNELS;

mod batches;
mod inputs;
mod sampling;
mod symmetry;
#[cfg(test)]
mod tests;

use batches::batches;
use inputs::{bad_input, lengths};
use sampling::sampling;
use symmetry::values_and_symmetry;

/// How hard [`check_contract`] looks.
#[derive(Debug, Clone, PartialEq)]
pub struct Contract {
    /// Random direction pairs for positivity, symmetry and batches.
    pub pairs: usize,
    /// Samples drawn at each view direction of the sampling checks (0 skips them).
    pub samples: usize,
    /// Relative tolerance of the declared symmetries: f32 rounding of the two values plus the
    /// rounding of two different computations of the same coordinates (default 1e-5).
    pub symmetry_tolerance: f64,
    /// Absolute tolerance of the declared symmetries, as a fraction of the channel's largest
    /// value over the pairs (default 1e-6). A table's linear lookup computes its angles with
    /// polynomial `atan2`/`acos` (error ≤ 2e-7 rad), so two pairs related by a symmetry land
    /// up to that far apart: |Δf| ≤ |∂f/∂φ| · 2e-7, which is large relative to f only where f
    /// is tiny and steep — negligible against the material's own scale.
    pub symmetry_floor: f64,
    /// Angular resolution of the declared symmetries, in radians (default 4e-7): a table's
    /// linear lookup computes its angles with polynomial `atan2`/`acos` (error ≤ 2e-7 rad each),
    /// so two pairs related by a symmetry may be looked up that far apart. Where f differs by
    /// more than the tolerances above, the difference must stay within f's own change when a
    /// direction turns by this angle about the normal.
    pub symmetry_angle: f64,
    /// Relative tolerance between a sample's pdf and `pdf(wi, wo)` (default 1e-7: both from
    /// f64 arithmetic; a sampler whose warps are f32 data, as an RGL file's, agrees to f32
    /// rounding through the warp, ~1e-6).
    pub pdf_tolerance: f64,
    /// Relative tolerance of `eval_batch` against `eval` (default 1e-6: a batch path may
    /// reorder the same f32 arithmetic, not approximate it differently).
    pub batch_tolerance: f64,
    /// Seed of the pairs and samples.
    pub seed: u64,
}

impl Default for Contract {
    fn default() -> Self {
        Contract {
            pairs: 2000,
            samples: 200,
            symmetry_tolerance: 1e-5,
            symmetry_floor: 1e-6,
            symmetry_angle: 4e-7,
            pdf_tolerance: 1e-7,
            batch_tolerance: 1e-6,
            seed: 1,
        }
    }
}

/// The view directions of the sampling checks: normal, moderate, steep and near-grazing, at
/// azimuths off the axes so anisotropic lobes are exercised.
pub(crate) fn views() -> [DVec3; 5] {
    [
        (0.0f64, 0.0f64),
        (30.0, 0.4),
        (60.0, 2.0),
        (80.0, -1.1),
        (88.0, 0.9),
    ]
    .map(|(t, p)| geometry::spherical(t.to_radians(), p))
}

/// At most this many violations are reported per check (one failure mode usually repeats).
const PER_CHECK: usize = 5;

/// Collects violations, `PER_CHECK` per check.
struct Log {
    all: Vec<String>,
    counts: Vec<(&'static str, usize)>,
}

impl Log {
    fn new() -> Log {
        Log {
            all: Vec::new(),
            counts: Vec::new(),
        }
    }

    #[cfg(test)]
    #[track_caller]
    fn assert_empty(self, what: &str) {
        assert!(self.all.is_empty(), "{what}:\n{}", self.all.join("\n"));
    }

    fn fail(&mut self, check: &'static str, msg: impl FnOnce() -> String) {
        let n = match self.counts.iter_mut().find(|(c, _)| *c == check) {
            Some((_, n)) => n,
            None => {
                self.counts.push((check, 0));
                &mut self.counts.last_mut().expect("just pushed").1
            }
        };
        *n += 1;
        if *n <= PER_CHECK {
            self.all.push(format!("{check}: {}", msg()));
        }
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    close_abs(a, b, rel, 1e-30)
}

fn close_abs(a: f64, b: f64, rel: f64, abs: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
}

/// Checks the whole `Brdf` contract on `brdf` (module docs); `Err` lists the violations found
/// (at most five per check, each naming its check and the directions).
pub fn check_contract(brdf: &dyn Brdf, opts: &Contract) -> Result<(), Vec<String>> {
    let mut log = Log::new();
    let c = brdf.channels().len();
    if c == 0 || c > MAX_CHANNELS {
        return Err(vec![format!("channels: {c} (expected 1..={MAX_CHANNELS})")]);
    }
    let mut rng = Pcg32::new(opts.seed);
    let pairs: Vec<(DVec3, DVec3)> = (0..opts.pairs)
        .map(|_| {
            (
                geometry::uniform_hemisphere(rng.next_dvec2()),
                geometry::uniform_hemisphere(rng.next_dvec2()),
            )
        })
        .collect();
    values_and_symmetry(brdf, opts, &pairs, &mut log);
    batches(brdf, opts, &pairs, &mut log);
    bad_input(brdf, &mut log);
    lengths(brdf, opts, &pairs, &mut log);
    if opts.samples > 0 {
        sampling(brdf, opts, &views(), &mut rng, &mut log);
    }
    if let Err(e) = brdf.health() {
        log.fail("health", || e.to_string());
    }
    if log.all.is_empty() {
        Ok(())
    } else {
        let hidden: usize = log
            .counts
            .iter()
            .map(|(_, n)| n.saturating_sub(PER_CHECK))
            .sum();
        if hidden > 0 {
            log.all.push(format!("... and {hidden} more"));
        }
        Err(log.all)
    }
}

fn eval<B: Brdf + ?Sized>(brdf: &B, wi: DVec3, wo: DVec3) -> [f32; MAX_CHANNELS] {
    let mut f = [0.0f32; MAX_CHANNELS];
    brdf.eval(wi, wo, &mut f[..brdf.channels().len()]);
    f
}

/// The bad-input part of the contract alone, panicking with the violations (the crate's model
/// tests).
#[cfg(test)]
#[track_caller]
pub(crate) fn assert_bad_input_gives_zero<B: Brdf + ?Sized>(brdf: &B) {
    let mut log = Log::new();
    bad_input(brdf, &mut log);
    log.assert_empty(&brdf.describe());
}

/// The sampling part of the contract alone, `n` samples at each of `wos`, panicking with the
/// violations (the crate's model tests).
#[cfg(test)]
#[track_caller]
pub(crate) fn assert_sampling_consistent<B: Brdf + ?Sized>(brdf: &B, wos: &[DVec3], n: usize) {
    let opts = Contract {
        samples: n,
        ..Contract::default()
    };
    let mut log = Log::new();
    sampling(brdf, &opts, wos, &mut Pcg32::new(5), &mut log);
    log.assert_empty(&brdf.describe());
}
