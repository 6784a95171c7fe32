//! The brdftab application's library: what the `brdftab` CLI needs beyond the core library
//! `brdftab`, kept out of it so that a renderer linking brdftab (the C ABI, the Python
//! extension) compiles none of it.
//!
//! - [`args`]: the subcommand that ran and library errors named by the flag the user typed;
//! - [`output`]: output paths checked before any work;
//! - [`preview`]: the preview renderer (path tracer and lit sphere), images (EXR, PNG), false
//!   colour, and slice images of any `Brdf`;
//! - [`progress`]: the library's progress reports as an indicatif bar on a terminal;
//! - [`report`]: the accuracy suite, the measured-table benchmark and their plots;
//! - [`rng`]: the tools' random numbers;
//! - [`text`]: the CLI's text input and output — lines of numbers from stdin (`eval` and
//!   `pdf`; `sample` takes its view as `--wo`) and writes to stdout that fail instead of
//!   panicking on a closed pipe;
//! - [`view`]: the `brdftab view` server (the BRDF explorer in the browser).

// `!(x > 0.0)` rejects NaN together with non-positive values, as in the core library.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Every public item is documented (DESIGN.md); clippy -D warnings in CI holds it.
#![warn(missing_docs)]

pub mod args;
pub mod output;
pub mod preview;
pub mod progress;
pub mod report;
pub mod rng;
pub mod text;
// The directory holds both `view.rs` (the binary's command) and `view/` (this module).
#[path = "view/mod.rs"]
pub mod view;
