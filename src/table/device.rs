//! The device layout: one typed, versioned description of a table for hosts that evaluate it
//! themselves (a GPU, a Dr.Jit kernel) instead of calling the library per lookup.
//!
//! Such a host cannot call back into Rust per query, so it re-implements the lookup. Rather
//! than have it re-derive the lookup from the grid's description (mappings, node placement,
//! folds, which path `TabulatedBrdf` takes, how the kernel packs values), the library hands
//! it a [`DeviceLayout`]: a small closed set of layouts with the arrays already in the form the
//! lookup reads, and a reference evaluator, [`DeviceLayout::eval`], that states the contract in
//! plain terms. The tests below hold `eval` equal to [`super::TabulatedBrdf`]'s lookup for
//! every table kind, so a host that implements `eval` implements the library's lookup; the
//! Python package's Mitsuba plugin (`brdftab.mitsuba.JitTable`) is such a host, tested against
//! the library to 1e-5.
//!
//! The layouts ([`DeviceKind`]):
//! - [`DeviceKind::Kernel`] — what [`super::kernel`] evaluates (adaptive `halfdiff` tables and
//!   small MERL-style ones): per axis the knot lines of the fractional node index in a warp
//!   variable computed from the vectors, the values as the kernel reads them (after its f16
//!   packing); a resampled axis's pairs beyond its cut take the [`GridLayout`] beside it.
//! - [`DeviceKind::Grid`] — every other table: a dense 4D grid of canonical coordinates (the
//!   symmetry folds of [`super::symmetry`]) with each stored axis's mapping and node placement
//!   ([`StoredAxis`]); packed `inout` reciprocal tables are unpacked into the full rectangle.
//!
//! [`VERSION`] changes whenever a field or the meaning of one does.

use glam::DVec3;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::table::Table;
use crate::table::calibration::Calibration;
use crate::table::grid::{Grid, Param, Quantity, StoredAxis};
pub use crate::table::kernel::KernelAxis;
use crate::table::kernel::{Kernel, Packed, project_f32, project_out, warp_vars};
use crate::table::lookup::Interp;
use crate::table::symmetry::{
    Symmetry, canonical_coords, canonical_coords_fast, canonical_corner_inout,
};
use crate::table::warp::WarpVar;

/// The version of the [`DeviceLayout`] description; a host refuses any other.
pub const VERSION: u32 = 1;

/// Which layout a [`DeviceLayout`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DeviceKind {
    /// [`KernelLayout`] (with a [`GridLayout`] for pairs beyond a resampled axis's cut).
    Kernel,
    /// [`GridLayout`] only.
    Grid,
}

impl DeviceKind {
    /// `kernel` or `grid`.
    pub fn name(self) -> &'static str {
        match self {
            DeviceKind::Kernel => "kernel",
            DeviceKind::Grid => "grid",
        }
    }
}

/// A table as a device evaluates it (see the module docs). Built by [`DeviceLayout::new`];
/// [`DeviceLayout::eval`] is the lookup a device implements.
#[derive(Debug, Clone, Serialize)]
pub struct DeviceLayout {
    /// [`VERSION`].
    pub version: u32,
    /// The layout.
    pub kind: DeviceKind,
    /// Values per node (λ innermost in every value array).
    pub channels: usize,
    /// What the values are: for a quantity other than f_r a lookup divides the interpolated
    /// value by cos θo ([`Quantity::FrCosOut`]) or cos θi cos θo, clamps it at 0 and multiplies
    /// by the [`Calibration`], if any.
    pub quantity: Quantity,
    /// The albedo calibration of a projected quantity (k_in(θi), optionally k_out(θo)).
    pub calibration: Option<Calibration>,
    /// The kernel's layout ([`DeviceKind::Kernel`]).
    pub kernel: Option<KernelLayout>,
    /// The general layout: the whole table ([`DeviceKind::Grid`]), or a kernel's fallback
    /// beyond its cut (resampled axes only; `None` when every axis is warped).
    pub grid: Option<GridLayout>,
}

