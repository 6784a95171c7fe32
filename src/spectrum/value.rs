//! Model parameters that may vary with wavelength ([`Value`]): resolving them for a channel
//! set, their checks and their JSON form.

use serde::{Deserialize, Serialize};

use super::{Channels, is_wavelength, lerp_sorted};
use crate::error::{Error, Result};

/// A model parameter that may vary with wavelength: grey, RGB, or a sampled spectrum.
///
/// In JSON: a number (`0.5`), an array of three (`[0.8, 0.6, 0.2]`), or
/// `{"wavelengths": [..], "values": [..]}`.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// The same value in every channel.
    Grey(f64),
    /// One value per R, G, B channel.
    Rgb([f64; 3]),
    /// A sampled spectrum, interpolated linearly (constant outside the samples).
    Spectral {
        /// Wavelengths in nm, strictly increasing.
        wavelengths: Vec<f64>,
        /// Values at those wavelengths.
        values: Vec<f64>,
    },
}

impl Value {
    /// The value at wavelength `nm` (RGB values through the colour-preserving basis,
    /// [`Channels::mix_at`]); NaN at a non-wavelength ([`is_wavelength`]), a grey value too.
    pub fn at(&self, nm: f64) -> f64 {
        match self {
            Value::Grey(_) if !is_wavelength(nm) => f64::NAN,
            Value::Grey(v) => *v,
            Value::Rgb(rgb) => Channels::Rgb.mix_at(nm).apply(|i| rgb[i]),
            Value::Spectral {
                wavelengths,
                values,
            } => {
                let (i0, i1, t) = lerp_sorted(wavelengths, nm, |k| k);
                (1.0 - t) * values[i0] + t * values[i1]
            }
        }
    }

    /// The value for every channel of `channels`.
    ///
    /// RGB values on RGB channels are taken as they are; everything else is evaluated at the
    /// channels' wavelengths.
    pub fn resolve(&self, channels: &Channels) -> Vec<f64> {
        match (self, channels) {
            (Value::Rgb(rgb), Channels::Rgb) => rgb.to_vec(),
            _ => (0..channels.len())
                .map(|i| self.at(channels.wavelength(i)))
                .collect(),
        }
    }

    /// Every number in the value (for validation).
    pub fn numbers(&self) -> Vec<f64> {
        match self {
            Value::Grey(v) => vec![*v],
            Value::Rgb(v) => v.to_vec(),
            Value::Spectral { values, .. } => values.clone(),
        }
    }

    /// Checks the value: finite, `>= min` (use `f64::NEG_INFINITY` for no bound) and 0 or of a
    /// magnitude in [`NUMBER_RANGE`]; spectra need matching lengths and increasing wavelengths.
    /// `field` names the value in the error.
    pub fn validate(&self, field: &str, min: f64) -> Result<()> {
        if let Value::Spectral {
            wavelengths,
            values,
        } = self
        {
            if wavelengths.is_empty() || wavelengths.len() != values.len() {
                return Err(Error::spec(
                    field,
                    format!(
                        "spectrum needs as many values ({}) as wavelengths ({}), at least one",
                        values.len(),
                        wavelengths.len()
                    ),
                ));
            }
            if wavelengths
                .windows(2)
                .any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
                || wavelengths.iter().any(|w| !w.is_finite() || *w <= 0.0)
            {
                return Err(Error::spec(
                    field,
                    "wavelengths must be positive and strictly increasing",
                ));
            }
        }
        for v in self.numbers() {
            if !v.is_finite() {
                return Err(Error::spec(field, format!("{v} is not a finite number")));
            }
            if v < min {
                return Err(Error::spec(
                    field,
                    format!("{v} is below the minimum {min}"),
                ));
            }
            check_range(v, field)?;
        }
        Ok(())
    }

    /// The mean over channels of `channels` (used e.g. for mixture weights).
    pub fn mean(&self, channels: &Channels) -> f64 {
        let v = self.resolve(channels);
        v.iter().sum::<f64>() / v.len() as f64
    }
}

impl From<f64> for Value {
    fn from(v: f64) -> Self {
        Value::Grey(v)
    }
}

impl Serialize for Value {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        match self {
            Value::Grey(v) => s.serialize_f64(*v),
            Value::Rgb(v) => v.serialize(s),
            Value::Spectral {
                wavelengths,
                values,
            } => {
                let mut m = s.serialize_map(Some(2))?;
                m.serialize_entry("wavelengths", wavelengths)?;
                m.serialize_entry("values", values)?;
                m.end()
            }
        }
    }
}

impl<'de> Deserialize<'de> for Value {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let v = serde_json::Value::deserialize(d)?;
        match v {
            serde_json::Value::Number(n) => n
                .as_f64()
                .map(Value::Grey)
                .ok_or_else(|| D::Error::custom("number out of range")),
            serde_json::Value::Array(a) => {
                if a.len() != 3 {
                    return Err(D::Error::custom(format!(
                        "an RGB value needs 3 numbers, got {}",
                        a.len()
                    )));
                }
                let mut rgb = [0.0; 3];
                for (i, x) in a.iter().enumerate() {
                    rgb[i] = x.as_f64().ok_or_else(|| {
                        D::Error::custom(format!("RGB entry {i} is not a number"))
                    })?;
                }
                Ok(Value::Rgb(rgb))
            }
            serde_json::Value::Object(o) => {
                #[derive(Deserialize)]
                #[serde(deny_unknown_fields)]
                struct Spec {
                    wavelengths: Vec<f64>,
                    values: Vec<f64>,
                }
                let s: Spec = serde_json::from_value(serde_json::Value::Object(o))
                    .map_err(|e| D::Error::custom(format!("spectrum: {e}")))?;
                Ok(Value::Spectral {
                    wavelengths: s.wavelengths,
                    values: s.values,
                })
            }
            other => Err(D::Error::custom(format!(
                "expected a number, an array of 3 (RGB) or {{\"wavelengths\": [..], \"values\": [..]}}, got {other}"
            ))),
        }
    }
}

/// The magnitudes a model parameter may have besides 0 (every [`Value`] and every number of a
/// [`crate::ModelSpec`]): the models compute in f64 and return f32, and beyond this range their
/// values over- or underflow (k_d = 1e300 evaluated as inf, a GGX α of 1e300 or a refractive
/// index of 1e-300 as NaN).
pub const NUMBER_RANGE: std::ops::RangeInclusive<f64> = 1e-12..=1e12;

/// `x` is 0 or its magnitude lies in [`NUMBER_RANGE`]; else the error for `field`.
pub(crate) fn check_range(x: f64, field: &str) -> Result<()> {
    if x == 0.0 || NUMBER_RANGE.contains(&x.abs()) {
        return Ok(());
    }
    Err(Error::spec(
        field,
        format!(
            "{x:e} is out of range: 0 or a magnitude within [{:e}, {:e}]",
            NUMBER_RANGE.start(),
            NUMBER_RANGE.end()
        ),
    ))
}
