//! # brdftab — tabulated BRDFs
//!
//! A library of BRDF models behind one [`Brdf`] trait, dense symmetry-reduced compressed tables
//! that sample any `Brdf` or load measured data, and the tools around them. The `brdftab`
//! command-line tool (`tools/brdftab`), the C ABI and the Python package (`bindings/`) are hosts
//! of this crate: what they do, a Rust program does with the calls below.
//!
//! ## Open any source
//!
//! [`open`] turns a SOURCE string — an inline JSON model spec, a `.json` spec file, a table
//! (`FILE.btdb`, or `DB#NAME` for one table of a database), a MERL `.binary` or an RGL-EPFL
//! `.bsdf` — into a `Box<dyn Brdf + Send + Sync>` ([`source`] says how each kind opens;
//! [`open_with`] takes [`OpenOptions`]: the interpolation, wavelengths instead of RGB, eager
//! decoding). The models and their parameters are [`spec::MODELS`] (`brdftab models`);
//! [`measured::data`] finds the RGL files the repository ships in `data/rgl`.
//!
//! ## Evaluate, sample, integrate
//!
//! [`Brdf::eval`] writes f_r in 1/sr (not times a cosine) per channel for `wi` towards the light
//! and `wo` towards the viewer, in the local frame whose z is the normal; [`Brdf::sample`] draws
//! `wi` for a `wo` with its pdf and weight f_r cos θi / pdf, [`Brdf::pdf`] is that density, and
//! [`Brdf::albedo`] integrates f_r cos θo over the hemisphere. [`Brdf::eval_batch`],
//! [`Brdf::pdf_batch`] and [`Brdf::sample_batch`] run slices of pairs on all cores. A table
//! decodes its chunks as lookups first touch them, and a chunk that fails its checksum puts it
//! in a failed state that [`Brdf::health`] reports: check it after a batch or a frame.
//!
//! ```
//! use brdftab::Brdf;
//! use glam::{DVec2, DVec3};
//!
//! let ggx = brdftab::open(r#"{"model": "ggx", "alpha": 0.2}"#)?;
//! assert_eq!(ggx.channels().len(), 3); // RGB unless wavelengths are asked for
//!
//! let wo = DVec3::new(-0.3, 0.0, 0.954); // towards the viewer; need not be normalized
//! let mut f = [0.0f32; 3];
//! ggx.eval(DVec3::new(0.3, 0.0, 0.954), wo, &mut f); // the mirror direction: the lobe's peak
//! assert!(f[0] > 1.0);
//!
//! // A direction towards the light drawn for `wo`, with its density and weight.
//! let mut weight = [0.0f32; 3];
//! let s = ggx.sample(wo, DVec2::new(0.3, 0.7), &mut weight).expect("wo is above the horizon");
//! assert!(s.wi.z > 0.0 && s.pdf > 0.0 && !s.delta);
//! assert!((ggx.pdf(s.wi, wo) - s.pdf).abs() <= 1e-9 * s.pdf);
//!
//! // Directional albedo ∫ f_r cos θo dωo: below 1, a GGX lobe without Fresnel loses only what
//! // its microfacets shadow.
//! let mut a = [0.0f64; 3];
//! ggx.albedo(DVec3::Z, &mut a);
//! assert!(a[0] > 0.9 && a[0] < 1.0);
//! # Ok::<(), brdftab::Error>(())
//! ```
//!
//! ## Bake tables and keep them in a database
//!
//! A [`BakeRequest`] bakes any SOURCE into a table — the grid ([`Preset`], [`GridChoice`]: presets,
//! the MERL grid, adaptive grids to an error target), the symmetry reduction and the codec are its
//! choices, with the defaults every host shares — and writes it ([`BakeTarget`]) to a file of one
//! table or as a named table of a database: one `.btdb` file of many tables, written atomically,
//! that `DB#NAME` opens one of. [`store::db`] lists, renames, removes and verifies a database's
//! tables, [`store::Store`] reads them chunk by chunk, and [`Table`] is a table in memory
//! ([`bake::BakeRequest::table`]).
//!
//! ```
//! use brdftab::{BakeRequest, BakeTarget, Brdf, Preset, store};
//! use glam::DVec3;
//! # let dir = std::env::temp_dir().join(format!("brdftab-lib-doc-{}", std::process::id()));
//! # std::fs::create_dir_all(&dir)?;
//! let db = dir.join("materials.btdb");
//! let gold = r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#;
//! for (name, source) in [("white", r#"{"model": "lambert", "kd": 0.25}"#), ("gold", gold)] {
//!     let report = BakeRequest::new(source)
//!         .preset(Preset::Small)
//!         .run(&BakeTarget::db(&db, name))?;
//!     // `report.info` is the written table's entry of `brdftab info --json`'s `tables`.
//!     assert_eq!(report.info["name"], name);
//! }
//! let names: Vec<String> = store::db::list(&db)?.into_iter().map(|(t, _)| t.name).collect();
//! assert_eq!(names, ["white", "gold"]);
//!
//! // A table opens as a `Brdf`, as the model it was baked from does.
//! let white = brdftab::open(format!("{}#white", db.display()))?;
//! let mut f = [0.0f32; 3];
//! white.eval(DVec3::new(0.0, 0.6, 0.8), DVec3::Z, &mut f);
//! white.health()?; // every chunk the lookups read passed its checksum
//! assert!((f[0] - 0.25).abs() <= 1e-3 * 0.25); // the log16 codec's bound, 1e-3 relative
//!
//! store::db::rename(&db, "gold", "gold-ct")?;
//! let chunks: u64 = store::db::list(&db)?.iter().map(|(t, _)| t.chunks).sum();
//! assert_eq!(store::db::verify(&db)? as u64, chunks); // every chunk decoded, checksums checked
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Analysis, fitting, conversion
//!
//! [`analysis`] measures any `Brdf`: its albedo (adaptive quadrature with an error estimate),
//! its plausibility (positivity, reciprocity, energy conservation: `brdftab check`), a table's
//! accuracy against its source. [`fit`] fits a model's parameters to any source by least
//! squares. [`request::convert`] writes any source as an RGL `.bsdf` file (which Mitsuba 3 and
//! pbrt-v4 load), a MERL `.binary` or a table.
//!
//! ## For hosts
//!
//! [`request`] holds the settings of a bake, a conversion, a fit, an open and a save as plain
//! structs whose fields are the CLI's flags, Python's keywords and the C ABI's JSON keys,
//! validated once; [`cache`] keeps baked tables on disk; [`Progress`] reports progress and
//! carries a host's request to stop; [`host`] and [`par`] contain panics at an FFI boundary and
//! hold the library's thread pool. Every error is an [`Error`]. Features: `clap` (the request
//! settings derive `clap::Args`, for the CLI) and `testkit` (the module `testkit`: a
//! deterministic RNG and the checks of the `Brdf` contract, for an implementation of your own).
//!
//! ## How data flows
//!
//! One way (see DESIGN.md in the repository): a source — an analytic model ([`models`],
//! described by a [`spec::ModelSpec`]) or a measurement ([`measured`]) — is baked on a grid into
//! a dense table ([`table`]); the table is split into chunks that the [`codec`] turns into bytes;
//! the [`store`] writes chunks and metadata; opening gives back a [`TabulatedBrdf`] that
//! implements `Brdf` again. Every consumer — [`analysis`], the hosts (the C ABI, the Python
//! package), and the application in `tools/brdftab` (the `brdftab` CLI, its preview renderer and
//! reports, a crate of its own that no host compiles) — sees only `Brdf`.

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
