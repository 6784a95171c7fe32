//! Dense 5D tables: grids, symmetry reduction, baking, interpolated lookup.
//!
//! - [`grid`]: the axes ([`Axis`], [`Mapping`], [`Nodes`]), the parameterization ([`Param`]),
//!   the stored layout and its chunks ([`Layout`]);
//! - [`symmetry`]: [`Symmetry`], the canonical maps, [`symmetry::verify`] and
//!   [`symmetry::detect`];
//! - [`Table`]: a grid plus its stored values, in memory; `edit`: the same grid holding values
//!   made elsewhere ([`Table::with_values`], [`Table::with_array`]), the road back in from
//!   numpy or an optimizer;
//! - [`fill`]: any `Brdf` → values, chunk by chunk ([`bake_chunks`], for streaming
//!   writers) or into a [`Table`];
//! - [`lookup`]: nearest and multilinear interpolation ([`Interp`]);
//! - [`device`]: [`device::DeviceLayout`], a table as a GPU or JIT host uploads and evaluates it;
//! - [`tabulated`]: [`TabulatedBrdf`], the `Brdf` over a table — every chunk in memory, or loaded
//!   on first touch through a [`ChunkLoader`];
//! - [`presets`]: `small`, `medium`, `large` grids with measured accuracy;
//! - [`raw`]: a minimal JSON-header + f32 file, uncompressed (`convert`'s output for a name that
//!   is not `.btdb`, `DB#NAME`, `.bsdf` or `.binary`; the compressed format is [`crate::store`]);
//! - [`sampling`]: importance sampling of tables ([`TableSampler`]: conditional half-vector
//!   densities of f_r·cos θi, drawn with alias tables).
//!
//! Values are stored λ innermost: the values of one node for every channel are contiguous, so
//! one set of angular interpolation weights serves all channels.

pub mod adaptive;
mod alias2d;
pub mod calibration;
pub mod device;
mod edit;
pub mod fill;
pub mod grid;
mod horizon;
pub mod kernel;
pub mod lookup;
pub mod param;
mod pole;
pub mod presets;
pub mod raw;
mod resolution;
pub mod sampling;
pub mod symmetry;
pub mod tabulated;
pub mod target;
mod views;
pub mod warp;
pub(crate) mod warp2d;

pub(crate) use edit::first_nonfinite_at;
pub use fill::{BakeOptions, BakeStats, bake, bake_chunks};
pub use grid::{Axis, Grid, Layout, Mapping, Nodes, Param, Quantity, StoredAxis};
pub use lookup::Interp;
pub use sampling::{
    Adjoint, AliasTables, Draw, HALF_MAP_LINEAR, SamplingNodes, SamplingResolution, TableSampler,
};
pub use symmetry::Symmetry;
pub use tabulated::{ChunkLoader, TabulatedBrdf};

use glam::DVec3;

use crate::error::{Error, Result};

/// A grid and its stored values, in memory (the layout is [`Grid::layout`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    grid: Grid,
    values: Vec<f32>,
    description: String,
}

impl Table {
    /// A table from values in the grid's stored layout; checks the length.
    pub fn new(grid: Grid, values: Vec<f32>, description: impl Into<String>) -> Result<Table> {
        if values.len() != grid.stored_values() {
            return Err(Error::arg(
                "values",
                format!(
                    "{} values given, the grid stores {}",
                    values.len(),
                    grid.stored_values()
                ),
            ));
        }
        Ok(Table {
            grid,
            values,
            description: description.into(),
        })
    }

    /// A table filled by `f(node index, node angles, out)` for every stored node, in layout order
    /// (single-threaded; for sources that are not a `Brdf`, e.g. a measurement array).
    pub fn from_fn(
        grid: Grid,
        description: impl Into<String>,
        mut f: impl FnMut([usize; 4], [f64; 4], &mut [f32]),
    ) -> Table {
        let l = grid.layout().clone();
        let c = l.channels;
        let mut values = vec![0.0f32; l.len()];
        for (idx, out) in l.stored_nodes().zip(values.chunks_exact_mut(c)) {
            f(idx, grid.node_angles(idx), out);
        }
        Table {
            grid,
            values,
            description: description.into(),
        }
    }

    /// The grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// All stored values (layout order, λ innermost).
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// Mutable stored values.
    pub fn values_mut(&mut self) -> &mut [f32] {
        &mut self.values
    }

    /// The array shape of the stored values: the stored axes and the channels
    /// (`stored_shape + [c]`, λ innermost); `None` for a packed layout (an `inout` reciprocal
    /// table stores a triangle of its θ axes, no rectangle).
    pub fn shape(&self) -> Option<[usize; 5]> {
        let l = self.grid.layout();
        let [a, b, c, d] = self.grid.stored_shape();
        (!l.packed).then_some([a, b, c, d, l.channels])
    }

