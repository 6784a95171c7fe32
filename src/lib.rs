//! # brdftab — tabulated BRDFs
//!
//! A library of BRDF models behind one [`Brdf`] trait, dense symmetry-reduced compressed tables
//! that sample any `Brdf` or load measured data, and the tools around them.
//!
//! Data flows one way (see DESIGN.md in the repository): a source — an analytic model ([`models`], described by a
//! [`spec::ModelSpec`]) or a measurement ([`measured`]) — is baked on a grid into a dense table
//! ([`table`]); the table is split into chunks that the [`codec`] turns into bytes; the [`store`]
//! writes chunks and metadata; opening gives back a `TabulatedBrdf` that implements `Brdf` again.
//! Every consumer — [`analysis`], the hosts (the C ABI, the Python package), and the application
//! in `tools/brdftab` (the `brdftab` CLI, its preview renderer and reports, a crate of its own
//! that no host compiles) — sees only `Brdf`.
//!
//! ```
//! use brdftab::{Brdf, spec::ModelSpec, spectrum::Channels};
//! use glam::DVec3;
//!
//! let brdf = ModelSpec::parse(r#"{"model": "lambert", "kd": 0.2}"#)?.build(&Channels::Rgb)?;
//! let mut f = [0.0f32; 3];
//! brdf.eval(DVec3::new(0.0, 0.6, 0.8), DVec3::Z, &mut f);
//! assert_eq!(f, [0.2; 3]);
//! # Ok::<(), brdftab::Error>(())
//! ```

// `!(x > 0.0)` is the idiom this crate uses to reject NaN together with non-positive values
// (DESIGN.md: NaN input gives 0, never a panic); rewriting it with `partial_cmp` obscures that.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Every public item is documented (DESIGN.md); clippy -D warnings in CI holds it.
#![warn(missing_docs)]

pub mod analysis;
pub mod bake;
pub mod batch;
pub mod brdf;
pub mod cache;
pub mod codec;
pub mod colour;
pub mod error;
pub(crate) mod fastmath;
pub(crate) mod files;
pub mod fit;
pub mod fresnel;
pub mod geometry;
pub mod host;
pub mod measured;
pub mod metals;
pub mod models;
pub mod par;
pub mod progress;
pub(crate) mod quadrature;
pub mod request;
pub(crate) mod rng;
pub(crate) mod simd;
pub mod source;
pub mod spec;
pub mod spectrum;
pub mod store;
pub mod table;
#[cfg(any(test, feature = "testkit"))]
pub mod testkit;

pub use bake::{BakeReport, BakeRequest, BakeTarget, GridChoice};
pub use batch::SampleOut;
pub use brdf::{BakeSource, Brdf, BrdfSample, Flags, Lobes};
pub use error::{Error, Result};
pub use progress::{Progress, Silent};
pub use source::{OpenOptions, SourceKind, classify, open, open_with};
pub use spec::ModelSpec;
pub use spectrum::{Channels, Value};
pub use table::presets::Preset;
pub use table::{Grid, Interp, Table, TabulatedBrdf};

/// The README's code examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
