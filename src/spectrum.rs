//! Channel sets and spectrally varying parameters.
//!
//! A BRDF in brdftab returns one value per *channel*. A channel set is either RGB or an explicit
//! list of wavelengths in nanometres ([`Channels`]). Model parameters ([`Value`]) may be grey, RGB
//! or sampled spectra; they are resolved once, when a model is built for a channel set, so that
//! evaluation never allocates or interpolates parameters.
//!
//! RGB and wavelengths meet in two directions:
//! - **RGB → spectrum** (RGB data or an RGB parameter asked at a wavelength): the colour-preserving
//!   basis of [`crate::colour`], RGB (r, g, b) at λ = r b_R(λ) + g b_G(λ) + b b_B(λ), whose CIE
//!   projection under D65 — what a spectral renderer's pixel is — gives (r, g, b) back. Grey
//!   stays exactly flat, non-negative RGB gives a non-negative spectrum ([`Channels::mix_at`]).
//! - **spectrum → RGB** (spectral data such as a metal's n, k evaluated for RGB): the spectrum at
//!   the channel's *representative wavelength* [`RGB_WAVELENGTHS`], as renderers evaluate
//!   optical constants for RGB.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Representative wavelengths (nm) of the R, G and B channels, used to convert between RGB and
/// spectral data (red 645 nm, green 526 nm, blue 444 nm).
pub const RGB_WAVELENGTHS: [f64; 3] = [645.0, 526.0, 444.0];

/// The most channels a channel set may have (keeps stack buffers possible for callers).
pub const MAX_CHANNELS: usize = 64;

/// The channel set of a BRDF: RGB, or wavelengths in nm (strictly increasing).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Channels {
    /// Three channels, red, green, blue (linear sRGB primaries).
    #[default]
    Rgb,
    /// Sampled spectrum: the wavelengths in nm, strictly increasing.
    Wavelengths(Vec<f64>),
}

impl Channels {
    /// A spectral channel set; checks that the wavelengths are finite, positive, strictly
    /// increasing, and at most [`MAX_CHANNELS`].
    pub fn wavelengths(nm: Vec<f64>) -> Result<Self> {
        check_wavelengths(&nm)?;
        Ok(Channels::Wavelengths(nm))
    }

    /// Checks a channel set built directly from its public variant
    /// (`Channels::Wavelengths(vec![])`) as [`Channels::wavelengths`] checks its list. Every
    /// door that takes a caller's channels — [`crate::spec::ModelSpec::build`],
    /// [`crate::open_with`], a bake ([`crate::BakeRequest`], and the source a bake samples) —
    /// calls it: an empty, NaN, unordered or oversized list made models of no channels and
    /// wrote tables a database could no longer read.
    pub fn validate(&self) -> Result<()> {
        match self {
            Channels::Rgb => Ok(()),
            Channels::Wavelengths(nm) => check_wavelengths(nm),
        }
    }

    /// `n` wavelengths evenly spaced from `start` to `end` nm inclusive.
    pub fn linspace(start: f64, end: f64, n: usize) -> Result<Self> {
        if n == 1 {
            return Self::wavelengths(vec![start]);
        }
        Self::wavelengths(
            (0..n)
                .map(|i| start + (end - start) * i as f64 / (n - 1) as f64)
                .collect(),
        )
    }

    /// Number of channels.
    pub fn len(&self) -> usize {
        match self {
            Channels::Rgb => 3,
            Channels::Wavelengths(w) => w.len(),
        }
    }

    /// Always false: a channel set has at least one channel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The wavelength (nm) of channel `i`: the representative wavelength for RGB.
    pub fn wavelength(&self, i: usize) -> f64 {
        match self {
            Channels::Rgb => RGB_WAVELENGTHS[i],
            Channels::Wavelengths(w) => w[i],
        }
    }

    /// Short names of the channels: `R G B`, or the wavelengths (`550nm`).
    pub fn names(&self) -> Vec<String> {
        match self {
            Channels::Rgb => vec!["R".into(), "G".into(), "B".into()],
            Channels::Wavelengths(w) => w.iter().map(|x| format!("{x}nm")).collect(),
        }
    }

    /// How channel data gives a value at wavelength `nm`: for wavelengths, linear interpolation
    /// between the two channels around `nm` (the nearest end channel outside them); for RGB, the
    /// colour-preserving basis [`crate::colour::rgb_basis_at`]. At a non-wavelength (NaN, ±∞,
    /// ≤ 0 nm: not [`is_wavelength`]) the weights are NaN, so the mix is NaN rather than an end
    /// channel's value passed off as data.
    #[inline]
    pub fn mix_at(&self, nm: f64) -> ChannelMix {
        match self {
            Channels::Rgb => ChannelMix {
                index: [0, 1, 2],
                weight: crate::colour::rgb_basis_at(nm),
            },
            Channels::Wavelengths(w) => {
                let (i0, i1, t) = lerp_sorted(w, nm, |k| k);
                if t.is_nan() {
                    return ChannelMix {
                        index: [i0; 3],
                        weight: [f64::NAN; 3],
                    };
                }
                ChannelMix {
                    index: [i0, i1, i1],
                    weight: [1.0 - t, t, 0.0],
                }
            }
        }
    }
}

