//! The road back in: a table's grid holding values that were made elsewhere — smoothed,
//! rescaled, fitted or optimized in numpy or a renderer — rather than by sampling a `Brdf`.
//!
//! Why a module: [`fill`](super::fill) makes a table's values from a source; here they arrive
//! as an array, and what the library owes them is the check against the grid (the length, or
//! the shape of the stored axes and channels that exports write; every stored value finite)
//! while everything else of the table stays as it was: the grid — its stored layout, symmetry,
//! quantity and albedo calibration, which lookups keep applying — and the description.
//!
//! **Negative values** keep the meaning they have in every table. In a table of f_r
//! ([`Quantity::Fr`](super::Quantity::Fr)) they mark unmeasured nodes, which lookups read as 0
//! and [`TabulatedBrdf::to_table`](super::TabulatedBrdf::to_table) gives back as they were
//! (see [`tabulated`](super::tabulated)); in a table of f_r cos θo or f_r cos θi cos θo they are
//! values like any other (a node beyond the horizon extrapolated below 0), interpolated, with
//! the lookup's result clamped at 0.

use super::{Grid, Table};
use crate::error::{Error, Result};

/// How an array of values lies on a grid.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Form {
    /// In the stored layout ([`Table::values`]): flat, or shaped by the stored axes and the
    /// channels of a layout that is not packed (the same order).
    Stored,
    /// The rectangle of the stored axes and channels of a packed layout (an `inout` reciprocal
    /// table): values at the nodes the table does not store are ignored.
    Rectangle,
}

impl Table {
    /// The same table — grid (stored layout, symmetry, quantity, albedo calibration) and
    /// description — holding `values`, in the grid's stored layout ([`Table::values`]'s order).
    ///
    /// Negative values keep their meaning (module docs): unmeasured nodes in a table of f_r.
    /// A table whose values come from another material should not keep the calibration's
    /// factors, which pinned the first material's albedo: give it the grid's
    /// [`Grid::without_calibration`] ([`Table::new`]).
    ///
    /// ```
    /// use brdftab::bake::BakeRequest;
    /// use brdftab::Brdf;
    /// use brdftab::table::TabulatedBrdf;
    /// let (t, _) = BakeRequest::new(r#"{"model": "lambert", "kd": 0.25}"#)
    ///     .grid("8x1x8x16".parse()?)
    ///     .table(&brdftab::progress::Silent)?;
    /// let brighter = t.with_values(t.values().iter().map(|x| 2.0 * x).collect())?;
    /// let (n, mut f, mut g) = (glam::DVec3::Z, [0.0f32; 3], [0.0f32; 3]);
    /// TabulatedBrdf::from_table(t).eval(n, n, &mut f);
    /// TabulatedBrdf::from_table(brighter).eval(n, n, &mut g);
    /// assert_eq!(g, f.map(|x| 2.0 * x));
    /// # Ok::<(), brdftab::Error>(())
    /// ```
    ///
    /// # Errors
    /// [`Error::InvalidArgument`] naming `values`: another count than the grid stores, or a
    /// NaN or infinite value (its index is in the message).
    pub fn with_values(&self, values: Vec<f32>) -> Result<Table> {
        if values.len() != self.grid.stored_values() {
            return Err(Error::arg(
                "values",
                format!(
                    "{} values given, the grid stores {}",
                    values.len(),
                    self.grid.stored_values()
                ),
            ));
        }
        let n = values.len();
        Table::from_array(self.grid.clone(), &[n], values, self.description.clone())
    }

    /// [`Table::with_values`] of an array of `shape` (`data` in C order): flat (the stored
    /// layout), `[nodes, c]` (the same order, a row of channels per stored node, as the nodes
    /// of [`Grid::stored_node_angles`] come: a source evaluated at them) or shaped by the
    /// stored axes and the channels (`grid.stored_shape() + [c]`, what [`Table::view`] and the
    /// `.npy` export give) — for a packed layout (an `inout` reciprocal table stores a triangle
    /// of its θ axes) the whole rectangle, whose unstored nodes are ignored (the export writes
    /// NaN there).
    ///
    /// # Errors
    /// [`Error::InvalidArgument`] naming `values`: a shape that is neither, `data` not of the
    /// shape's size, or a NaN or infinite value at a stored node (its index is in the message).
    pub fn with_array(&self, shape: &[usize], data: Vec<f32>) -> Result<Table> {
        Table::from_array(self.grid.clone(), shape, data, self.description.clone())
    }