/// A dense 4D table on canonical coordinates, looked up as [`super::lookup`] does.
#[derive(Debug, Clone, Serialize)]
pub struct GridLayout {
    /// The parameterization of the canonical coordinates.
    pub param: Param,
    /// The symmetry folds applied to them.
    pub symmetry: Symmetry,
    /// Linear lookups take the polynomial acos/atan2
    /// ([`canonical_coords_fast`]), nearest ones the exact functions ([`canonical_coords`]).
    pub interp: Interp,
    /// The four stored axes: size, domain, mapping, node placement, periodicity.
    pub axes: [StoredAxis; 4],
    /// Nodes per axis: `values` is `shape[0] × … × shape[3] × channels`, row-major.
    pub shape: [usize; 4],
    /// The values as lookups read them (an f_r table's negative, unmeasured, values are 0).
    #[serde(skip)]
    pub values: Vec<f32>,
}

/// What [`super::kernel`] evaluates: three axes (θh, θd, φd) whose fractional node index is a
/// piecewise line in a warp variable computed in f32 from the unit vectors.
#[derive(Debug, Clone, Serialize)]
pub struct KernelLayout {
    /// θh's variable: [`WarpVar::SqrtSine`] (sin θh)^½ or [`WarpVar::QuarterPower`]
    /// (1 − cos θh)^¼.
    pub h_var: WarpVar,
    /// φd folded onto [0, π/2] (reciprocity): v_φ = |d_y|/(|d_x| + |d_y|); else
    /// ½ − ½ d_x/(|d_x| + |d_y|).
    pub quarter: bool,
    /// θh, θd, φd.
    pub axes: [KernelAxis; 3],
    /// The values as the kernel reads them (f16-rounded and scaled back, or exact f32),
    /// `axes[0].nodes × axes[1].nodes × axes[2].nodes × channels`.
    #[serde(skip)]
    pub values: Vec<f32>,
}

impl DeviceLayout {
    /// The layout of `table` looked up with `interp`: [`DeviceKind::Kernel`] where
    /// `TabulatedBrdf` uses the kernel (linear lookups of tables that have one), else
    /// [`DeviceKind::Grid`].
    ///
    /// # Errors
    /// [`Error::Unsupported`] when the unpacked grid would not fit in memory.
    pub fn new(table: &Table, interp: Interp) -> Result<DeviceLayout> {
        let fr = table.grid().quantity() == Quantity::Fr;
        let values = unpacked(table, |x| read(fr, x))?;
        Ok(DeviceLayout::build(table.grid(), values, interp))
    }

    /// [`DeviceLayout::new`] taking the table: its values become the layout's without a copy
    /// (unless the layout is packed, or a kernel's).
    ///
    /// # Errors
    /// As [`DeviceLayout::new`].
    pub fn from_table(table: Table, interp: Interp) -> Result<DeviceLayout> {
        if table.grid().layout().packed {
            return DeviceLayout::new(&table, interp);
        }
        let (grid, mut values, _) = table.into_parts();
        let fr = grid.quantity() == Quantity::Fr;
        for x in values.iter_mut() {
            *x = read(fr, *x);
        }
        Ok(DeviceLayout::build(&grid, values, interp))
    }

    /// The layout of `grid` with `values` as lookups read them (unpacked, f_r clamped).
    fn build(grid: &Grid, values: Vec<f32>, interp: Interp) -> DeviceLayout {
        let channels = grid.channels().len();
        let quantity = grid.quantity();
        let kernel = match interp {
            Interp::Linear => Kernel::new(grid),
            Interp::Nearest => None,
        };
        let general = |values: Vec<f32>| GridLayout {
            param: grid.param(),
            symmetry: grid.symmetry(),
            interp,
            axes: grid.stored_axes().clone(),
            shape: grid.stored_shape(),
            values,
        };
        let (kind, kernel, grid_layout) = match kernel {
            Some(k) => {
                let packed = Packed::for_kernel(&k, &values);
                let layout = KernelLayout {
                    h_var: k.h_var(),
                    quarter: k.quarter(),
                    axes: k.device_axes(),
                    values: (0..packed.len()).map(|i| packed.get(i)).collect(),
                };
                let fallback = k.has_cut().then(|| general(values));
                (DeviceKind::Kernel, Some(layout), fallback)
            }
            None => (DeviceKind::Grid, None, Some(general(values))),
        };
        DeviceLayout {
            version: VERSION,
            kind,
            channels,
            quantity,
            calibration: grid.calibration().cloned(),
            kernel,
            grid: grid_layout,
        }
    }

