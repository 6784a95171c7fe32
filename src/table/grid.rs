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
use std::ops::Range;

use crate::error::{Error, Result};
use crate::spectrum::Channels;
use crate::table::calibration::Calibration;
pub use crate::table::param::Param;
use crate::table::symmetry::Symmetry;
pub use crate::table::warp::{Warp, WarpVar};

/// How an axis's coordinate x ∈ [lo, hi] maps to u ∈ [0, 1] before node placement.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Default, Hash)]
#[serde(rename_all = "snake_case")]
pub enum Mapping {
    /// u = (x − lo)/(hi − lo).
    #[default]
    Uniform,
    /// u = sqrt((x − lo)/(hi − lo)): MERL's θh mapping, dense near the specular peak θh = 0.
    Sqrt,
    /// Uniform in cos θ: u = (cos lo − cos x)/(cos lo − cos hi) (θ axes; dense near the horizon
    /// in θ, uniform in projected solid angle for the polar part).
    Cos,
    /// A data-adaptive warp ([`Warp`]): θ axes ([`Nodes::Centers`] or [`Nodes::Edges`]), and φd
    /// of an isotropic `halfdiff` table folded by bilateral symmetry ([`Nodes::Edges`]).
    Warp(Warp),
}

impl Mapping {
    /// A short name for summaries: `Uniform`, `Sqrt`, `Cos`, `Warp(SqrtSine, 129 knots)`.
    pub fn label(&self) -> String {
        match self {
            Mapping::Warp(w) => format!("Warp({:?}, {} knots)", w.var(), w.knots().len()),
            m => format!("{m:?}"),
        }
    }
}

/// Where the nodes of an axis sit (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, Hash)]
#[serde(rename_all = "snake_case")]
pub enum Nodes {
    /// Node i at u = (i + ½)/n (cell centres); the domain ends are not nodes.
    #[default]
    Centers,
    /// Node i at u = i/(n − 1); both domain ends are nodes.
    Edges,
    /// Node i at u = i/n and stands for the cell [i/n, (i+1)/n): nearest = floor (MERL).
    CellStart,
}

/// One full (unreduced) angular axis: its size, mapping and node placement. The domain follows
/// from the axis's role: θ axes [0, π/2], φ axes periodic [0, 2π).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, Hash)]
pub struct Axis {
    /// Number of nodes (≥ 1).
    pub size: usize,
    /// Coordinate → [0, 1] mapping (θ axes only; φ axes are uniform).
    #[serde(default)]
    pub mapping: Mapping,
    /// Node placement (θ axes; φ axes are always `cell_start`).
    #[serde(default)]
    pub nodes: Nodes,
}

impl Axis {
    /// A θ axis with `size` nodes.
    pub fn theta(size: usize, mapping: Mapping, nodes: Nodes) -> Self {
        Axis {
            size,
            mapping,
            nodes,
        }
    }

    /// A periodic φ axis over [0, 2π) with node i at i·2π/size; nearest lookups round.
    pub fn phi(size: usize) -> Self {
        Axis {
            size,
            mapping: Mapping::Uniform,
            nodes: Nodes::Edges,
        }
    }

    /// A periodic φ axis like [`Axis::phi`] whose nearest lookups take ⌊s⌋ (MERL's φd).
    pub fn phi_cells(size: usize) -> Self {
        Axis {
            size,
            mapping: Mapping::Uniform,
            nodes: Nodes::CellStart,
        }
    }
}

/// A stored axis: domain, size, mapping, node placement and periodicity — everything lookups
/// need. Derived from a [`Grid`] by [`Grid::stored_axes`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StoredAxis {
    /// Number of stored nodes.
    pub size: usize,
    /// Lower end of the domain (radians).
    pub lo: f64,
    /// Upper end of the domain (for a periodic axis, lo + period).
    pub hi: f64,
    /// Coordinate mapping.
    pub mapping: Mapping,
    /// Node placement.
    pub nodes: Nodes,
    /// Whether the axis wraps around (φ axes that are not folded).
    pub periodic: bool,
    /// 1 / (hi − lo) (0 for a single node), so that linear lookups multiply instead of divide.
    #[serde(skip)]
    inv_range: f64,
    /// 1 / (cos lo − cos hi) for [`Mapping::Cos`] axes (θ axes only, lo = 0).
    #[serde(skip)]
    inv_cos_range: f64,
}

