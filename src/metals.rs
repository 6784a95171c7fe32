//! Named metals: spectral complex refractive indices n + kj from published measurements.

use crate::spectrum::Value;

/// Names of the metals [`metal`] knows.
pub const NAMES: &[&str] = &[];

/// The spectral (n, k) of a named metal, or `None`.
pub fn metal(_name: &str) -> Option<(Value, Value)> {
    None
}
