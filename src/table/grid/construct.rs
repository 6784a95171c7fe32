//! Building a [`Grid`]: [`Grid::new`] and its consistency checks, the stored axes and layout it
//! derives, and the grids built from sizes ([`Grid::with_sizes`]) and of MERL ([`Grid::merl`]).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use super::{Axis, Grid, Layout, Mapping, Nodes, Param, Quantity, StoredAxis};
use crate::error::{Error, Result};
use crate::spectrum::Channels;
use crate::table::symmetry::Symmetry;

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
}