/// Channel data at one wavelength ([`Channels::mix_at`]): value = Σ `weight[k]` · `v[index[k]]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelMix {
    /// The channels read.
    pub index: [usize; 3],
    /// Their weights (≥ 0, summing to 1; NaN at a non-wavelength).
    pub weight: [f64; 3],
}

impl ChannelMix {
    /// The mix of the channel values `v(i)`; channels of weight 0 are not read (an infinite
    /// value there does not turn the result into NaN).
    #[inline]
    pub fn apply(&self, v: impl Fn(usize) -> f64) -> f64 {
        let mut s = 0.0;
        for k in 0..3 {
            if self.weight[k] != 0.0 {
                s += self.weight[k] * v(self.index[k]);
            }
        }
        s
    }
}

/// Whether `nm` can be a wavelength: finite and positive. The rule of
/// [`Channels::wavelengths`], and of every wavelength a host evaluates at: the Python and C
/// hosts refuse anything else with an error; in Rust, where [`crate::Brdf::eval_wavelength`]
/// and its kin cannot fail, every source gives NaN there (never an end channel's value, which
/// passed a NaN or 0 nm off as data).
#[inline]
pub fn is_wavelength(nm: f64) -> bool {
    nm.is_finite() && nm > 0.0
}

/// The neighbours of `nm` in the increasing list `w` and the weight of the upper one; the
/// weight is NaN at a non-wavelength ([`is_wavelength`]). Checked only at the ends, where a
/// non-wavelength lands (NaN fails every comparison, ∞ and ≤ 0 fall outside any list).
fn lerp_sorted(w: &[f64], nm: f64, map: impl Fn(usize) -> usize) -> (usize, usize, f64) {
    let n = w.len();
    if n == 1 || nm.is_nan() || nm <= w[0] {
        return (
            map(0),
            map(0),
            if is_wavelength(nm) { 0.0 } else { f64::NAN },
        );
    }
    if nm >= w[n - 1] {
        return (
            map(n - 1),
            map(n - 1),
            if is_wavelength(nm) { 0.0 } else { f64::NAN },
        );
    }
    let k = w.partition_point(|&x| x <= nm).clamp(1, n - 1);
    let t = (nm - w[k - 1]) / (w[k] - w[k - 1]);
    (map(k - 1), map(k), t)
}

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

/// `"rgb".parse::<Channels>()` or `"450, 550, 650".parse::<Channels>()` (wavelengths in nm, as
/// [`Channels::wavelengths`] checks them; errors name `wavelengths`).
impl std::str::FromStr for Channels {
    type Err = Error;