impl StoredAxis {
    fn theta(a: &Axis) -> Self {
        StoredAxis {
            size: a.size,
            lo: 0.0,
            hi: FRAC_PI_2,
            mapping: a.mapping.clone(),
            nodes: a.nodes,
            periodic: false,
            inv_range: 1.0 / FRAC_PI_2,
            inv_cos_range: 1.0 / (1.0 - FRAC_PI_2.cos()),
        }
    }

    fn periodic(size: usize, period: f64, nodes: Nodes) -> Self {
        StoredAxis {
            size,
            lo: 0.0,
            hi: period,
            mapping: Mapping::Uniform,
            nodes,
            periodic: true,
            inv_range: 1.0 / period,
            inv_cos_range: 0.0,
        }
    }

    fn folded(size: usize, hi: f64, mapping: Mapping) -> Self {
        StoredAxis {
            size,
            lo: 0.0,
            hi,
            mapping,
            nodes: Nodes::Edges,
            periodic: false,
            inv_range: 1.0 / hi,
            inv_cos_range: 0.0,
        }
    }

    fn single() -> Self {
        StoredAxis {
            size: 1,
            lo: 0.0,
            hi: 0.0,
            mapping: Mapping::Uniform,
            nodes: Nodes::Edges,
            periodic: false,
            inv_range: 0.0,
            inv_cos_range: 0.0,
        }
    }

    /// The fractional node index s of coordinate `x` (not clamped or wrapped).
    ///
    /// On [`Nodes::CellStart`] axes node i is the centre of cell [i, i+1) — a binned measurement
    /// stands for its cell, and baking samples the centre — so s is the cell coordinate − ½;
    /// [`StoredAxis::nearest`] still floors the unshifted cell coordinate, exactly as MERL.
    #[inline(always)]
    pub fn continuous(&self, x: f64) -> f64 {
        self.continuous_impl::<true>(x)
    }

    /// [`StoredAxis::continuous`], exact (`EXACT`: divides by the range as MERL does, for
    /// nearest lookups whose cell boundaries must match) or multiplying by the precomputed
    /// reciprocal (a rounding-level difference; for linear lookups).
    #[inline(always)]
    fn continuous_impl<const EXACT: bool>(&self, x: f64) -> f64 {
        let c = self.cell_coordinate::<EXACT>(x);
        if self.nodes == Nodes::CellStart && self.size > 1 {
            c - 0.5
        } else {
            c
        }
    }

    /// The position of `x` in units of cells (node spacing), before the half-cell shift of
    /// [`Nodes::CellStart`] axes; for those it is the MERL index before truncation.
    #[inline(always)]
    fn cell_coordinate<const EXACT: bool>(&self, x: f64) -> f64 {
        if self.size <= 1 {
            return 0.0;
        }
        let n = self.size as f64;
        let r = if EXACT {
            (x - self.lo) / (self.hi - self.lo)
        } else {
            (x - self.lo) * self.inv_range
        };
        if self.periodic {
            // Node i at i/n of the period on every periodic axis.
            return r * n;
        }
        match (&self.mapping, self.nodes) {
            // MERL arithmetic order: sqrt(((θ/(π/2))·n)·n).
            (Mapping::Sqrt, Nodes::CellStart) => (r * n * n).max(0.0).sqrt(),
            (Mapping::Uniform, Nodes::CellStart) => r * n,
            (m, nodes) => {
                let u = match m {
                    Mapping::Uniform => r,
                    Mapping::Sqrt => r.max(0.0).sqrt(),
                    Mapping::Cos if EXACT => {
                        let (cl, ch) = (self.lo.cos(), self.hi.cos());
                        (cl - x.cos()) / (cl - ch)
                    }
                    Mapping::Cos => {
                        // Polynomial cosine (|error| ≤ 2e-15) instead of three libm calls; θ axes
                        // start at lo = 0, cos lo = 1.
                        let c =
                            crate::fastmath::sin_cos_2pi(x * (0.5 * std::f64::consts::FRAC_1_PI)).1;
                        (1.0 - c) * self.inv_cos_range
                    }
                    Mapping::Warp(w) => w.u_of_angle(x, self.hi),
                };
                match nodes {
                    Nodes::Centers => u * n - 0.5,
                    Nodes::Edges => u * (n - 1.0),
                    Nodes::CellStart => u * n,
                }
            }
        }
    }

