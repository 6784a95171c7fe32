//! A grid's axes: how a coordinate maps to [0, 1] ([`Mapping`]), where the nodes sit
//! ([`Nodes`]), the full axes a grid is described by ([`Axis`]) and the stored axes lookups use
//! ([`StoredAxis`]); see the parent module's docs for the conventions.

use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;

use crate::table::warp::Warp;

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
/// need. Derived from a [`Grid`](super::Grid) by [`Grid::stored_axes`](super::Grid::stored_axes).
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
    pub(super) fn theta(a: &Axis) -> Self {
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

    pub(super) fn periodic(size: usize, period: f64, nodes: Nodes) -> Self {
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

    pub(super) fn folded(size: usize, hi: f64, mapping: Mapping) -> Self {
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

    pub(super) fn single() -> Self {
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
