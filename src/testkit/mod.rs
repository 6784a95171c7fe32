//! The test kit (feature `testkit`): what a test of a [`Brdf`](crate::Brdf) needs and nothing a renderer does.
//!
//! Every `Brdf` in this crate — each model, a table of any grid, a MERL file, an RGL file — owes
//! its callers the same contract, and [`check_contract`] checks all of it on one value:
//!
//! - **positivity**: f_r is finite and ≥ 0 for every pair of directions;
//! - **declared symmetry**: what [`Flags`](crate::Flags) declares holds — reciprocity
//!   f(a, b) = f(b, a), isotropy (a rotation of both directions about the normal changes
//!   nothing), bilateral symmetry (nor does a mirror in the plane of incidence);
//! - **the horizon and bad input**: a direction below the horizon, NaN, infinite or zero gives
//!   f_r = 0, pdf = 0 and no sample, and so does a `u` outside [0, 1)² (an edge's 1, beyond,
//!   NaN); a pair a hair above it (cosines down to the smallest subnormal, 5e-324) gives no NaN
//!   and nothing negative (values may overflow where f_r grows like 1/cos θ);
//! - **lengths**: directions need not be unit — any finite nonzero length, 1e-300 to 1e300
//!   (whose squares under- or overflow), gives what the unit direction gives: f_r, pdf and the
//!   sample;
//! - **batches**: `eval_batch` gives what `eval` gives, pair by pair;
//! - **wavelengths**: `eval_at_wavelengths` gives what `eval_wavelength` gives, and at a
//!   non-wavelength (NaN, ±∞, ≤ 0 nm) both, and `sample_wavelengths`' weights, are NaN;
//! - **sampling**: a sample's pdf is `pdf(wi, wo)`, its weight is f_r cos θi / pdf, the fused
//!   `eval_pdf` agrees with both, and sampled directions are unit and above the horizon (a delta
//!   lobe: samples marked delta with finite weights).
//!
//! The crate's own tests run it over every model and every source kind (tests/contract.rs); a
//! `Brdf` written outside the crate can run it too. [`Pcg32`] is the crate's deterministic
//! generator, for tests and benchmarks that must draw the same pairs every run; [`TempDir`] a
//! scratch directory that removes itself.
//!
//! ```
//! use brdftab::testkit::{Contract, check_contract};
//! let lambert = brdftab::open(r#"{"model": "lambert", "kd": 0.5}"#)?;
//! check_contract(lambert.as_ref(), &Contract::default()).map_err(|v| v.join("\n")).unwrap();
//! # Ok::<(), brdftab::Error>(())
//! ```

pub(crate) mod contract;
mod progress_log;
mod tempdir;

pub use crate::rng::Pcg32;
pub use contract::{Contract, check_contract};
pub use progress_log::ProgressLog;
pub use tempdir::TempDir;