    /// The coordinate at fractional node index `s` (inverse of [`StoredAxis::continuous`]).
    pub fn coord(&self, s: f64) -> f64 {
        if self.size <= 1 {
            return self.lo;
        }
        let n = self.size as f64;
        if self.periodic {
            let s = if self.nodes == Nodes::CellStart {
                s + 0.5
            } else {
                s
            };
            return self.lo + s / n * (self.hi - self.lo);
        }
        let u = match self.nodes {
            Nodes::Centers | Nodes::CellStart => (s + 0.5) / n,
            Nodes::Edges => s / (n - 1.0),
        };
        let r = match &self.mapping {
            Mapping::Uniform => u,
            Mapping::Sqrt => u * u,
            Mapping::Warp(w) => return w.angle_of_u(u, self.hi),
            Mapping::Cos => {
                let (cl, ch) = (self.lo.cos(), self.hi.cos());
                let c = (cl - u * (cl - ch)).clamp(-1.0, 1.0);
                return c.acos();
            }
        };
        self.lo + r * (self.hi - self.lo)
    }

    /// The coordinate of node `i`.
    pub fn node(&self, i: usize) -> f64 {
        self.coord(i as f64)
    }

    /// The node a *nearest* lookup of `x` uses: ⌊s⌋ for [`Nodes::CellStart`], the rounded s
    /// otherwise; clamped (or wrapped when periodic) into 0..size.
    #[inline]
    pub fn nearest(&self, x: f64) -> usize {
        let i = if self.nodes == Nodes::CellStart {
            crate::fastmath::floor(self.cell_coordinate::<true>(x))
        } else {
            crate::fastmath::floor(self.continuous(x) + 0.5)
        };
        self.index(i)
    }

    #[inline]
    fn index(&self, i: f64) -> usize {
        let n = self.size;
        if self.periodic {
            let k = if i.is_finite() { i as i64 } else { 0 };
            k.rem_euclid(n as i64) as usize
        } else if i.is_nan() || i <= 0.0 {
            0
        } else {
            (i as usize).min(n - 1)
        }
    }

    /// The two nodes and the weight of the second for linear interpolation at `x`:
    /// `value = (1 − t)·v[i0] + t·v[i1]`.
    #[inline(always)]
    pub fn linear(&self, x: f64) -> (usize, usize, f32) {
        let n = self.size;
        if n <= 1 {
            return (0, 0, 0.0);
        }
        let s = self.continuous_impl::<false>(x);
        if self.periodic {
            if !s.is_finite() {
                return (0, 1, 0.0);
            }
            // floor without a libm call (s is usually in [0, n]).
            let mut i = s as i64;
            if (i as f64) > s {
                i -= 1;
            }
            let t = (s - i as f64) as f32;
            let ni = n as i64;
            let i0 = if (0..ni).contains(&i) {
                i
            } else if (ni..2 * ni).contains(&i) {
                i - ni
            } else {
                i.rem_euclid(ni)
            } as usize;
            let i1 = if i0 + 1 == n { 0 } else { i0 + 1 };
            (i0, i1, t)
        } else {
            // NaN → 0; clamp to [0, n − 1]; `as usize` truncates (= floor for s ≥ 0).
            let s = if s > 0.0 { s.min((n - 1) as f64) } else { 0.0 };
            let i0 = (s as usize).min(n - 2);
            (i0, i0 + 1, (s - i0 as f64) as f32)
        }
    }
}

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

/// What a table's values are. A lookup always returns f_r; the quantity says what was
/// interpolated to get it.
///
/// Measured reflectance is stored as f_r · cos θo (an RGL file) or f_r (MERL) and near the horizon
/// grows like 1/cos θ: a piecewise-linear interpolant of f_r between a node at cos θ = 0.1 and
/// one at 0.02 is off by 80 % halfway, and a node beyond the horizon (baked at a direction
/// lifted to z = [`HORIZON_Z`](super::HORIZON_Z)) carries hundreds of times the value at 88°
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

/// The stored layout: a row-major array over the four stored axes and λ (innermost), split into
/// chunks = slabs of axis 0. With `packed` (inout reciprocity) only θ2 ≥ θ1 is stored: chunk a
/// holds axis-2 indices a..n, so its size is (n − a)·s1·s3·c.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Layout {
    /// Stored axis sizes.
    pub shape: [usize; 4],
    /// Upper-triangle packing of (axis 0, axis 2).
    pub packed: bool,
    /// Number of channels (values per node).
    pub channels: usize,
    /// Start offset (in values) of each chunk, plus the total at the end.
    chunk_starts: Vec<usize>,
}

impl Layout {
    fn new(shape: [usize; 4], packed: bool, channels: usize) -> Layout {
        let [n0, s1, n2, s3] = shape;
        let mut starts = Vec::with_capacity(n0 + 1);
        let mut acc = 0usize;
        for a in 0..n0 {
            starts.push(acc);
            let rows = if packed { n2.saturating_sub(a) } else { n2 };
            acc += s1 * rows * s3 * channels;
        }
        starts.push(acc);
        Layout {
            shape,
            packed,
            channels,
            chunk_starts: starts,
        }
    }

