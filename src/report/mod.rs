//! Reports: the accuracy suite (tables vs their sources, per grid and codec) and its plots.
//!
//! - [`suite`]: which sources, grids and codecs; running them ([`suite::run`]); the rows and
//!   their CSV and Markdown forms;
//! - [`plot`]: rate–distortion PNGs (error vs bytes stored) with plotters and an embedded font.

pub mod plot;
pub mod suite;

pub use suite::{CodecDef, Report, Row, SourceDef, SuiteConfig, run};
