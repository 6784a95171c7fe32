//! The angular parameterization of a table: which four angles its axes are.
//!
//! A room of its own (below both [`grid`](super::grid) and [`symmetry`](super::symmetry)), so
//! that the grid can name its symmetry and the symmetry its parameterization without a cycle.

use serde::{Deserialize, Serialize};

use crate::error::Error;

/// The angular parameterization of a table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, Hash)]
pub enum Param {
    /// (θi, φi, θo, φo): incident and outgoing spherical angles (the lecture's table).
    #[serde(rename = "inout")]
    InOut,
    /// (θh, φh, θd, φd): Rusinkiewicz half/difference angles (MERL).
    #[default]
    #[serde(rename = "halfdiff")]
    HalfDiff,
}

impl Param {
    /// Names of the four angular axes.
    pub fn axis_names(self) -> [&'static str; 4] {
        match self {
            Param::InOut => ["theta_i", "phi_i", "theta_o", "phi_o"],
            Param::HalfDiff => ["theta_h", "phi_h", "theta_d", "phi_d"],
        }
    }

    /// `inout` or `halfdiff`: the name [`str::parse`] reads and tables store.
    pub fn name(self) -> &'static str {
        match self {
            Param::InOut => "inout",
            Param::HalfDiff => "halfdiff",
        }
    }
}

impl std::str::FromStr for Param {
    type Err = crate::Error;

    /// Parses `inout` or `halfdiff`.
    fn from_str(s: &str) -> std::result::Result<Self, crate::Error> {
        match s.trim().to_ascii_lowercase().as_str() {
            "inout" | "in_out" => Ok(Param::InOut),
            "halfdiff" | "half_diff" => Ok(Param::HalfDiff),
            other => Err(Error::arg(
                "param",
                format!("`{other}`: expected inout or halfdiff"),
            )),
        }
    }
}

impl std::fmt::Display for Param {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
