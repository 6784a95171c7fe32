//! The interpolation a lookup uses (nearest or multilinear), the default a grid is read with,
//! and its name as hosts pass it.

use serde::{Deserialize, Serialize};

use crate::table::grid::Grid;

/// The interpolation of a table lookup.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, Hash)]
#[serde(rename_all = "snake_case")]
pub enum Interp {
    /// The nearest node (⌊s⌋ on [`Nodes::CellStart`](crate::table::Nodes) axes, as MERL).
    Nearest,
    /// Multilinear over the stored angular axes.
    #[default]
    Linear,
}

impl Interp {
    /// The interpolation a table on `grid` is read with unless told otherwise: nearest when an
    /// axis holds cells rather than nodes ([`crate::table::Nodes::CellStart`], the MERL grid: a MERL
    /// reader looks such values up by cell, so nearest reproduces the source), linear otherwise.
    pub fn default_for(grid: &Grid) -> Interp {
        if grid
            .axes()
            .iter()
            .any(|a| a.nodes == crate::table::grid::Nodes::CellStart)
        {
            Interp::Nearest
        } else {
            Interp::Linear
        }
    }
}

impl std::str::FromStr for Interp {
    type Err = crate::Error;

    /// Parses `nearest` or `linear`.
    fn from_str(s: &str) -> std::result::Result<Self, crate::Error> {
        match s.trim().to_ascii_lowercase().as_str() {
            "nearest" => Ok(Interp::Nearest),
            "linear" => Ok(Interp::Linear),
            o => Err(crate::Error::arg(
                "interp",
                format!("`{o}`: expected nearest or linear"),
            )),
        }
    }
}
