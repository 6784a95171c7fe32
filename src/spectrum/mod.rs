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

mod channels;
mod value;

pub use channels::{ChannelMix, Channels};
pub(crate) use value::check_range;
pub use value::{NUMBER_RANGE, Value};

/// Representative wavelengths (nm) of the R, G and B channels, used to convert between RGB and
/// spectral data (red 645 nm, green 526 nm, blue 444 nm).
pub const RGB_WAVELENGTHS: [f64; 3] = [645.0, 526.0, 444.0];

/// The most channels a channel set may have (keeps stack buffers possible for callers).
pub const MAX_CHANNELS: usize = 64;

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

#[cfg(test)]
mod tests;
