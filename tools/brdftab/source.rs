//! Opening a SOURCE argument: an inline JSON spec (starts with `{`) or a `.json` spec file.
//! Later: table files, databases (`DB#NAME`), MERL `.binary` and RGL `.bsdf` files.

use brdftab::{Brdf, Channels, Error, ModelSpec, Result};

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

/// Opens SOURCE as a `Brdf` with the given channels.
pub fn open(source: &str, channels: &Channels) -> Result<Box<dyn Brdf>> {
    let spec = if source.trim_start().starts_with('{') {
        ModelSpec::parse(source)?
    } else {
        ModelSpec::from_file(source)?
    };
    spec.build(channels)
}
