//! Grids: the five axes of a dense table, their mappings and node placement, and the stored
//! (symmetry-reduced) layout with its chunks.
//!
//! # Parameterizations
//!
//! A table has four angular axes and the channel (λ) axis:
//!
//! | [`Param`]    | axis 0 (`theta1`) | axis 1 (`phi1`) | axis 2 (`theta2`) | axis 3 (`phi2`) |
//! |--------------|-------------------|-----------------|-------------------|-----------------|
//! | `inout`      | θi                | φi              | θo                | φo (Δφ = φo − φi when isotropic) |
//! | `halfdiff`   | θh                | φh              | θd                | φd              |
//!
//! `inout` is the lecture's table; `halfdiff` is Rusinkiewicz's (MERL's) parameterization, see
//! [`crate::geometry::half_diff_vectors`].
//!
//! # Full axes and stored axes
//!
//! A [`Grid`] is described by its four *full* axes — the unreduced grid over the whole domain:
//! θ axes over [0, π/2], φ axes periodic over [0, 2π) — plus a [`Symmetry`]. The symmetry
//! determines the *stored* axes ([`Grid::stored_axes`]), which are what a table holds:
//!
//! - isotropy: φ1 is stored with size 1; in `inout` axis 3 holds Δφ = φo − φi;
//! - bilateral symmetry folds a φ axis onto [0, π] (or [0, π/2] together with reciprocity in
//!   `halfdiff`), stored with [`Nodes::Edges`] so that the folded nodes are exactly full nodes;
//! - reciprocity: `halfdiff` stores φd over the period [0, π); `inout` *packs* θ1 ≤ θ2 (only the
//!   upper triangle of the (θ1, θ2) plane is stored, see [`Layout`]).
//!
//! Full φ axes are periodic with node i at i·2π/N ([`Mapping::Uniform`]); their `nodes` field only
//! selects the *nearest* rule: [`Nodes::Edges`] (the default, [`Axis::phi`]) rounds,
//! [`Nodes::CellStart`] ([`Axis::phi_cells`], MERL) takes ⌊s⌋. Every symmetry maps full nodes onto
//! full nodes, so linear interpolation commutes with the reduction, and so does nearest lookup
//! with rounding (⌊s⌋ is not mirror-symmetric: bilateral folds of `cell_start` φ axes are
//! consistent for linear lookups only).
//!
//! # Node placement
//!
//! An axis maps a coordinate x in its domain [lo, hi] to u ∈ [0, 1] ([`Mapping`]: uniform,
//! square root, cosine, or a data-fitted [`Warp`] carried by the axis — see
//! [`crate::table::warp`]), then u to a fractional node index s ([`Nodes`]):
//!
//! - [`Nodes::Centers`]: node i at u = (i + ½)/n, s = u·n − ½. No node on the domain ends; lookups
//!   beyond the first/last node clamp. The default for θ axes: the horizon (where many models
//!   are singular) is never evaluated.
//! - [`Nodes::Edges`]: node i at u = i/(n − 1), s = u·(n − 1); both ends are nodes.
//! - [`Nodes::CellStart`]: the axis is cut into n cells [i/n, (i+1)/n) of u; node i stands for
//!   cell i and sits at its centre u = (i + ½)/n (baking samples there and linear interpolation
//!   runs between centres, so binned data such as MERL's are not shifted by half a cell), while a
//!   *nearest* lookup takes ⌊u·n⌋ (not the rounded index). This is MERL's convention:
//!   `int(sqrt(θh/(π/2))·90)`, `int(θd/(π/2)·90)`, `int(φd/π·180)`. The arithmetic is done in the
//!   same order as the MERL reader so a nearest lookup on [`Grid::merl`] reproduces its indices
//!   value for value (`sqrt(((θh/(π/2))·90)·90)`, `(θd/(π/2))·90`, `(φd/π)·180`, with φd + π when
//!   negative). One documented difference: φd = π exactly wraps to index 0 (it *is* φd = 0 by
//!   reciprocity) where the MERL reader clamps to 179; this is a measure-zero event.
//!
//! Linear interpolation is between neighbouring nodes in s on every node placement; on a
//! non-periodic axis s is clamped to [0, n − 1], on a periodic axis it wraps.
//!
//! # Chunks
//!
//! The stored values are a dense row-major array over (axis 0, axis 1, axis 2, axis 3, λ), λ
//! innermost. A *chunk* is the slab of one index of axis 0 (θi or θh): `chunk_count = n0`.
//! Chunks are the unit of baking, compression and lazy loading; [`Layout::chunk_range`] gives
//! each chunk's place in the value array. With packed `inout` reciprocity chunks differ in size
//! (chunk a holds θ2 indices a..n).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::spectrum::Channels;
use crate::table::calibration::Calibration;
pub use crate::table::param::Param;
use crate::table::symmetry::Symmetry;
pub use crate::table::warp::{Warp, WarpVar};

