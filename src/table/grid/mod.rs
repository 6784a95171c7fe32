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
use std::f64::consts::{FRAC_PI_2, PI, TAU};

use crate::error::{Error, Result};
use crate::spectrum::Channels;
use crate::table::calibration::Calibration;
pub use crate::table::param::Param;
use crate::table::symmetry::Symmetry;
pub use crate::table::warp::{Warp, WarpVar};

mod axis;
mod layout;
mod quantity;
#[cfg(test)]
mod tests;

pub use axis::{Axis, Mapping, Nodes, StoredAxis};
pub use layout::Layout;
pub use quantity::Quantity;

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

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct GridRepr {
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

impl Grid {
    /// A grid from its full axes `[θ1, φ1, θ2, φ2]` (see the table in the module docs).
    ///
    /// Requirements (checked): valid channels ([`Channels::validate`]: a grid of no channels
    /// made `Table::from_fn` panic); every size ≥ 1 and the grid at most 2^40 values; φ axes uniform
    /// with `cell_start` nodes; φ1 of size 1 only when isotropic (it then counts as φ2's size in
    /// [`Grid::full_values`]); folded φ axes need an even size (a multiple of 4 when
    /// `halfdiff` φd is folded by both reciprocity and bilateral symmetry); `inout` reciprocity
    /// needs identical θ axes (and equal φ sizes when anisotropic).
    pub fn new(
        param: Param,
        axes: [Axis; 4],
        channels: Channels,
        symmetry: Symmetry,
    ) -> Result<Grid> {
        channels.validate()?;
        let name = param.axis_names();
        for (k, a) in axes.iter().enumerate() {
            if a.size == 0 {
                return Err(Error::arg("grid", format!("axis {} has size 0", name[k])));
            }
            let warp_ok =
                k == 3 && param == Param::HalfDiff && symmetry.isotropic && symmetry.bilateral;
            if let Mapping::Warp(_) = a.mapping {
                let nodes_ok = match k % 2 {
                    0 => matches!(a.nodes, Nodes::Centers | Nodes::Edges),
                    _ => a.nodes == Nodes::Edges && warp_ok,
                };
                if !nodes_ok {
                    return Err(Error::arg(
                        "grid",
                        format!(
                            "a warped axis is a θ axis (centers or edges nodes) or the φd of an \
                             isotropic halfdiff table with bilateral symmetry (edges) ({})",
                            name[k]
                        ),
                    ));
                }
            } else if k % 2 == 1 && (a.mapping != Mapping::Uniform || a.nodes == Nodes::Centers) {
                return Err(Error::arg(
                    "grid",
                    format!(
                        "φ axis {} must be uniform with edges or cell_start nodes (periodic)",
                        name[k]
                    ),
                ));
            }
        }
        // The grid's size before anything is built from it (the layout holds a start per θ1
        // node): a hostile size in a file's header is this error, not an overflow, a panic or
        // an allocation of its size.
        let p1_full = if axes[1].size == 1 {
            axes[3].size
        } else {
            axes[1].size
        };
        let full = [
            axes[0].size,
            p1_full,
            axes[2].size,
            axes[3].size,
            channels.len(),
        ]
        .iter()
        .try_fold(1u64, |acc, &n| acc.checked_mul(n as u64));
        if full.is_none_or(|n| n > 1 << 40) {
            return Err(Error::arg("grid", "more than 2^40 values"));
        }
        let [t1, p1, t2, p2] = &axes;
        if p1.size == 1 && !symmetry.isotropic && p2.size > 1 {
            return Err(Error::arg(
                "grid",
                format!("{} of size 1 needs an isotropic table", name[1]),
            ));
        }
        let even = |n: usize, what: &str, m: usize| -> Result<()> {
            if !n.is_multiple_of(m) {
                Err(Error::arg(
                    "grid",
                    format!(
                        "{what} of size {n} must be a multiple of {m} to be folded by symmetry"
                    ),
                ))
            } else {
                Ok(())
            }
        };
        let (s, iso) = (symmetry, symmetry.isotropic);
        let stored = match param {
            Param::InOut => {
                let sp1 = if iso {
                    StoredAxis::single()
                } else if s.bilateral {
                    even(p1.size, name[1], 2)?;
                    StoredAxis::folded(p1.size / 2 + 1, PI, Mapping::Uniform)
                } else {
                    StoredAxis::periodic(p1.size, TAU, p1.nodes)
                };
                let sp2 = if iso && s.bilateral {
                    even(p2.size, name[3], 2)?;
                    StoredAxis::folded(p2.size / 2 + 1, PI, Mapping::Uniform)
                } else {
                    StoredAxis::periodic(p2.size, TAU, p2.nodes)
                };
                if s.reciprocal {
                    if t1 != t2 {
                        return Err(Error::arg(
                            "grid",
                            "inout reciprocity needs identical θi and θo axes",
                        ));
                    }
                    if !iso && p1.size != p2.size {
                        return Err(Error::arg(
                            "grid",
                            "anisotropic inout reciprocity needs equal φi and φo sizes",
                        ));
                    }
                }
                [StoredAxis::theta(t1), sp1, StoredAxis::theta(t2), sp2]
            }
            Param::HalfDiff => {
                let sp1 = if iso {
                    StoredAxis::single()
                } else if s.bilateral {
                    even(p1.size, name[1], 2)?;
                    StoredAxis::folded(p1.size / 2 + 1, PI, Mapping::Uniform)
                } else {
                    StoredAxis::periodic(p1.size, TAU, p1.nodes)
                };
                let sp2 = match (s.reciprocal, s.bilateral && iso) {
                    (true, true) => {
                        even(p2.size, name[3], 4)?;
                        StoredAxis::folded(p2.size / 4 + 1, FRAC_PI_2, p2.mapping.clone())
                    }
                    (true, false) => {
                        even(p2.size, name[3], 2)?;
                        StoredAxis::periodic(p2.size / 2, PI, p2.nodes)
                    }
                    (false, true) => {
                        even(p2.size, name[3], 2)?;
                        StoredAxis::folded(p2.size / 2 + 1, PI, p2.mapping.clone())
                    }
                    (false, false) => StoredAxis::periodic(p2.size, TAU, p2.nodes),
                };
                [StoredAxis::theta(t1), sp1, StoredAxis::theta(t2), sp2]
            }
        };
        let packed = param == Param::InOut && s.reciprocal;
        let layout = Layout::new(
            [
                stored[0].size,
                stored[1].size,
                stored[2].size,
                stored[3].size,
            ],
            packed,
            channels.len(),
        );
        let g = Grid {
            param,
            axes,
            channels,
            symmetry,
            quantity: Quantity::Fr,
            calibration: None,
            stored,
            layout,
        };
        Ok(g)
    }

    /// Convenience: θ axes of sizes `n_theta1`, `n_theta2` with the given mappings and
    /// [`Nodes::Centers`], φ axes of sizes `n_phi1`, `n_phi2`.
    pub fn with_sizes(
        param: Param,
        sizes: [usize; 4],
        mappings: [Mapping; 2],
        channels: Channels,
        symmetry: Symmetry,
    ) -> Result<Grid> {
        let [m1, m2] = mappings;
        Grid::new(
            param,
            [
                Axis::theta(sizes[0], m1, Nodes::Centers),
                Axis::phi(sizes[1]),
                Axis::theta(sizes[2], m2, Nodes::Centers),
                Axis::phi(sizes[3]),
            ],
            channels,
            symmetry,
        )
    }

    /// The MERL grid: `halfdiff`, θh 90 nodes with the square-root mapping, θd 90, φd 180 over
    /// [0, π) (full φd 360), all [`Nodes::CellStart`]; isotropic and reciprocal. Stored shape
    /// 90 × 1 × 90 × 180. A *nearest* lookup reproduces the MERL reader's indices.
    pub fn merl(channels: Channels) -> Grid {
        let sym = Symmetry {
            isotropic: true,
            reciprocal: true,
            bilateral: false,
        };
        Grid::new(
            Param::HalfDiff,
            [
                Axis::theta(90, Mapping::Sqrt, Nodes::CellStart),
                Axis::phi_cells(360),
                Axis::theta(90, Mapping::Uniform, Nodes::CellStart),
                Axis::phi_cells(360),
            ],
            channels,
            sym,
        )
        .expect("the MERL grid is valid")
    }

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