    /// f_r of the pair in `out[..channels]` (0 below the horizon and for invalid directions):
    /// the lookup a device implements. Never panics, also on a hand-made inconsistent layout
    /// (values missing from an array count as 0).
    pub fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let c = self.channels.min(out.len());
        let out = &mut out[..c];
        out.fill(0.0);
        if let Some(k) = &self.kernel {
            match k.vars(wi, wo) {
                None => return,
                Some((v, cos)) if v.iter().zip(&k.axes).all(|(v, a)| *v < a.cut) => {
                    k.blend(v, out);
                    if self.quantity != Quantity::Fr || self.calibration.is_some() {
                        project_f32(self.quantity, self.calibration.as_ref(), cos, out);
                    }
                    return;
                }
                // Beyond a cut: the grid below.
                Some(_) => {}
            }
        }
        if let Some(g) = &self.grid {
            g.eval(wi, wo, out);
            if self.quantity != Quantity::Fr || self.calibration.is_some() {
                project_out(self.quantity, self.calibration.as_ref(), wi, wo, out);
            }
        }
    }
}

/// A stored value as lookups read it: as `TabulatedBrdf` sets them aside, an f_r table's
/// negative values (unmeasured cells) are 0.
#[inline]
fn read(fr: bool, x: f32) -> f32 {
    if fr && x < 0.0 { 0.0 } else { x }
}

/// The stored values in the full rectangle of the stored axes: a packed `inout` reciprocal
/// table's corners below the diagonal are filled from their reciprocal node.
/// Each value goes through `read` (one pass: this copy is the layout's only one).
fn unpacked(table: &Table, read: impl Fn(f32) -> f32) -> Result<Vec<f32>> {
    let grid = table.grid();
    if !grid.layout().packed {
        return Ok(table.values().iter().map(|&x| read(x)).collect());
    }
    let shape = grid.stored_shape();
    let c = grid.channels().len();
    let n = shape.iter().product::<usize>().checked_mul(c);
    let Some(n) = n.filter(|&n| n <= isize::MAX as usize / 4) else {
        return Err(Error::Unsupported(format!(
            "{}: the unpacked table does not fit in memory",
            grid.summary()
        )));
    };
    let (sym, n3) = (grid.symmetry(), grid.axes()[3].size);
    let mut out = Vec::with_capacity(n);
    for a in 0..shape[0] {
        for p in 0..shape[1] {
            for b in 0..shape[2] {
                for q in 0..shape[3] {
                    let idx = canonical_corner_inout(sym, [a, p, b, q], n3);
                    match table.node(idx) {
                        Some(v) => out.extend(v.iter().map(|&x| read(x))),
                        None => out.extend(std::iter::repeat_n(0.0, c)),
                    }
                }
            }
        }
    }
    Ok(out)
}

impl GridLayout {
    /// The interpolated stored value (before any projection) into `out` (zeroed by the caller):
    /// canonical coordinates, then per axis [`StoredAxis::nearest`] or [`StoredAxis::linear`],
    /// then the nearest node or the 16 corners, blended in f32 in the order axis 0, 1, 2, 3
    /// (corners of weight 0 add nothing).
    pub fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let x = match self.interp {
            Interp::Nearest => canonical_coords(self.param, self.symmetry, wi, wo),
            Interp::Linear => canonical_coords_fast(self.param, self.symmetry, wi, wo),
        };
        let Some(x) = x else {
            return;
        };
        let c = out.len();
        let [_, s1, s2, s3] = self.shape;
        let offset = |i: [usize; 4]| (((i[0] * s1 + i[1]) * s2 + i[2]) * s3 + i[3]) * c;
        let ax = &self.axes;
        if self.interp == Interp::Nearest {
            let o = offset(std::array::from_fn(|k| ax[k].nearest(x[k])));
            if let Some(v) = self.values.get(o..o + c) {
                out.copy_from_slice(v);
            }
            return;
        }
        let l: [(usize, usize, f32); 4] = std::array::from_fn(|k| ax[k].linear(x[k]));
        let corner = |k: usize, j: usize| {
            let (i0, i1, t) = l[k];
            if j == 0 { (i0, 1.0 - t) } else { (i1, t) }
        };
        for j in 0..16 {
            let b = |k: usize| (j >> (3 - k)) & 1;
            let ((i0, w0), (i1, w1), (i2, w2), (i3, w3)) = (
                corner(0, b(0)),
                corner(1, b(1)),
                corner(2, b(2)),
                corner(3, b(3)),
            );
            let w = w0 * w1 * w2 * w3;
            if w0 == 0.0 || w1 == 0.0 || w2 == 0.0 || w3 == 0.0 {
                continue;
            }
            let o = offset([i0, i1, i2, i3]);
            if let Some(v) = self.values.get(o..o + c) {
                for (o, &x) in out.iter_mut().zip(v) {
                    *o += w * x;
                }
            }
        }
    }
}

