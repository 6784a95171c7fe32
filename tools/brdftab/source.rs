//! SOURCE arguments: thin over [`brdftab::source`], the library's one place that knows the
//! kinds. This module only maps the CLI's flags (`--wavelengths`, `--interp`, `--rgl`) to it.

use brdftab::source::OpenOptions;
use brdftab::table::Interp;
use brdftab::{Brdf, Channels, Result};

pub use brdftab::source::{SourceKind as Kind, classify as kind};

/// Parses `--wavelengths 400,500,600` (`None`: the source's own channels).
pub fn channels(wavelengths: Option<&str>) -> Result<Option<Channels>> {
    wavelengths
        .map(brdftab::source::parse_wavelengths)
        .transpose()
        .map_err(|e| crate::bake::flag(e, "--wavelengths"))
}

/// Opens SOURCE (tables with linear interpolation).
pub fn open(source: &str, channels: &Option<Channels>) -> Result<Box<dyn Brdf + Send + Sync>> {
    open_with(source, channels, Interp::Linear)
}

/// Opens SOURCE, tables with interpolation `interp`.
pub fn open_with(
    source: &str,
    channels: &Option<Channels>,
    interp: Interp,
) -> Result<Box<dyn Brdf + Send + Sync>> {
    let opts = OpenOptions {
        interp,
        channels: channels.clone(),
        ..OpenOptions::default()
    };
    brdftab::open_with(source, &opts)
}

/// The directory of RGL `.bsdf` files used by `demo` and `accuracy`: `--rgl DIR`, else the
/// library's search ([`brdftab::measured::data::rgl_dir`]: `$BRDFTAB_RGL_DIR`, the shipped
/// `data/rgl`, `../shared/data/measured/rgl`); `None` when none exists.
pub fn rgl_dir(arg: Option<&std::path::Path>) -> Option<std::path::PathBuf> {
    match arg {
        Some(p) => Some(p.to_path_buf()),
        None => brdftab::measured::data::rgl_dir(),
    }
}