    fn from_str(s: &str) -> Result<Channels> {
        if s.trim().eq_ignore_ascii_case("rgb") {
            return Ok(Channels::Rgb);
        }
        let nm = s
            .split(',')
            .map(|x| {
                x.trim().parse::<f64>().map_err(|_| {
                    Error::arg("wavelengths", format!("`{}` is not a number", x.trim()))
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Channels::wavelengths(nm)
    }
}

/// The rules of [`Channels::wavelengths`]: 1..=[`MAX_CHANNELS`] finite positive wavelengths,
/// strictly increasing.
fn check_wavelengths(nm: &[f64]) -> Result<()> {
    if nm.is_empty() {
        return Err(Error::arg(
            "wavelengths",
            "at least one wavelength is needed",
        ));
    }
    if nm.len() > MAX_CHANNELS {
        return Err(Error::arg(
            "wavelengths",
            format!("{} wavelengths given, at most {MAX_CHANNELS}", nm.len()),
        ));
    }
    for (i, &w) in nm.iter().enumerate() {
        if !is_wavelength(w) {
            return Err(Error::arg(
                "wavelengths",
                format!(
                    "{w} (item {} of the list) is not a wavelength (a finite number of nm > 0)",
                    i + 1
                ),
            ));
        }
        if i > 0 && w <= nm[i - 1] {
            return Err(Error::arg(
                "wavelengths",
                "wavelengths must be strictly increasing",
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb_value_on_rgb_channels_is_exact() {
        let v = Value::Rgb([0.1, 0.2, 0.3]);
        assert_eq!(v.resolve(&Channels::Rgb), vec![0.1, 0.2, 0.3]);
    }

    #[test]
    fn grey_stays_grey_in_every_mode() {
        let v = Value::Grey(0.25);
        let ch = Channels::linspace(400.0, 700.0, 7).unwrap();
        assert!(v.resolve(&ch).iter().all(|&x| x == 0.25));
    }

    #[test]
    fn spectral_interpolates_linearly_and_clamps() {
        let v = Value::Spectral {
            wavelengths: vec![400.0, 500.0],
            values: vec![1.0, 3.0],
        };
        assert_eq!(v.at(450.0), 2.0);
        assert_eq!(v.at(300.0), 1.0);
        assert_eq!(v.at(900.0), 3.0);
    }

    #[test]
    fn an_rgb_value_as_a_spectrum_keeps_its_colour() {
        // What a spectral renderer shows of the parameter (its CIE projection) is the RGB given.
        let v = Value::Rgb([1.0, 2.0, 3.0]);
        let back = crate::colour::srgb_of(|nm| v.at(nm));
        for (i, c) in back.iter().enumerate() {
            assert!((c - (i as f64 + 1.0)).abs() < 1e-11, "{back:?}");
        }
        // On spectral channels it is that spectrum at each wavelength.
        let ch = Channels::linspace(400.0, 700.0, 4).unwrap();
        let r = v.resolve(&ch);
        for (i, x) in r.iter().enumerate() {
            assert_eq!(*x, v.at(ch.wavelength(i)));
        }
    }

    #[test]
    fn wavelength_mixes_interpolate_between_neighbours() {
        let ch = Channels::wavelengths(vec![400.0, 500.0, 600.0]).unwrap();
        let m = ch.mix_at(450.0);
        assert_eq!(m.apply(|i| [1.0, 3.0, 100.0][i]), 2.0);
        assert_eq!(ch.mix_at(300.0).apply(|i| [1.0, 3.0, 5.0][i]), 1.0);
        assert_eq!(
            ch.mix_at(900.0).apply(|i| [1.0, 3.0, f64::INFINITY][i]),
            f64::INFINITY
        );
        assert_eq!(
            ch.mix_at(500.0).apply(|i| [f64::INFINITY, 3.0, 5.0][i]),
            3.0
        );
    }

    #[test]
    fn a_non_wavelength_has_no_value() {
        // NaN, ±∞, 0 and negative nm are not wavelengths: NaN, never an end channel's value.
        let ch = Channels::wavelengths(vec![400.0, 500.0]).unwrap();
        let spectral = Value::Spectral {
            wavelengths: vec![400.0, 500.0],
            values: vec![1.0, 3.0],
        };
        for nm in [
            f64::NAN,
            0.0,
            -0.0,
            -450.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ] {
            assert!(ch.mix_at(nm).apply(|i| [1.0, 3.0][i]).is_nan(), "{nm}");
            assert!(
                Channels::Rgb.mix_at(nm).apply(|i| [0.2; 3][i]).is_nan(),
                "{nm}"
            );
            for v in [
                Value::Grey(0.5),
                Value::Rgb([0.1, 0.2, 0.3]),
                spectral.clone(),
            ] {
                assert!(v.at(nm).is_nan(), "{v:?} at {nm}");
            }
        }
        // The ends of real wavelengths are held, as before.
        assert_eq!(ch.mix_at(1e-300).apply(|i| [1.0, 3.0][i]), 1.0);
        assert_eq!(ch.mix_at(1e300).apply(|i| [1.0, 3.0][i]), 3.0);
        assert_eq!(Value::Grey(0.5).at(1e-300), 0.5);
    }

    #[test]
    fn json_forms_parse_and_bad_forms_fail() {
        let a: Value = serde_json::from_str("0.5").unwrap();
        assert_eq!(a, Value::Grey(0.5));
        let b: Value = serde_json::from_str("[1,2,3]").unwrap();
        assert_eq!(b, Value::Rgb([1.0, 2.0, 3.0]));
        let c: Value = serde_json::from_str(r#"{"wavelengths":[400,500],"values":[1,2]}"#).unwrap();
        assert!(matches!(c, Value::Spectral { .. }));
        assert!(serde_json::from_str::<Value>("[1,2]").is_err());
        assert!(serde_json::from_str::<Value>("\"x\"").is_err());
        assert!(
            serde_json::from_str::<Value>(r#"{"wavelengths":[1],"values":[1],"z":1}"#).is_err()
        );
    }

    #[test]
    fn validation_names_the_field() {
        let e = Value::Grey(-1.0).validate("kd", 0.0).unwrap_err();
        assert!(e.to_string().contains("kd"), "{e}");
        assert!(Value::Grey(f64::NAN).validate("kd", 0.0).is_err());
        let bad = Value::Spectral {
            wavelengths: vec![500.0, 400.0],
            values: vec![1.0, 1.0],
        };
        assert!(bad.validate("k", 0.0).is_err());
    }
}
