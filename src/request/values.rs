//! Values a setting may be written in two ways — a string on a command line, a number or a list
//! in JSON and Python — normalized once here.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::spectrum::Channels;

/// Wavelengths in nm: `"400,500,600"` or `[400, 500, 600]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "NumbersOrText", into = "Vec<f64>")]
pub struct Wavelengths(pub Vec<f64>);

impl Wavelengths {
    /// The channels at these wavelengths (strictly increasing, positive).
    pub fn channels(&self) -> Result<Channels> {
        Channels::wavelengths(self.0.clone())
    }
}

impl std::str::FromStr for Wavelengths {
    type Err = BadValue;

    /// `400,500,600`. The error names no field (a `BadValue`): `--wavelengths abc` said
    /// "invalid value 'abc' for '--wavelengths': invalid argument `wavelengths`: …".
    fn from_str(s: &str) -> std::result::Result<Wavelengths, BadValue> {
        let nm = s
            .split(',')
            .map(|x| {
                x.trim()
                    .parse::<f64>()
                    .map_err(|_| BadValue(format!("`{}` is not a number", x.trim())))
            })
            .collect::<std::result::Result<Vec<_>, BadValue>>()?;
        Ok(Wavelengths(nm))
    }
}

impl From<Wavelengths> for Vec<f64> {
    fn from(w: Wavelengths) -> Vec<f64> {
        w.0
    }
}

/// How a list of numbers may be written.
#[derive(Deserialize)]
#[serde(untagged)]
enum NumbersOrText {
    Numbers(Vec<f64>),
    Text(String),
}

impl TryFrom<NumbersOrText> for Wavelengths {
    type Error = BadValue;
    fn try_from(v: NumbersOrText) -> std::result::Result<Wavelengths, BadValue> {
        match v {
            NumbersOrText::Numbers(n) => Ok(Wavelengths(n)),
            NumbersOrText::Text(s) => s.parse(),
        }
    }
}

/// An error target as a fraction: `0.005`, `"0.005"` or `"0.5%"`; positive and finite.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "NumberOrText", into = "f64")]
pub struct ErrorTarget(pub f64);

/// What is wrong with a written value, without the field's name: the parsers that report it
/// (the settings' `from_value`, a command line's flag) name the field or flag themselves, so
/// the message says it once.
#[derive(Debug, Clone, PartialEq)]
pub struct BadValue(pub String);

impl std::fmt::Display for BadValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadValue {}

impl std::str::FromStr for ErrorTarget {
    type Err = BadValue;

    /// `0.5%` or `0.005`.
    fn from_str(s: &str) -> std::result::Result<ErrorTarget, BadValue> {
        let t = s.trim();
        let (num, scale) = match t.strip_suffix('%') {
            Some(n) => (n.trim(), 0.01),
            None => (t, 1.0),
        };
        let x = num.parse::<f64>().map_err(|_| bad_target_msg(s))?;
        ErrorTarget::new(x * scale).map_err(|_| bad_target_msg(s))
    }
}

impl ErrorTarget {
    /// A positive, finite error.
    pub fn new(x: f64) -> Result<ErrorTarget> {
        if x > 0.0 && x.is_finite() {
            Ok(ErrorTarget(x))
        } else {
            Err(bad_target(&x.to_string()))
        }
    }
}

fn bad_target(s: &str) -> Error {
    Error::arg("target_error", bad_target_msg(s).0)
}

fn bad_target_msg(s: &str) -> BadValue {
    BadValue(format!(
        "`{s}`: expected a positive error such as 0.5% or 0.005"
    ))
}

impl From<ErrorTarget> for f64 {
    fn from(e: ErrorTarget) -> f64 {
        e.0
    }
}

/// How a number may be written.
#[derive(Deserialize)]
#[serde(untagged)]
enum NumberOrText {
    Number(f64),
    Text(String),
}

impl TryFrom<NumberOrText> for ErrorTarget {
    type Error = BadValue;
    fn try_from(v: NumberOrText) -> std::result::Result<ErrorTarget, BadValue> {
        match v {
            NumberOrText::Number(x) => {
                ErrorTarget::new(x).map_err(|_| bad_target_msg(&x.to_string()))
            }
            NumberOrText::Text(s) => s.parse(),
        }
    }
}

/// A list of names: `"a,b"` or `["a", "b"]` (empty items dropped).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "ListOrText", into = "Vec<String>")]
pub struct Names(pub Vec<String>);

impl std::str::FromStr for Names {
    type Err = Error;

    /// `a,b,c`.
    fn from_str(s: &str) -> Result<Names> {
        Ok(ListOrText::Text(s.to_owned()).into())
    }
}

impl From<Names> for Vec<String> {
    fn from(n: Names) -> Vec<String> {
        n.0
    }
}

/// How a list of names may be written.
#[derive(Deserialize)]
#[serde(untagged)]
enum ListOrText {
    List(Vec<String>),
    Text(String),
}

impl From<ListOrText> for Names {
    fn from(v: ListOrText) -> Names {
        let items = match v {
            ListOrText::List(l) => l,
            ListOrText::Text(s) => s.split(',').map(str::to_owned).collect(),
        };
        Names(
            items
                .into_iter()
                .map(|x| x.trim().to_owned())
                .filter(|x| !x.is_empty())
                .collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_spellings_give_the_same_value() {
        let a: Wavelengths = serde_json::from_str("\"450, 550,650\"").unwrap();
        let b: Wavelengths = serde_json::from_str("[450, 550, 650]").unwrap();
        assert_eq!(a, b);
        assert!(serde_json::from_str::<Wavelengths>("\"450,x\"").is_err());
        let a: ErrorTarget = serde_json::from_str("\"0.5%\"").unwrap();
        let b: ErrorTarget = serde_json::from_str("0.005").unwrap();
        assert!((a.0 - b.0).abs() < 1e-15);
        for bad in ["0", "-0.1", "\"x\"", "\"-1%\""] {
            assert!(serde_json::from_str::<ErrorTarget>(bad).is_err(), "{bad}");
        }
        // The field is named once, by the settings parser (it was named twice: "invalid
        // argument `target_error`: invalid argument `target_error`: ...").
        let e =
            crate::request::from_json::<crate::request::BakeSettings>(r#"{"target_error": -1}"#)
                .unwrap_err()
                .to_string();
        assert_eq!(e.matches("target_error").count(), 1, "{e}");
        let a: Names = serde_json::from_str("\"kd, ks,,n\"").unwrap();
        let b: Names = serde_json::from_str("[\"kd\", \"ks\", \"n\"]").unwrap();
        assert_eq!(a, b);
        assert_eq!(a.0.len(), 3);
    }
}