    /// Total number of stored values.
    pub fn len(&self) -> usize {
        *self.chunk_starts.last().unwrap_or(&0)
    }

    /// True when nothing is stored (never for a valid grid).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of chunks (= size of stored axis 0).
    pub fn chunk_count(&self) -> usize {
        self.shape[0]
    }

    /// The value range of chunk `i` in the whole array.
    pub fn chunk_range(&self, i: usize) -> Range<usize> {
        self.chunk_starts[i]..self.chunk_starts[i + 1]
    }

    /// Number of values in chunk `i`.
    pub fn chunk_len(&self, i: usize) -> usize {
        self.chunk_starts[i + 1] - self.chunk_starts[i]
    }

    /// Number of axis-2 indices stored in chunk `a` and the first one.
    #[inline]
    pub fn rows2(&self, a: usize) -> (usize, usize) {
        if self.packed {
            (a, self.shape[2] - a)
        } else {
            (0, self.shape[2])
        }
    }

    /// Offset of node `[a, p, b, q]` (its channel 0) inside chunk `a`, or `None` when the node
    /// is not stored (out of range, or b < a when packed).
    #[inline]
    pub fn offset_in_chunk(&self, idx: [usize; 4]) -> Option<usize> {
        let [a, p, b, q] = idx;
        let [n0, s1, _, s3] = self.shape;
        let (b0, nb) = self.rows2(a.min(n0.saturating_sub(1)));
        if a >= n0 || p >= s1 || b < b0 || b - b0 >= nb || q >= s3 {
            return None;
        }
        Some(((p * nb + (b - b0)) * s3 + q) * self.channels)
    }

    /// Offset of node `[a, p, b, q]` (its channel 0) in the whole array.
    pub fn offset(&self, idx: [usize; 4]) -> Option<usize> {
        Some(self.chunk_starts[idx[0].min(self.shape[0])] + self.offset_in_chunk(idx)?)
    }

    /// The node of row `r` of chunk `a` (a row = all axis-3 nodes × channels for one (p, b)).
    pub fn row_node(&self, a: usize, r: usize) -> (usize, usize) {
        let (b0, nb) = self.rows2(a);
        (r / nb, b0 + r % nb)
    }

    /// Number of rows in chunk `a`.
    pub fn rows_in_chunk(&self, a: usize) -> usize {
        self.shape[1] * self.rows2(a).1
    }

    /// Every stored node `[a, p, b, q]` in the stored order: chunk by chunk, row by row, axis 3
    /// innermost, so node k's values are `k·c..(k + 1)·c` of the whole array.
    pub fn stored_nodes(&self) -> impl Iterator<Item = [usize; 4]> + '_ {
        (0..self.chunk_count()).flat_map(move |a| {
            (0..self.rows_in_chunk(a)).flat_map(move |r| {
                let (p, b) = self.row_node(a, r);
                (0..self.shape[3]).map(move |q| [a, p, b, q])
            })
        })
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

#[cfg(test)]
mod tests {
    use super::*;

    fn sym(i: bool, r: bool, b: bool) -> Symmetry {
        Symmetry {
            isotropic: i,
            reciprocal: r,
            bilateral: b,
        }
    }

    #[test]
    fn lecture_counts_on_one_degree_inout_grid() {
        // 90 x 360 x 90 x 360, 1 channel: the brief's counts.
        let ch = Channels::wavelengths(vec![550.0]).unwrap();
        let g = |s| {
            Grid::with_sizes(
                Param::InOut,
                [90, 360, 90, 360],
                [Mapping::Uniform, Mapping::Uniform],
                ch.clone(),
                s,
            )
            .unwrap()
        };
        let full = g(sym(false, false, false));
        assert_eq!(full.stored_values(), 1_049_760_000);
        assert_eq!(full.full_values(), 1_049_760_000);
        let iso = g(sym(true, false, false)).stored_values();
        assert_eq!(iso, 2_916_000); // 2.9e6
        let rec = g(sym(true, true, false)).stored_values();
        assert_eq!(rec, 4095 * 360); // 1.47e6
        let bil = g(sym(true, true, true)).stored_values();
        assert_eq!(bil, 4095 * 181); // 0.74e6
        let ratio = full.stored_values() as f64 / bil as f64;
        assert!((1400.0..1450.0).contains(&ratio), "{ratio}");
    }

