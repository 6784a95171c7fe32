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
    // Each setting once, and only where it means something: a silently dropped or overridden
    // tolerance stores a table at another precision than the one asked for.
    if let (Some(t), Some(u)) = (tol, tolerance) {
        return Err(Error::arg(
            "codec_tolerance",
            format!("the codec `{name}:{t}` gives a tolerance already; {u} is a second one"),
        ));
    }
    let plain = matches!(name.trim(), "f32" | "f16");
    for (field, given) in [
        ("codec", tol.is_some()),
        ("codec_tolerance", tolerance.is_some()),
        ("floor", floor.is_some()),
    ] {
        if given && plain {
            let what = if field == "floor" {
                "a floor"
            } else {
                "a tolerance"
            };
            return Err(Error::arg(
                field,
                format!(
                    "{what} applies to the log16 codec only; `{}` stores values as they are",
                    name.trim()
                ),
            ));
        }
    }
    let quant = Quant::parse(name.trim(), tolerance.or(tol), floor).map_err(|e| match e {
        // A tolerance written into the codec (`log16:0`) is the codec's field.
        Error::InvalidArgument { name: f, msg } if f == "codec_tolerance" && tol.is_some() => {
            Error::arg("codec", msg)
        }
        e => e,
    })?;
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

#[cfg(test)]
mod tests {
    use super::*;

    fn field(r: Result<Codec>) -> String {
        match r {
            Err(Error::InvalidArgument { name, .. }) => name,
            r => panic!("not an argument error: {r:?}"),
        }
    }

    #[test]
    fn a_setting_given_twice_or_where_it_means_nothing_is_refused() {
        // `log16:1e-2` and a separate tolerance of 1e-4: 1e-4 won without a word.
        assert_eq!(
            field(codec("log16:1e-2", Some(1e-4), None, None, false)),
            "codec_tolerance"
        );
        assert_eq!(field(codec("f16:1e-2", None, None, None, false)), "codec");
        assert_eq!(
            field(codec("f32", Some(1e-2), None, None, false)),
            "codec_tolerance"
        );
        assert_eq!(field(codec("f32", None, Some(1e-3), None, false)), "floor");
        assert_eq!(field(codec("f16", None, Some(1e-3), None, false)), "floor");
        assert_eq!(field(codec("zip:1e-2", None, None, None, false)), "codec");
        // A tolerance out of range written into the codec is the codec's (`--codec log16:0`
        // was reported as `--codec-tolerance`); given on its own, the tolerance's.
        assert_eq!(field(codec("log16:0", None, None, None, false)), "codec");
        assert_eq!(
            field(codec("log16", Some(0.0), None, None, false)),
            "codec_tolerance"
        );
        let q = |r: Result<Codec>| r.unwrap().quant;
        assert_eq!(
            q(codec("log16:1e-2", None, Some(1e-6), None, false)),
            Quant::Log16 {
                tolerance: 1e-2,
                floor: Some(1e-6)
            }
        );
        assert_eq!(
            q(codec("log16", Some(1e-4), None, None, false)),
            Quant::Log16 {
                tolerance: 1e-4,
                floor: None
            }
        );
        assert_eq!(q(codec("f16", None, None, Some(9), false)), Quant::F16);
    }
}