    /// The stored values as an `ndarray` view shaped by [`Table::shape`], without a copy: what
    /// hosts hand to numpy and what exports slice.
    ///
    /// ```
    /// use brdftab::bake::BakeRequest;
    /// let (table, _) = BakeRequest::new(r#"{"model": "lambert", "kd": 0.5}"#)
    ///     .grid("8x1x8x16".parse()?)
    ///     .table(&brdftab::progress::Silent)?;
    /// let v = table.view()?;
    /// assert_eq!(v.shape(), &table.shape().unwrap()[..]);
    /// assert_eq!(v[[0, 0, 0, 0, 2]], table.values()[2]);
    /// # Ok::<(), brdftab::Error>(())
    /// ```
    ///
    /// # Errors
    /// [`Error::Unsupported`] for a packed layout (use [`Table::values`]).
    pub fn view(&self) -> Result<ndarray::ArrayView5<'_, f32>> {
        let shape = self.shape().ok_or_else(|| self.packed_error())?;
        ndarray::ArrayView5::from_shape(shape, &self.values)
            .map_err(|e| Error::Unsupported(format!("table values as an array: {e}")))
    }

    /// The stored values as an owned array shaped by [`Table::shape`] (no copy: the vector
    /// moves into it).
    ///
    /// # Errors
    /// [`Error::Unsupported`] for a packed layout.
    pub fn into_array(self) -> Result<ndarray::Array5<f32>> {
        let shape = self.shape().ok_or_else(|| self.packed_error())?;
        ndarray::Array5::from_shape_vec(shape, self.values)
            .map_err(|e| Error::Unsupported(format!("table values as an array: {e}")))
    }

    fn packed_error(&self) -> Error {
        Error::Unsupported(format!(
            "a packed {} table has no rectangular array of values (use the flat values)",
            self.grid.summary()
        ))
    }

    /// The values of chunk `i` (a slab of stored axis 0).
    pub fn chunk(&self, i: usize) -> &[f32] {
        &self.values[self.grid.layout().chunk_range(i)]
    }

    /// What the table was made from (the source's `describe()`).
    pub fn description(&self) -> &str {
        &self.description
    }

    /// The grid, values and description.
    pub fn into_parts(self) -> (Grid, Vec<f32>, String) {
        (self.grid, self.values, self.description)
    }

    /// The values of the stored node `idx` (all channels), if stored.
    pub fn node(&self, idx: [usize; 4]) -> Option<&[f32]> {
        let o = self.grid.layout().offset(idx)?;
        Some(&self.values[o..o + self.grid.channels().len()])
    }
}

/// The direction pair (wi, wo) of stored coordinates `c` (in the stored domains): `inout` →
/// spherical(θ1, φ1), spherical(θ2, φ2); `halfdiff` → the inverse Rusinkiewicz transform. Unit
/// vectors, at or below the horizon for nodes outside the physical domain (which a table holds
/// for interpolation next to it).
pub fn node_pair(param: Param, c: [f64; 4]) -> (DVec3, DVec3) {
    match param {
        Param::InOut => (
            crate::geometry::spherical(c[0], c[1]),
            crate::geometry::spherical(c[2], c[3]),
        ),
        Param::HalfDiff => crate::geometry::from_half_diff(crate::geometry::HalfDiff {
            theta_h: c[0],
            phi_h: c[1],
            theta_d: c[2],
            phi_d: c[3],
        }),
    }
}

/// The representative direction pair a bake evaluates for stored coordinates `c`:
/// [`node_pair`], with directions at or below the horizon lifted to z = [`HORIZON_Z`] so that
/// nodes outside the physical domain carry the nearby boundary value (this keeps interpolation
/// next to the horizon accurate, and constant sources exact).
pub fn pair_of(param: Param, c: [f64; 4]) -> (DVec3, DVec3) {
    let (wi, wo) = node_pair(param, c);
    (lift(wi), lift(wo))
}

/// Minimum z of a baked direction (see [`pair_of`]).
pub const HORIZON_Z: f64 = 1e-3;

fn lift(w: DVec3) -> DVec3 {
    if w.z >= HORIZON_Z {
        return w;
    }
    let r = (w.x * w.x + w.y * w.y).sqrt();
    let s = (1.0 - HORIZON_Z * HORIZON_Z).sqrt();
    if r > 0.0 {
        DVec3::new(w.x / r * s, w.y / r * s, HORIZON_Z)
    } else {
        DVec3::new(s, 0.0, HORIZON_Z)
    }
}
