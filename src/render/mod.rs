//! Preview renderer: path tracing and lit spheres for looking at materials.
//!
//! - [`image`]: the [`Image`] type and its files (EXR, PNG), tone mapping, false colour.

pub mod image;

pub use image::{Image, read_exr, write_exr, write_png};