mod axis;
mod construct;
mod layout;
mod quantity;
mod repr;
#[cfg(test)]
mod tests;

pub use axis::{Axis, Mapping, Nodes, StoredAxis};
pub use layout::Layout;
pub use quantity::Quantity;
use repr::GridRepr;
pub(crate) use repr::json_sizes;

/// A dense table's grid: parameterization, four full angular axes, channels and the symmetry
/// reduction that decides what is stored. Serializable (it goes into file headers); built with
/// [`Grid::new`], which checks consistency.
///
/// ```
/// use brdftab::table::{Grid, Symmetry};
/// use brdftab::Channels;
/// let g = Grid::merl(Channels::Rgb);
/// assert_eq!(g.stored_shape(), [90, 1, 90, 180]);
/// assert_eq!(g.stored_values(), 90 * 90 * 180 * 3);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "GridRepr", into = "GridRepr")]
pub struct Grid {
    param: Param,
    axes: [Axis; 4],
    channels: Channels,
    symmetry: Symmetry,
    quantity: Quantity,
    calibration: Option<Calibration>,
    stored: [StoredAxis; 4],
    layout: Layout,
}

impl Grid {
    /// The parameterization.
    pub fn param(&self) -> Param {
        self.param
    }
    /// The full axes `[θ1, φ1, θ2, φ2]`.
    pub fn axes(&self) -> &[Axis; 4] {
        &self.axes
    }
    /// The channels (λ axis).
    pub fn channels(&self) -> &Channels {
        &self.channels
    }
    /// The symmetry reduction in force.
    pub fn symmetry(&self) -> Symmetry {
        self.symmetry
    }
    /// What the values are ([`Quantity::Fr`] unless set with [`Grid::with_quantity`]).
    pub fn quantity(&self) -> Quantity {
        self.quantity
    }
    /// The same grid storing `quantity`. An error for [`Quantity::FrCosOut`] on a grid folded
    /// by reciprocity (f_r cos θo differs between a pair and its swap).
    pub fn with_quantity(mut self, quantity: Quantity) -> Result<Grid> {
        if quantity == Quantity::FrCosOut && self.symmetry.reciprocal {
            return Err(Error::arg(
                "quantity",
                "f_r cos θo is not reciprocal: a grid storing it cannot fold by reciprocity",
            ));
        }
        self.quantity = quantity;
        Ok(self)
    }
    /// The albedo calibration the lookups apply, if any ([`Calibration`]).
    pub fn calibration(&self) -> Option<&Calibration> {
        self.calibration.as_ref()
    }
    /// The same grid with lookups multiplied by `calibration`'s k_in(θi) k_out(θo), one factor
    /// per channel. A grid folded by reciprocity takes only a symmetric calibration (k_out =
    /// k_in, [`Calibration::is_symmetric`]): other factors would break the reciprocity its
    /// fold assumes.
    pub fn with_calibration(mut self, calibration: Calibration) -> Result<Grid> {
        if self.symmetry.reciprocal && !calibration.is_symmetric() {
            return Err(Error::arg(
                "calibration",
                "a table folded by reciprocity takes only a symmetric albedo calibration \
                 (k_out = k_in)",
            ));
        }
        if calibration.channels() != self.channels.len() {
            return Err(Error::arg(
                "calibration",
                format!(
                    "{} factors per node for {} channels",
                    calibration.channels(),
                    self.channels.len()
                ),
            ));
        }
        self.calibration = Some(calibration);
        Ok(self)
    }
    fn with_optional_calibration(self, calibration: Option<Calibration>) -> Result<Grid> {
        match calibration {
            Some(c) => self.with_calibration(c),
            None => Ok(self),
        }
    }
    /// The same grid without a calibration: lookups return the interpolated values (divided by
    /// the stored quantity's cosines) without the albedo factors. For a caller that puts
    /// another material's values on this grid ([`Table::with_values`](super::Table::with_values)):
    /// the factors pinned the albedo of the source the grid was baked from, not theirs.
    pub fn without_calibration(mut self) -> Grid {
        self.calibration = None;
        self
    }
    /// The stored (reduced) axes.
    pub fn stored_axes(&self) -> &[StoredAxis; 4] {
        &self.stored
    }
    /// Sizes of the stored axes.
    pub fn stored_shape(&self) -> [usize; 4] {
        self.layout.shape
    }
    /// The stored layout and chunks.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }
    /// Number of stored values (stored nodes × channels).
    pub fn stored_values(&self) -> usize {
        self.layout.len()
    }
    /// Number of values of the unreduced grid (full axes × channels).
    pub fn full_values(&self) -> u64 {
        let a = &self.axes;
        let p1 = if a[1].size == 1 { a[3].size } else { a[1].size };
        (a[0].size * p1) as u64 * (a[2].size * a[3].size) as u64 * self.channels.len() as u64
    }

