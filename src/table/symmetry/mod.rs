//! Symmetry reduction: isotropy, bilateral symmetry and Helmholtz reciprocity.
//!
//! Each symmetry is a map from any direction pair (wi, wo) to *canonical* coordinates in the
//! stored domains of a [`Grid`](super::Grid) ([`canonical_coords`]); a reduced table stores only
//! canonical nodes. The maps:
//!
//! | symmetry    | `inout`                                          | `halfdiff`                        |
//! |-------------|--------------------------------------------------|-----------------------------------|
//! | isotropic   | (θi, θo, Δφ = φo − φi), φi dropped               | φh dropped                        |
//! | bilateral   | Δφ → \|Δφ\| ∈ [0, π] (anisotropic: φi, φo → −φi, −φo when φi > π) | φd → −φd (anisotropic: (φh, φd) → (−φh, −φd) when φh < 0) |
//! | reciprocal  | swap so θ1 ≤ θ2 (Δφ → −Δφ), upper-triangle packing | φd ≡ φd + π: φd ∈ [0, π)         |
//!
//! Because full φ nodes sit at i·2π/N and folded axes keep exactly those nodes, every map sends
//! nodes to nodes and cells to cells, so interpolating a reduced table gives the same value as
//! interpolating the full table of a symmetric source. The one place where a cell crosses the
//! stored region is the diagonal θ1 = θ2 of packed `inout` reciprocity; lookups canonicalize
//! those corners individually ([`canonical_corner_inout`]).
//!
//! A symmetry is *declared* (from [`Flags`](crate::Flags) or by the user) or *detected*
//! ([`detect`]) and always *verified* ([`verify`]) before a reduced table is baked: a source
//! breaking a declared symmetry beyond tolerance gives [`Error::Symmetry`] unless forced.

use serde::{Deserialize, Serialize};
use std::fmt;

use crate::error::Error;
pub use crate::error::SymmetryKind;

mod check;
mod coords;
#[cfg(test)]
mod tests;

pub use check::{CHECK_PAIRS, DEFAULT_TOLERANCE, detect, sampled_violation, verify, violation};
pub use coords::{
    canonical_coords, canonical_coords_fast, canonical_corner_inout, canonical_half_diff,
    fast_acos, fast_atan2,
};

/// Which symmetries a table exploits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, Hash)]
#[serde(default, deny_unknown_fields)]
pub struct Symmetry {
    /// Invariance under a common rotation about the normal.
    pub isotropic: bool,
    /// Helmholtz reciprocity f(wi, wo) = f(wo, wi).
    pub reciprocal: bool,
    /// Mirror symmetry through the x–z plane (for isotropic sources: Δφ → −Δφ).
    pub bilateral: bool,
}

impl Symmetry {
    /// No reduction.
    pub const NONE: Symmetry = Symmetry {
        isotropic: false,
        reciprocal: false,
        bilateral: false,
    };
    /// All three.
    pub const ALL: Symmetry = Symmetry {
        isotropic: true,
        reciprocal: true,
        bilateral: true,
    };

    /// The symmetries a model declares in its flags.
    pub fn from_flags(f: crate::Flags) -> Symmetry {
        Symmetry {
            isotropic: f.isotropic,
            reciprocal: f.reciprocal,
            bilateral: f.bilateral,
        }
    }

    /// The symmetries present in both.
    pub fn intersect(self, o: Symmetry) -> Symmetry {
        Symmetry {
            isotropic: self.isotropic && o.isotropic,
            reciprocal: self.reciprocal && o.reciprocal,
            bilateral: self.bilateral && o.bilateral,
        }
    }
}

impl std::str::FromStr for Symmetry {
    type Err = crate::Error;

    /// Parses a comma-separated list: `isotropic,reciprocal,bilateral` (also `iso`, `recip`,
    /// `bilat`), `none` or `all`.
    fn from_str(s: &str) -> std::result::Result<Self, crate::Error> {
        let mut out = Symmetry::NONE;
        for w in s.split(',').map(|w| w.trim().to_ascii_lowercase()) {
            match w.as_str() {
                "" | "none" => {}
                "all" => out = Symmetry::ALL,
                "isotropic" | "iso" | "isotropy" => out.isotropic = true,
                "reciprocal" | "recip" | "reciprocity" => out.reciprocal = true,
                "bilateral" | "bilat" => out.bilateral = true,
                other => {
                    return Err(Error::arg(
                        "symmetry",
                        format!(
                            "`{other}`: expected auto, none, all or a list of isotropic, reciprocal, bilateral"
                        ),
                    ));
                }
            }
        }
        Ok(out)
    }
}

impl fmt::Display for Symmetry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut v = Vec::new();
        if self.isotropic {
            v.push("isotropic");
        }
        if self.reciprocal {
            v.push("reciprocal");
        }
        if self.bilateral {
            v.push("bilateral");
        }
        if v.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&v.join("+"))
        }
    }
}
