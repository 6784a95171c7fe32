//! [`OpenSettings`] and [`open`]: how every host asks to open a SOURCE.

use serde::{Deserialize, Serialize};

use super::values::Wavelengths;
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::source::OpenOptions;

/// The settings of an open (the CLI's `--interp`/`--wavelengths`, Python's `open` keywords, the
/// C ABI's JSON).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct OpenSettings {
    /// Interpolation of tables and MERL files: auto (default: nearest on tables of MERL cells and
    /// MERL files, which a MERL reader looks up by cell, linear otherwise), nearest or linear.
    #[cfg_attr(feature = "clap", arg(long))]
    pub interp: Option<String>,
    /// Wavelengths in nm (`400,500,600`) instead of the source's channels (model specs and RGL
    /// files).
    #[cfg_attr(feature = "clap", arg(long))]
    pub wavelengths: Option<Wavelengths>,
    /// Decode every chunk of a table at open, checking each checksum (default false: on first
    /// touch).
    #[cfg_attr(feature = "clap", arg(long))]
    pub eager: Option<bool>,
}

impl OpenSettings {
    /// The open options these settings describe.
    ///
    /// # Errors
    /// [`crate::Error::InvalidArgument`] naming the field.
    pub fn options(&self) -> Result<OpenOptions> {
        let interp = match self
            .interp
            .as_deref()
            .map(|s| s.trim().to_ascii_lowercase())
        {
            None => None,
            Some(s) if s == "auto" => None,
            Some(s) => Some(s.parse().map_err(|_| {
                Error::arg("interp", format!("`{s}`: expected auto, nearest or linear"))
            })?),
        };
        Ok(OpenOptions {
            interp,
            channels: self
                .wavelengths
                .as_ref()
                .map(|w| w.channels())
                .transpose()?,
            eager: self.eager.unwrap_or(false),
        })
    }
}

/// Opens SOURCE as `settings` say ([`crate::open_with`]).
pub fn open(
    source: impl AsRef<std::ffi::OsStr>,
    settings: &OpenSettings,
) -> Result<Box<dyn Brdf + Send + Sync>> {
    crate::source::open_with(source, &settings.options()?)
}
