//! A parameter's bounds, the logistic map that keeps the optimizer unconstrained inside them,
//! and the table of default bounds per field.

use serde::Serialize;

use crate::error::{Error, Result};

/// How a bounded parameter is mapped to the optimizer's unconstrained variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scale {
    /// Logistic between `lo` and `hi`.
    Linear,
    /// Logistic between `ln lo` and `ln hi` (needs `lo > 0`).
    Log,
}

/// Closed bounds of one parameter and the scale in which it is fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bounds {
    /// Lower bound.
    pub lo: f64,
    /// Upper bound (> `lo`).
    pub hi: f64,
    /// Linear or log space.
    pub scale: Scale,
}

impl Bounds {
    /// Linear bounds `[lo, hi]`.
    pub const fn linear(lo: f64, hi: f64) -> Self {
        Bounds {
            lo,
            hi,
            scale: Scale::Linear,
        }
    }

    /// Bounds `[lo, hi]` fit in log space.
    pub const fn log(lo: f64, hi: f64) -> Self {
        Bounds {
            lo,
            hi,
            scale: Scale::Log,
        }
    }

    /// Checks `lo < hi`, finiteness, and `lo > 0` for log scale.
    pub fn validate(&self, path: &str) -> Result<()> {
        if !(self.lo.is_finite() && self.hi.is_finite() && self.lo < self.hi) {
            return Err(Error::arg(
                path,
                format!(
                    "bounds [{}, {}] must be finite with lo < hi",
                    self.lo, self.hi
                ),
            ));
        }
        if self.scale == Scale::Log && self.lo <= 0.0 {
            return Err(Error::arg(
                path,
                format!("log-space bounds need lo > 0, got {}", self.lo),
            ));
        }
        Ok(())
    }

    fn ends(&self) -> (f64, f64) {
        match self.scale {
            Scale::Linear => (self.lo, self.hi),
            Scale::Log => (self.lo.ln(), self.hi.ln()),
        }
    }

    /// The position `u ∈ [0, 1]` of `x` between the bounds (in the bound's scale), clamped.
    pub fn to_unit(&self, x: f64) -> f64 {
        let (a, b) = self.ends();
        let y = match self.scale {
            Scale::Linear => x,
            Scale::Log => x.max(self.lo).ln(),
        };
        ((y - a) / (b - a)).clamp(0.0, 1.0)
    }

    /// The value at unit position `u ∈ [0, 1]`. A value nearer 0 than a spec may hold
    /// ([`crate::spectrum::NUMBER_RANGE`]: 0 or a magnitude of at least 1e-12) is 0 where the
    /// bounds hold 0: a start heading for a lower bound of 0 (a Lambert term the source does not
    /// have) passed through such values, failed the spec's check and was dropped.
    pub fn from_unit(&self, u: f64) -> f64 {
        let (a, b) = self.ends();
        let y = a + (b - a) * u;
        let x = match self.scale {
            Scale::Linear => y,
            Scale::Log => y.exp(),
        };
        let x = x.clamp(self.lo, self.hi);
        let tiny = x != 0.0 && x.abs() < *crate::spectrum::NUMBER_RANGE.start();
        if tiny && (self.lo..=self.hi).contains(&0.0) {
            0.0
        } else {
            x
        }
    }

    /// Unconstrained variable → parameter value (always within the bounds).
    pub fn from_free(&self, t: f64) -> f64 {
        self.from_unit(logistic(t))
    }

    /// Parameter value → unconstrained variable; values at or beyond a bound are pulled inside
    /// by 1e-4 of the range so the start is not on a flat part of the logistic.
    pub fn to_free(&self, x: f64) -> f64 {
        let u = self.to_unit(x).clamp(1e-4, 1.0 - 1e-4);
        (u / (1.0 - u)).ln()
    }
}

fn logistic(t: f64) -> f64 {
    if t >= 0.0 {
        1.0 / (1.0 + (-t).exp())
    } else {
        let e = t.exp();
        e / (1.0 + e)
    }
}

/// True when the field `key` of model `model` holds a [`Value`](crate::Value) (grey, RGB or
/// spectral) rather than a plain number.
pub fn is_value_field(key: &str) -> bool {
    matches!(key, "kd" | "ks" | "eta" | "schlick")
}

/// The default bounds of field `key` in model `model`, or `None` when the field has no default
/// (it can still be fit with explicit bounds).
///
/// | field | models | bounds | scale |
/// |---|---|---|---|
/// | `kd` | lambert, oren_nayar | [0, 1.2/π] | linear |
/// | `ks` | cook_torrance, ggx, blinn_phong, ward | [0, 1.5] | linear |
/// | `ks` | phong, reciprocal_phong, max_phong, pumped_phong | [1e-3, 1e4] | log |
/// | `m`, `alpha`, `alpha_x`, `alpha_y` | microfacet, ward | [0.01, 1.5] | log |
/// | `n` | Phong family, blinn_phong | [1, 10000] | log |
/// | `sigma` | oren_nayar | [0, 1.5] rad | linear |
/// | `fresnel.schlick` (F0) | microfacet | [0, 1] | linear |
/// | `fresnel.eta` (dielectric) | microfacet | [1.01, 3] | linear |
///
/// `k_d ≤ 1.2/π` allows a little more than energy conservation (albedo 1.2) so that measured data
/// with calibration error is not clipped; `k_s` of the Phong family is the lobe's peak value, which
/// grows with n, hence log space.
pub fn default_bounds(model: &str, key: &str) -> Option<Bounds> {
    use std::f64::consts::PI;
    Some(match key {
        "kd" => Bounds::linear(0.0, 1.2 / PI),
        "ks" => match model {
            "phong" | "reciprocal_phong" | "max_phong" | "pumped_phong" => Bounds::log(1e-3, 1e4),
            _ => Bounds::linear(0.0, 1.5),
        },
        "m" | "alpha" | "alpha_x" | "alpha_y" => Bounds::log(0.01, 1.5),
        "n" => Bounds::log(1.0, 10000.0),
        "sigma" => Bounds::linear(0.0, 1.5),
        "schlick" => Bounds::linear(0.0, 1.0),
        "eta" if model != "refractor" => Bounds::linear(1.01, 3.0),
        _ => return None,
    })
}
