//! Opening a SOURCE argument as a `Brdf`.
//!
//! A SOURCE is one of: an inline JSON model spec (starts with `{`), a `.json` spec file, a
//! brdftab table file or database entry (`FILE` / `DB#NAME`), a MERL `.binary` file, or an RGL
//! `.bsdf` file. Each kind is handled by the library; this module only dispatches.

use brdftab::table::{Interp, Table, TabulatedBrdf};
use brdftab::{Brdf, Channels, Error, ModelSpec, Result};

/// What a SOURCE argument names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// Inline JSON or a `.json` file.
    Spec,
    /// A MERL `.binary` file.
    Merl,
    /// An RGL `.bsdf` tensor file.
    Rgl,
    /// A brdftab table file or database (optionally `#NAME`).
    Table,
}

/// Classifies a SOURCE argument.
pub fn kind(source: &str) -> Kind {
    let s = source.trim_start();
    let lower = s.to_ascii_lowercase();
    if s.starts_with('{') || lower.ends_with(".json") {
        Kind::Spec
    } else if lower.ends_with(".binary") {
        Kind::Merl
    } else if lower.ends_with(".bsdf") {
        Kind::Rgl
    } else {
        Kind::Table
    }
}

/// Parses `--wavelengths 400,500,600` into a channel set (RGB when absent).
pub fn channels(wavelengths: Option<&str>) -> Result<Channels> {
    match wavelengths {
        None => Ok(Channels::Rgb),
        Some(s) => {
            let nm = s
                .split(',')
                .map(|x| {
                    x.trim()
                        .parse::<f64>()
                        .map_err(|_| Error::arg("--wavelengths", format!("`{x}` is not a number")))
                })
                .collect::<Result<Vec<_>>>()?;
            Channels::wavelengths(nm)
        }
    }
}

/// Parses a spec SOURCE (inline JSON or a .json file).
pub fn spec(source: &str) -> Result<ModelSpec> {
    if source.trim_start().starts_with('{') {
        ModelSpec::parse(source)
    } else {
        ModelSpec::from_file(source)
    }
}

/// Opens SOURCE as a `Brdf`. `channels` applies to model specs (tables and measurements have
/// their own channel sets). Tables use linear interpolation.
pub fn open(source: &str, channels: &Channels) -> Result<Box<dyn Brdf>> {
    open_with(source, channels, Interp::Linear)
}

/// Opens SOURCE as a `Brdf`, tables with interpolation `interp`.
pub fn open_with(source: &str, channels: &Channels, interp: Interp) -> Result<Box<dyn Brdf>> {
    match kind(source) {
        Kind::Spec => spec(source)?.build(channels),
        Kind::Merl => Ok(Box::new(brdftab::measured::MerlBrdf::open(source)?)),
        // An RGL file answers in its own channels (RGB, or its wavelengths) unless wavelengths
        // are asked for explicitly.
        Kind::Rgl if *channels != Channels::Rgb => Ok(Box::new(
            brdftab::measured::RglBrdf::open_with_channels(source, channels)?,
        )),
        Kind::Rgl => Ok(Box::new(brdftab::measured::RglBrdf::open(source)?)),
        Kind::Table => {
            let path = brdftab::store::db::split_source(source).0;
            if brdftab::store::tables::is_store_file(path) {
                Ok(Box::new(
                    brdftab::store::tables::open_brdf(source, false)?.with_interp(interp),
                ))
            } else if Table::is_raw(source) {
                Ok(Box::new(
                    TabulatedBrdf::from_table(Table::open_raw(source)?).with_interp(interp),
                ))
            } else if !std::path::Path::new(source).exists() {
                Err(Error::NotFound(format!("{source}: no such table file")))
            } else {
                Err(Error::Unsupported(format!(
                    "{source}: not a table file this build can read"
                )))
            }
        }
    }
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