    /// The same grid with another symmetry reduction.
    pub fn with_symmetry(&self, symmetry: Symmetry) -> Result<Grid> {
        Grid::new(
            self.param,
            self.axes.clone(),
            self.channels.clone(),
            symmetry,
        )
        .and_then(|g| g.with_quantity(self.quantity))
        .and_then(|g| g.with_optional_calibration(self.calibration.clone()))
    }

    /// The same grid with other channels.
    pub fn with_channels(&self, channels: Channels) -> Result<Grid> {
        // A calibration is per channel: it does not carry over to other channels.
        Grid::new(self.param, self.axes.clone(), channels, self.symmetry)
            .and_then(|g| g.with_quantity(self.quantity))
    }

    /// The angles of stored node `idx` (in the stored domains; for isotropic `inout`, axis 3 is
    /// Δφ and axis 1 is 0).
    pub fn node_angles(&self, idx: [usize; 4]) -> [f64; 4] {
        [
            self.stored[0].node(idx[0]),
            self.stored[1].node(idx[1]),
            self.stored[2].node(idx[2]),
            self.stored[3].node(idx[3]),
        ]
    }

    /// The angles of every stored node ([`Grid::node_angles`]) in the stored order
    /// ([`Layout::stored_nodes`]): node k's values are `k·c..(k + 1)·c` of the table's values.
    pub fn stored_node_angles(&self) -> Vec<[f64; 4]> {
        self.layout
            .stored_nodes()
            .map(|idx| self.node_angles(idx))
            .collect()
    }

    /// A one-line human description, e.g. `halfdiff 90x1x90x180 (sqrt θh) rgb isotropic+reciprocal`.
    pub fn summary(&self) -> String {
        let s = self.stored_shape();
        format!(
            "{} full {}x{}x{}x{} stored {}x{}x{}x{} x{} ch, θ1 {}/{:?}, θ2 {}/{:?}, symmetry {}",
            self.param.name(),
            self.axes[0].size,
            self.axes[1].size,
            self.axes[2].size,
            self.axes[3].size,
            s[0],
            s[1],
            s[2],
            s[3],
            self.channels.len(),
            self.axes[0].mapping.label(),
            self.axes[0].nodes,
            self.axes[2].mapping.label(),
            self.axes[2].nodes,
            self.symmetry,
        ) + &match &self.axes[3].mapping {
            Mapping::Warp(_) => format!(", φ2 {}", self.axes[3].mapping.label()),
            _ => String::new(),
        } + &match self.quantity {
            Quantity::Fr => String::new(),
            q => format!(", stores {}", q.label()),
        } + &match &self.calibration {
            Some(c) => {
                let (lo, hi) = c.range();
                let kind = if c.is_symmetric() {
                    "k(θi) k(θo), symmetric"
                } else {
                    "k_in(θi) k_out(θo)"
                };
                format!(
                    ", albedo calibrated ({kind}, {} nodes, factors {lo:.3}–{hi:.3})",
                    c.nodes()
                )
            }
            None => String::new(),
        }
    }
}