    /// A table on `grid` from an array of `shape` (`data` in C order), read as
    /// [`Table::with_array`] reads it.
    ///
    /// # Errors
    /// As [`Table::with_array`].
    pub fn from_array(
        grid: Grid,
        shape: &[usize],
        data: Vec<f32>,
        description: impl Into<String>,
    ) -> Result<Table> {
        let form = form(&grid, shape, data.len())?;
        if let Some(i) = first_nonfinite(&grid, form, &data) {
            let only = match form {
                Form::Rectangle => {
                    " (NaN is allowed only at the nodes a packed table does not store)"
                }
                Form::Stored => "",
            };
            return Err(Error::arg(
                "values",
                format!(
                    "values{} is {}: every value the table stores must be finite{only}",
                    index_text(i, shape),
                    data[i]
                ),
            ));
        }
        let values = match form {
            Form::Stored => data,
            Form::Rectangle => gather(&grid, &data),
        };
        Table::new(grid, values, description)
    }

    /// The same table described as `description` (what it was made from).
    pub fn with_description(mut self, description: impl Into<String>) -> Table {
        self.description = description.into();
        self
    }
}

/// The first NaN or infinite value of `data` (an array of `shape` on `grid`, as
/// [`Table::with_array`] takes it) at a node the grid stores: its flat index in `data` and its
/// index in the array (`[a, b, c, d, ch]`); `None` when there is none.
///
/// # Errors
/// As [`Table::with_array`], for a shape it refuses.
pub(crate) fn first_nonfinite_at(
    grid: &Grid,
    shape: &[usize],
    data: &[f32],
) -> Result<Option<(usize, String)>> {
    let form = form(grid, shape, data.len())?;
    Ok(first_nonfinite(grid, form, data).map(|i| (i, index_text(i, shape))))
}

/// How an array of `shape` holding `len` values lies on `grid`, or an error naming `values`.
fn form(grid: &Grid, shape: &[usize], len: usize) -> Result<Form> {
    let size = shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
    if size != Some(len) {
        return Err(Error::arg(
            "values",
            format!("{len} values given for an array of shape {shape:?}"),
        ));
    }
    let l = grid.layout();
    let rect: Vec<usize> = l.shape.iter().copied().chain([l.channels]).collect();
    if shape == rect.as_slice() {
        return Ok(if l.packed {
            Form::Rectangle
        } else {
            Form::Stored
        });
    }
    // Flat, or one row of channels a stored node (the stored order: what a host gets by
    // evaluating a source at the nodes `stored_node_angles` lists, packed or not).
    let c = l.channels.max(1);
    let rows = [grid.stored_values() / c, c];
    if shape == [grid.stored_values()] || shape == rows {
        return Ok(Form::Stored);
    }
    let packed = if l.packed {
        " — the rectangle of a packed table, whose unstored nodes are ignored"
    } else {
        ""
    };
    Err(Error::arg(
        "values",
        format!(
            "an array of shape {shape:?} does not fit the grid: it stores an array of shape \
             {rect:?} (its stored axes and channels{packed}), {rows:?} (a row of channels a \
             stored node) or {} values flat",
            grid.stored_values()
        ),
    ))
}

/// The row-major node index `[a, p, b, q]` of every node of the stored rectangle, in order.
fn rectangle_nodes(grid: &Grid) -> impl Iterator<Item = [usize; 4]> {
    let [n0, n1, n2, n3] = grid.layout().shape;
    (0..n0).flat_map(move |a| {
        (0..n1).flat_map(move |p| (0..n2).flat_map(move |b| (0..n3).map(move |q| [a, p, b, q])))
    })
}

fn first_nonfinite(grid: &Grid, form: Form, data: &[f32]) -> Option<usize> {
    match form {
        Form::Stored => data.iter().position(|x| !x.is_finite()),
        Form::Rectangle => {
            let (l, c) = (grid.layout(), grid.layout().channels);
            rectangle_nodes(grid)
                .enumerate()
                .filter(|(_, idx)| l.offset(*idx).is_some())
                .find_map(|(k, _)| (0..c).map(|ch| k * c + ch).find(|&i| !data[i].is_finite()))
        }
    }
}

/// The stored values of the rectangle `data` (one node after another, `c` values each).
fn gather(grid: &Grid, data: &[f32]) -> Vec<f32> {
    let (l, c) = (grid.layout(), grid.layout().channels);
    let mut values = vec![0.0f32; l.len()];
    for (k, idx) in rectangle_nodes(grid).enumerate() {
        if let Some(o) = l.offset(idx) {
            values[o..o + c].copy_from_slice(&data[k * c..(k + 1) * c]);
        }
    }
    values
}