impl KernelLayout {
    /// The warp variables (v_h, v_d, v_φ) of a pair in f32 and (cos θi, cos θo), from the
    /// unit vectors (made unit in f64 unless they are within 2⁻⁴⁰ of it, then rounded to
    /// f32); `None` below the horizon. With h = ωi + ωo, e = ωi − ωo and r² = h_x² + h_y²:
    /// v_h = (r²/|h|²)^¼ (SqrtSine) or (r²/(|h|² + |h| h_z))^¼ (QuarterPower);
    /// v_d = (|e|²/(2(2 + |h|)))^½; d_x = h_z(h_x ωi_x + h_y ωi_y) − r² ωi_z,
    /// d_y = ||h|(h_x ωi_y − h_y ωi_x)|, and v_φ as [`KernelLayout::quarter`] says (0 when
    /// |d_x| + |d_y| = 0). The operations and their order are those of the kernel.
    pub fn vars(&self, wi: DVec3, wo: DVec3) -> Option<([f32; 3], [f32; 2])> {
        warp_vars(wi, wo, self.h_var == WarpVar::QuarterPower, self.quarter)
    }

    /// The eight corners blended in f32 into `out` (zeroed by the caller). Per axis: t = v·K,
    /// knot interval j = trunc(min(t, K − ½)), s = `c[j] + t·d[j]` clamped to \[0, n − 1\], lower
    /// node i = trunc(min(s, n − 1.5)), weight s − i. The four (θh, θd) rows in order
    /// (i_h, i_d), (i_h, i_d + 1), (i_h + 1, i_d), (i_h + 1, i_d + 1), each adding
    /// `w·(1 − t_φ)·x[i_φ] + w·t_φ·x[i_φ + 1]` per channel.
    pub fn blend(&self, v: [f32; 3], out: &mut [f32]) {
        let node = |a: &KernelAxis, v: f32| {
            let k = a.c.len() as f32;
            let t = v * k;
            let j = (t.min(k - 0.5) as usize).min(a.c.len().saturating_sub(1));
            let line = (a.c.get(j).copied(), a.d.get(j).copied());
            let (c, d) = (line.0.unwrap_or(0.0), line.1.unwrap_or(0.0));
            let s = (c + t * d).max(0.0).min(a.nodes as f32 - 1.0);
            let i = (s.min(a.nodes as f32 - 1.5) as usize).min(a.nodes.saturating_sub(2));
            (i, s - i as f32)
        };
        let [(ih, th), (id, td), (ip, tp)] = [0, 1, 2].map(|k| node(&self.axes[k], v[k]));
        let c = out.len();
        let row = self.axes[2].nodes * c;
        let chunk = self.axes[1].nodes * row;
        let o = ih * chunk + id * row + ip * c;
        let rows = [
            (o, (1.0 - th) * (1.0 - td)),
            (o + row, (1.0 - th) * td),
            (o + chunk, th * (1.0 - td)),
            (o + chunk + row, th * td),
        ];
        for (r, w) in rows {
            let (w0, w1) = (w * (1.0 - tp), w * tp);
            if let (Some(a), Some(b)) =
                (self.values.get(r..r + c), self.values.get(r + c..r + 2 * c))
            {
                for ((o, &x0), &x1) in out.iter_mut().zip(a).zip(b) {
                    *o += w0 * x0 + w1 * x1;
                }
            }
        }
    }
}

#[cfg(test)]
#[path = "device_tests.rs"]
mod tests;
