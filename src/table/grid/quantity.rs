//! What a table's values are ([`Quantity`]): f_r, or f_r times the cosines that keep it bounded
//! at the horizon.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// What a table's values are. A lookup always returns f_r; the quantity says what was
/// interpolated to get it.
///
/// Measured reflectance is stored as f_r · cos θo (an RGL file) or f_r (MERL) and near the horizon
/// grows like 1/cos θ: a piecewise-linear interpolant of f_r between a node at cos θ = 0.1 and
/// one at 0.02 is off by 80 % halfway, and a node beyond the horizon (baked at a direction
/// lifted to z = [`HORIZON_Z`](crate::table::HORIZON_Z)) carries hundreds of times the value at 88°
/// into the cells next to it. f_r cos θi cos θo is bounded and smooth there, and it is also
/// what the light transport integrates, so an interpolation error in it is an error of the same
/// size in the rendered radiance — at every angle, up to the horizon.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// f_r itself (analytic models; MERL cells copied verbatim).
    #[default]
    Fr,
    /// f_r cos θi cos θo: the lookup divides by the two cosines of the pair.
    FrCosCos,
    /// f_r cos θo, what an RGL file stores: bounded where measured f_r grows like 1/cos θo,
    /// and — unlike f_r cos θi cos θo — not vanishing as wi nears the horizon, so the albedo
    /// a(θ′) = ∫ f_r cos θo dωo, the integral of this quantity, stays accurate at θ′ = 89°. Not
    /// symmetric in the two directions: a table of it cannot fold by reciprocity.
    FrCosOut,
}

impl Quantity {
    /// True for [`Quantity::Fr`] (which the file header leaves out).
    pub fn is_fr(&self) -> bool {
        *self == Quantity::Fr
    }

    /// The name used in headers and summaries: `fr`, `fr_cos_cos` or `fr_cos_out`.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Fr => "fr",
            Quantity::FrCosCos => "fr_cos_cos",
            Quantity::FrCosOut => "fr_cos_out",
        }
    }

    /// The quantity of a [`Quantity::name`].
    ///
    /// ```
    /// use brdftab::table::Quantity;
    /// assert_eq!(Quantity::from_name("fr_cos_cos"), Some(Quantity::FrCosCos));
    /// assert_eq!(Quantity::from_name("cos"), None);
    /// ```
    pub fn from_name(name: &str) -> Option<Quantity> {
        [Quantity::Fr, Quantity::FrCosCos, Quantity::FrCosOut]
            .into_iter()
            .find(|q| q.name() == name)
    }

    /// The factor of f_r in this quantity for a pair with cosines `cos_i`, `cos_o`.
    #[inline(always)]
    pub fn factor(self, cos_i: f64, cos_o: f64) -> f64 {
        match self {
            Quantity::Fr => 1.0,
            Quantity::FrCosCos => cos_i * cos_o,
            Quantity::FrCosOut => cos_o,
        }
    }

    /// A one-line description: `f_r`, `f_r cos θi cos θo`, `f_r cos θo`.
    pub fn label(self) -> &'static str {
        match self {
            Quantity::Fr => "f_r",
            Quantity::FrCosCos => "f_r cos θi cos θo",
            Quantity::FrCosOut => "f_r cos θo",
        }
    }
}

/// `"fr_cos_cos".parse::<Quantity>()`: [`Quantity::from_name`], an unknown name an argument
/// error naming `quantity`.
impl std::str::FromStr for Quantity {
    type Err = Error;

    fn from_str(s: &str) -> Result<Quantity> {
        Quantity::from_name(s.trim()).ok_or_else(|| {
            Error::arg(
                "quantity",
                format!("unknown quantity `{s}` (expected fr, fr_cos_cos or fr_cos_out)"),
            )
        })
    }
}