/// `[i]` for a flat array, `[a, b, ...]` (row-major) for one of `shape`.
fn index_text(i: usize, shape: &[usize]) -> String {
    let mut idx = vec![0usize; shape.len()];
    let mut rest = i;
    for (k, &d) in shape.iter().enumerate().rev() {
        if d > 0 {
            idx[k] = rest % d;
            rest /= d;
        }
    }
    let parts: Vec<String> = idx.iter().map(usize::to_string).collect();
    format!("[{}]", parts.join(", "))
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::bake::{BakeRequest, GridChoice};
    use crate::brdf::Brdf;
    use crate::geometry::uniform_hemisphere;
    use crate::progress::Silent;
    use crate::rng::Pcg32;
    use crate::table::{Mapping, Param, Symmetry, TabulatedBrdf};

    const PAIRS: usize = 2000;

    /// `PAIRS` random pairs of unit directions above the horizon, the same for every call.
    fn pairs() -> Vec<(DVec3, DVec3)> {
        let mut rng = Pcg32::new(11);
        (0..PAIRS)
            .map(|_| {
                (
                    uniform_hemisphere(rng.next_dvec2()),
                    uniform_hemisphere(rng.next_dvec2()),
                )
            })
            .collect()
    }

    /// Every lookup of `t` at [`pairs`], channels concatenated.
    fn lookups(t: &Table) -> Vec<f32> {
        let b = TabulatedBrdf::from_table(t.clone());
        let c = t.grid().channels().len();
        let mut out = vec![0.0f32; PAIRS * c];
        for (k, (wi, wo)) in pairs().into_iter().enumerate() {
            b.eval(wi, wo, &mut out[k * c..(k + 1) * c]);
        }
        out
    }

    /// The error of a call that must fail (without printing the table it made otherwise).
    fn refused(r: Result<Table>) -> Error {
        match r {
            Ok(_) => panic!("accepted"),
            Err(e) => e,
        }
    }

    fn baked(source: &str, grid: GridChoice) -> Table {
        BakeRequest::new(source)
            .grid(grid)
            .table(&Silent)
            .unwrap()
            .0
    }

    /// A plain preset table, a calibrated adaptive model table (its kernel reads f16 codes)
    /// and a calibrated adaptive RGL table (f_r cos θo, factors k_in and k_out).
    fn tables() -> Vec<(&'static str, Table)> {
        let rgl = crate::measured::data::rgl_file("paper_white_rgb.bsdf").unwrap();
        let adaptive = || "adaptive:24x12x7".parse::<GridChoice>().unwrap();
        vec![
            (
                "ggx small",
                baked(
                    r#"{"model": "ggx", "alpha": 0.3}"#,
                    "small".parse().unwrap(),
                ),
            ),
            (
                "ggx adaptive",
                baked(r#"{"model": "ggx", "alpha": 0.3}"#, adaptive()),
            ),
            ("rgl adaptive", baked(rgl.to_str().unwrap(), adaptive())),
        ]
    }

    #[test]
    fn a_tables_own_values_evaluate_as_the_table() {
        for (what, t) in tables() {
            let same = t.with_values(t.values().to_vec()).unwrap();
            assert_eq!(same, t, "{what}");
            assert_eq!(lookups(&same), lookups(&t), "{what}");
        }
    }

    /// Every step of a lookup is linear in the values — the blend, the division by the stored
    /// quantity's cosines, the clamp at 0, the calibration's factors, and the kernel's f16
    /// codes, scaled by the power of two that puts the largest value in [2^14, 2^15) — and
    /// multiplying by 2 is exact in binary floating point: every lookup doubles bit for bit.
    #[test]
    fn doubled_values_double_every_lookup() {
        let mut calibrated = 0;
        for (what, t) in tables() {
            calibrated += t.grid().calibration().is_some() as usize;
            let doubled = t
                .with_values(t.values().iter().map(|x| 2.0 * x).collect())
                .unwrap();
            let (a, b) = (lookups(&t), lookups(&doubled));
            assert!(a.iter().any(|&x| x > 0.0), "{what}");
            for (k, (x, y)) in a.iter().zip(&b).enumerate() {
                assert_eq!(2.0 * x, *y, "{what}: lookup {k}");
            }
        }
        assert_eq!(calibrated, 2, "the adaptive tables are calibrated");
    }

    /// Without the calibration a lookup is the calibrated one before its factors: multiplied
    /// by them it agrees to the rounding of the two products (a few f32 ulps).
    #[test]
    fn without_calibration_lookups_lack_exactly_the_factors() {
        let t = &tables()[2].1;
        let cal = t.grid().calibration().unwrap().clone();
        let (grid, values, desc) = t.clone().into_parts();
        let plain = Table::new(grid.without_calibration(), values, desc).unwrap();
        assert!(plain.grid().calibration().is_none());
        let (a, b) = (lookups(t), lookups(&plain));
        let c = t.grid().channels().len();
        let mut differ = 0;
        for (k, (wi, wo)) in pairs().into_iter().enumerate() {
            let mut f = b[k * c..(k + 1) * c].to_vec();
            cal.apply(wi.z as f32, wo.z as f32, &mut f);
            for (x, y) in f.iter().zip(&a[k * c..(k + 1) * c]) {
                assert!((x - y).abs() <= 1e-6 * y.abs(), "{k}: {x} vs {y}");
            }
            differ += (b[k * c..(k + 1) * c] != a[k * c..(k + 1) * c]) as usize;
        }
        assert!(differ > PAIRS / 2, "{differ} of {PAIRS} lookups changed");
    }

    #[test]
    fn a_wrong_count_or_a_non_finite_value_is_an_error_naming_values() {
        let t = &tables()[0].1;
        let n = t.values().len();
        let name = |e: Error| match e {
            Error::InvalidArgument { name, msg } => (name, msg),
            e => panic!("{e}"),
        };
        let (field, msg) = name(refused(t.with_values(vec![0.5; n - 1])));
        assert_eq!(field, "values");
        assert!(msg.contains(&format!("{}", n - 1)), "{msg}");
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let mut v = t.values().to_vec();
            v[n / 2 + 1] = bad;
            let (field, msg) = name(refused(t.with_values(v)));
            assert_eq!(field, "values");
            assert!(msg.contains(&format!("values[{}]", n / 2 + 1)), "{msg}");
        }
        let shape = t.shape().unwrap();
        let mut wrong = shape.to_vec();
        wrong.swap(1, 3);
        let (field, msg) = name(refused(t.with_array(&wrong, t.values().to_vec())));
        assert!(
            field == "values" && msg.contains(&format!("{shape:?}")),
            "{msg}"
        );
        // Negative values are kept as they are (unmeasured nodes of an f_r table).
        let mut v = t.values().to_vec();
        v[3] = -1.0;
        assert_eq!(t.with_values(v).unwrap().values()[3], -1.0);
    }

    /// A packed table (`inout` reciprocal: the triangle θi ≤ θo) takes its stored values flat
    /// or the whole rectangle, as the export writes it: unstored nodes ignored, NaN included,
    /// and a NaN at a stored node named by its index in the rectangle.
    #[test]
    fn a_packed_table_takes_the_rectangle_and_ignores_its_unstored_nodes() {
        let sym = Symmetry {
            isotropic: true,
            reciprocal: true,
            bilateral: false,
        };
        let g = Grid::with_sizes(
            Param::InOut,
            [6, 1, 6, 8],
            [Mapping::Uniform, Mapping::Uniform],
            crate::spectrum::Channels::Rgb,
            sym,
        )
        .unwrap();
        let t = Table::from_fn(g, "ramp", |i, _, out| {
            for (c, o) in out.iter_mut().enumerate() {
                *o = (i[0] * 1000 + i[2] * 100 + i[3] * 10 + c) as f32;
            }
        });
        assert!(t.grid().layout().packed && t.shape().is_none());
        let [n0, n1, n2, n3] = t.grid().stored_shape();
        let shape = [n0, n1, n2, n3, 3];
        let mut rect = vec![f32::NAN; shape.iter().product()];
        for (k, idx) in rectangle_nodes(t.grid()).enumerate() {
            if let Some(v) = t.node(idx) {
                rect[k * 3..k * 3 + 3].copy_from_slice(v);
            }
        }
        let back = t.with_array(&shape, rect.clone()).unwrap();
        assert_eq!(back.values(), t.values());
        let flat = t
            .with_array(&[t.values().len()], t.values().to_vec())
            .unwrap();
        assert_eq!(flat.values(), t.values());
        // A row of channels per stored node, as a source evaluated at the stored nodes gives.
        let nodes = t.grid().stored_node_angles().len();
        let rows = t.with_array(&[nodes, 3], t.values().to_vec()).unwrap();
        assert_eq!(rows.values(), t.values());
        let e = refused(t.with_array(&[3, nodes], t.values().to_vec())).to_string();
        assert!(
            e.contains(&format!("[{nodes}, 3] (a row of channels")),
            "{e}"
        );
        // Node [2, 0, 1, 0] lies below the diagonal (not stored); [2, 0, 3, 0] is stored.
        let at = |idx: [usize; 4]| ((idx[0] * n1 + idx[1]) * n2 + idx[2]) * n3 + idx[3];
        assert!(t.node([2, 0, 1, 0]).is_none() && t.node([2, 0, 3, 0]).is_some());
        rect[at([2, 0, 1, 0]) * 3] = 7.0;
        assert_eq!(
            t.with_array(&shape, rect.clone()).unwrap().values(),
            t.values()
        );
        rect[at([2, 0, 3, 0]) * 3 + 1] = f32::NAN;
        let e = refused(t.with_array(&shape, rect.clone()));
        let e = e.to_string();
        assert!(e.contains("values[2, 0, 3, 0, 1] is NaN"), "{e}");
        assert_eq!(
            first_nonfinite_at(t.grid(), &shape, &rect).unwrap(),
            Some((at([2, 0, 3, 0]) * 3 + 1, "[2, 0, 3, 0, 1]".to_owned()))
        );
    }
}