    #[test]
    fn stored_nodes_walk_the_values_in_order() {
        // Plain and packed (inout reciprocal: a triangle of the θ axes) layouts: node k of the
        // walk has its values at k·c, and every stored value belongs to one node.
        for (param, s) in [
            (Param::HalfDiff, sym(true, true, true)),
            (Param::InOut, sym(true, true, false)),
            (Param::InOut, sym(false, false, false)),
        ] {
            let g = Grid::with_sizes(
                param,
                [6, 8, 6, 12],
                [Mapping::Cos, Mapping::Cos],
                Channels::Rgb,
                s,
            )
            .unwrap();
            let l = g.layout();
            let nodes: Vec<_> = l.stored_nodes().collect();
            assert_eq!(nodes.len() * l.channels, l.len(), "{param:?} {s:?}");
            for (k, idx) in nodes.iter().enumerate() {
                assert_eq!(l.offset(*idx), Some(k * l.channels), "{idx:?}");
            }
            let angles = g.stored_node_angles();
            assert_eq!(angles.len(), nodes.len());
            assert_eq!(
                angles[nodes.len() - 1],
                g.node_angles(nodes[nodes.len() - 1])
            );
        }
    }

    #[test]
    fn merl_indices_match_the_reader_formulas() {
        let g = Grid::merl(Channels::Rgb);
        let [th, _, td, pd] = g.stored_axes().clone();
        let mut rng = crate::rng::Pcg32::new(5);
        for _ in 0..100_000 {
            let a = rng.next_f64() * FRAC_PI_2;
            let b = rng.next_f64() * FRAC_PI_2;
            let c = rng.next_f64() * PI;
            let merl_h = ((((a / (PI / 2.0)) * 90.0) * 90.0).sqrt() as i64).clamp(0, 89) as usize;
            let merl_d = (((b / (PI / 2.0)) * 90.0) as i64).clamp(0, 89) as usize;
            let merl_p = (((c / PI) * 180.0) as i64).clamp(0, 179) as usize;
            assert_eq!(th.nearest(a), merl_h);
            assert_eq!(td.nearest(b), merl_d);
            assert_eq!(pd.nearest(c), merl_p);
        }
    }

    #[test]
    fn continuous_and_coord_are_inverse() {
        for nodes in [Nodes::Centers, Nodes::Edges, Nodes::CellStart] {
            for m in [Mapping::Uniform, Mapping::Sqrt, Mapping::Cos] {
                let ax = StoredAxis::theta(&Axis::theta(17, m.clone(), nodes));
                for i in 0..17 {
                    let x = ax.node(i);
                    assert!(
                        (ax.continuous(x) - i as f64).abs() < 1e-9,
                        "{m:?} {nodes:?} {i}"
                    );
                    assert_eq!(ax.nearest(x + 1e-12), i);
                }
            }
        }
    }

    #[test]
    fn packed_layout_offsets_are_dense_and_unique() {
        let g = Grid::with_sizes(
            Param::InOut,
            [5, 4, 5, 4],
            [Mapping::Uniform, Mapping::Uniform],
            Channels::Rgb,
            sym(false, true, true),
        )
        .unwrap();
        let l = g.layout();
        let [n0, s1, n2, s3] = l.shape;
        let mut seen = vec![false; l.len() / 3];
        for a in 0..n0 {
            for p in 0..s1 {
                for b in 0..n2 {
                    for q in 0..s3 {
                        let o = l.offset([a, p, b, q]);
                        assert_eq!(o.is_some(), b >= a);
                        if let Some(o) = o {
                            assert!(l.chunk_range(a).contains(&o));
                            assert!(!seen[o / 3]);
                            seen[o / 3] = true;
                        }
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn grid_json_round_trips() {
        let g = Grid::merl(Channels::Rgb);
        let j = serde_json::to_string(&g).unwrap();
        let h: Grid = serde_json::from_str(&j).unwrap();
        assert_eq!(g, h);
        assert!(j.contains("\"halfdiff\""), "{j}");
    }

    #[test]
    fn inconsistent_grids_are_rejected() {
        let bad = Grid::with_sizes(
            Param::HalfDiff,
            [8, 1, 8, 10],
            [Mapping::Sqrt, Mapping::Uniform],
            Channels::Rgb,
            sym(true, true, true),
        );
        assert!(bad.is_err());
        let bad = Grid::with_sizes(
            Param::InOut,
            [8, 1, 8, 8],
            [Mapping::Uniform, Mapping::Uniform],
            Channels::Rgb,
            sym(false, false, false),
        );
        assert!(bad.is_err());
    }
}
