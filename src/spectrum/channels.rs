//! The channel set ([`Channels`]): its checks, its parsing, and the mix of channel data at a
//! wavelength ([`ChannelMix`]) that lookups at wavelengths use.

use serde::{Deserialize, Serialize};

use super::{MAX_CHANNELS, RGB_WAVELENGTHS, is_wavelength, lerp_sorted};
use crate::error::{Error, Result};

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
