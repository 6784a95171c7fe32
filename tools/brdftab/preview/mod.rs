//! Preview renderer: path tracing and lit spheres for looking at materials.
//!
//! - [`image`]: the [`Image`] type and its files (EXR, PNG), tone mapping, false colour;
//! - [`scene`]: a unit sphere (optionally on a grey ground) under a smooth procedural sky or an
//!   EXR lat-long map, with an optional point or spherical light, seen by a pinhole camera;
//! - [`options`]: [`RenderOptions`], what a render is asked for, and its limits;
//! - [`path`]: the path tracer (MIS between light sampling and `Brdf::sample`) and the
//!   direct-lighting "lit sphere" mode, [`render`];
//! - [`compare`](mod@compare): relative RMSE between renders and false-colour difference images.
//!
//! ```
//! use brdftab::{spec::ModelSpec, spectrum::Channels};
//! use brdftab_tools::preview::{RenderOptions, Mode, render};
//!
//! let brdf = ModelSpec::parse(r#"{"model": "lambert", "kd": 0.2}"#)?.build(&Channels::Rgb)?;
//! let opts = RenderOptions { width: 16, height: 16, spp: 4, mode: Mode::Lit, ..Default::default() };
//! let img = render(brdf.as_ref(), &opts, &brdftab::progress::Silent)?;
//! assert_eq!((img.width, img.height, img.channels), (16, 16, 3));
//! # Ok::<(), brdftab::Error>(())
//! ```

pub mod compare;
pub mod image;
pub mod options;
pub mod path;
pub mod sampler;
pub mod scene;
pub mod slice;

pub use compare::{CompareResult, compare, difference_image};
pub use image::{
    ExrPrecision, FalseColor, Image, colormap, false_color, read_exr, write_auto, write_exr,
    write_png,
};
pub use options::{
    EnvChoice, LightChoice, MAX_PIXELS, MAX_SAMPLE_BYTES, MAX_THREADS, Mode, RenderOptions,
    Sampling,
};
pub use path::render;
pub use scene::{Environment, Light, Scene};
