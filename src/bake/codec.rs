//! The codec a bake writes with: [`default_codec`], the one every host shares unless told
//! otherwise, and [`codec`], which builds one from the parts hosts name.

use crate::codec::{Codec, Quant};
use crate::error::{Error, Result};

/// The codec every host bakes with unless told otherwise: log16 ≤ 1e-3 at its default level.
pub fn default_codec() -> Codec {
    let quant = Quant::Log16 {
        tolerance: 1e-3,
        floor: None,
    };
    Codec {
        quant,
        level: quant.default_level(),
        ..Codec::default()
    }
}

/// Builds a codec from its parts as hosts name them: `name` is `f32`, `f16` or `log16` (also
/// `log16:TOL`), `tolerance` log16's relative bound, `level` the zstd level (default per codec).
pub fn codec(
    name: &str,
    tolerance: Option<f64>,
    floor: Option<f64>,
    level: Option<i32>,
    exhaustive: bool,
) -> Result<Codec> {
    let (name, tol) = match name.split_once(':') {
        Some((n, t)) => (
            n,
            Some(
                t.trim()
                    .parse::<f64>()
                    .map_err(|_| Error::arg("codec", format!("`{t}` is not a tolerance")))?,
            ),
        ),
        None => (name, None),
    };
    let quant = Quant::parse(name.trim(), tolerance.or(tol), floor)?;
    let level = level.unwrap_or(quant.default_level());
    if !(1..=22).contains(&level) {
        return Err(Error::arg(
            "level",
            format!("zstd level {level} is outside 1..=22"),
        ));
    }
    Ok(Codec {
        quant,
        level,
        exhaustive,
        ..Codec::default()
    })
}
