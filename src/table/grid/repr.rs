//! A [`Grid`]'s serialized form (file headers): the axes by name, built back through
//! [`Grid::new`]'s checks; and [`json_sizes`], the sizes a reader bounds before it builds one.

use serde::{Deserialize, Serialize};

use super::{Axis, Grid, Param, Quantity};
use crate::error::{Error, Result};
use crate::spectrum::Channels;
use crate::table::calibration::Calibration;
use crate::table::symmetry::Symmetry;

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct GridRepr {
    param: Param,
    theta1: Axis,
    phi1: Axis,
    theta2: Axis,
    phi2: Axis,
    channels: Channels,
    symmetry: Symmetry,
    #[serde(default, skip_serializing_if = "Quantity::is_fr")]
    quantity: Quantity,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    calibration: Option<Calibration>,
}

impl TryFrom<GridRepr> for Grid {
    type Error = Error;
    fn try_from(r: GridRepr) -> Result<Grid> {
        Grid::new(
            r.param,
            [r.theta1, r.phi1, r.theta2, r.phi2],
            r.channels,
            r.symmetry,
        )?
        .with_quantity(r.quantity)?
        .with_optional_calibration(r.calibration)
    }
}

impl From<Grid> for GridRepr {
    fn from(g: Grid) -> GridRepr {
        GridRepr {
            param: g.param,
            theta1: g.axes[0].clone(),
            phi1: g.axes[1].clone(),
            theta2: g.axes[2].clone(),
            phi2: g.axes[3].clone(),
            channels: g.channels,
            symmetry: g.symmetry,
            quantity: g.quantity,
            calibration: g.calibration,
        }
    }
}

/// Every `size` in a grid's JSON, at any depth (`u64::MAX` for one that is not a number): what
/// a reader bounds by the values its file holds before it builds the grid
/// ([`Grid::new`] holds one offset per θ1 node, so a size is an allocation).
pub(crate) fn json_sizes(v: &serde_json::Value) -> Vec<u64> {
    fn walk(v: &serde_json::Value, out: &mut Vec<u64>) {
        match v {
            serde_json::Value::Object(m) => {
                for (k, x) in m {
                    if k == "size" {
                        out.push(x.as_u64().unwrap_or(u64::MAX));
                    }
                    walk(x, out);
                }
            }
            serde_json::Value::Array(a) => a.iter().for_each(|x| walk(x, out)),
            _ => {}
        }
    }
    let mut out = Vec::new();
    walk(v, &mut out);
    out
}
