//! Nodes beyond the horizon of an f_r cos θi cos θo table: linear extrapolation of the
//! physical ones.
//!
//! A `halfdiff` node whose pair has a direction at or below the horizon has no value of its own;
//! it matters only through the cells it shares with physical nodes, where a lookup blends it in.
//! Baked at its pair lifted to the horizon ([`super::pair_of`]), it holds the source's value
//! *at* the horizon. For f_r cos θi cos θo ([`Quantity::FrCosCos`]) that is about 0 wherever
//! the quantity vanishes there (a bounded f_r), and holding 0 beyond a boundary the values
//! cross linearly puts a positive bias into every cell the horizon cuts: an RGL table's albedo
//! came out 30–70 % high at θ′ = 89°.
//!
//! For fixed θh, φh and φd the pair leaves the upper hemisphere once as θd grows (one cosine is
//! R cos(θd + δ) with δ ≥ 0, the other stays positive up to θd = 90°), so the physical nodes of
//! such a θd line are a prefix. [`HorizonFill`] continues each line's last physical cell
//! linearly, in node-index space — the space in which the lookup is linear — so that a cut
//! cell's interpolant is the continuation of its neighbour's. A line with fewer than two
//! physical nodes (θh near 90°, where nearly nothing is physical) is continued along θh from
//! the two previous θh nodes instead, and a line with neither is left as baked.
//! The extrapolated values may be negative; lookups of such tables clamp f_r at 0.

use crate::geometry::{self, HalfDiff};
use crate::table::grid::{Grid, Param, Quantity};

/// Fills the nodes beyond the horizon of one chunk (θh node) after another, in order.
pub(crate) struct HorizonFill<'g> {
    grid: &'g Grid,
    /// The two previous chunks' filled values (chunk k − 1, then k − 2), when they exist.
    prev: [Option<Vec<f32>>; 2],
}

impl<'g> HorizonFill<'g> {
    /// The fill of `grid`, when it needs one: an f_r cos θi cos θo `halfdiff` grid.
    pub(crate) fn new(grid: &'g Grid) -> Option<HorizonFill<'g>> {
        (grid.quantity() != Quantity::Fr && grid.param() == Param::HalfDiff).then_some(
            HorizonFill {
                grid,
                prev: [None, None],
            },
        )
    }

    /// Whether the node `idx` has both directions above the horizon.
    fn physical(&self, idx: [usize; 4]) -> bool {
        let c = self.grid.node_angles(idx);
        let (wi, wo) = geometry::from_half_diff(HalfDiff {
            theta_h: c[0],
            phi_h: c[1],
            theta_d: c[2],
            phi_d: c[3],
        });
        wi.z > 0.0 && wo.z > 0.0
    }

    /// Fills chunk `chunk` (its values in layout order); chunks must come in order.
    pub(crate) fn fill(&mut self, chunk: usize, values: &mut [f32]) {
        let l = self.grid.layout();
        let c = l.channels;
        let [_, n1, n2, n3] = l.shape;
        let at = |p: usize, b: usize, q: usize| ((p * n2 + b) * n3 + q) * c;
        for p in 0..n1 {
            for q in 0..n3 {
                // The physical prefix of the θd line (p, ·, q).
                let mut m = 0;
                while m < n2 && self.physical([chunk, p, m, q]) {
                    m += 1;
                }
                if m == n2 {
                    continue;
                }
                for b in m..n2 {
                    for k in 0..c {
                        let v = if m >= 2 {
                            // Along θd: v(m − 1) + (b − m + 1)·(v(m − 1) − v(m − 2)).
                            let v1 = values[at(p, m - 1, q) + k];
                            let v2 = values[at(p, m - 2, q) + k];
                            v1 + (b - m + 1) as f32 * (v1 - v2)
                        } else if let [Some(a), Some(z)] = &self.prev {
                            // Along θh from the two previous θh nodes.
                            let o = at(p, b, q) + k;
                            2.0 * a[o] - z[o]
                        } else if m == 1 {
                            values[at(p, 0, q) + k]
                        } else {
                            continue;
                        };
                        values[at(p, b, q) + k] = v;
                    }
                }
            }
        }
        let done = values.to_vec();
        self.prev.swap(0, 1);
        self.prev[0] = Some(done);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Brdf;
    use crate::models::lambert::Lambert;
    use crate::spectrum::{Channels, Value};
    use crate::table::symmetry::Symmetry;
    use crate::table::{Axis, BakeOptions, Mapping, Nodes, TabulatedBrdf, bake};

    fn grid(n: [usize; 3]) -> Grid {
        grid_of(n, Quantity::FrCosCos)
    }

    fn grid_of(n: [usize; 3], quantity: Quantity) -> Grid {
        let sym = Symmetry {
            isotropic: true,
            reciprocal: false,
            bilateral: true,
        };
        Grid::new(
            Param::HalfDiff,
            [
                Axis::theta(n[0], Mapping::Uniform, Nodes::Edges),
                Axis::phi(2 * (n[2] - 1)),
                Axis::theta(n[1], Mapping::Uniform, Nodes::Centers),
                Axis::phi(2 * (n[2] - 1)),
            ],
            Channels::Rgb,
            sym,
        )
        .unwrap()
        .with_quantity(quantity)
        .unwrap()
    }

    #[test]
    fn a_lambertian_table_keeps_its_albedo_to_the_horizon() {
        // f_r cos θi cos θo of Lambert vanishes linearly at the horizon; held at 0 beyond it,
        // the cut cells are too bright and a(89°) is far off; extrapolated, it is within the
        // interpolation error of a 1° cell. The albedo at θ′ divides that quantity by cos θ′,
        // which magnifies its interpolation error 57× at 89°: f_r cos θi cos θo is checked to
        // 85°, f_r cos θo (which does not vanish as wi nears the horizon) to 89°.
        for (quantity, last) in [(Quantity::FrCosCos, 85.0), (Quantity::FrCosOut, 89.0)] {
            lambert_albedo(quantity, last);
        }
    }

    fn lambert_albedo(quantity: Quantity, last: f64) {
        let l = Lambert::new(Value::Grey(0.5), &Channels::Rgb).unwrap();
        let (t, _) = bake(
            &l,
            &grid_of([91, 90, 46], quantity),
            &BakeOptions::default(),
        )
        .unwrap();
        let tb = TabulatedBrdf::from_table(t);
        for deg in [30.0f64, 60.0, 80.0, 85.0, 89.0]
            .into_iter()
            .filter(|&d| d <= last)
        {
            let wi = geometry::spherical(deg.to_radians(), 0.0);
            let mut a = [0.0; 3];
            crate::analysis::albedo::quadrature(&tb, wi, &mut a);
            let want = 0.5 * std::f64::consts::PI;
            assert!(
                (a[0] - want).abs() < 0.01 * want,
                "{quantity:?} {deg}°: {} vs {want}",
                a[0]
            );
        }
        let mut f = [0f32; 3];
        tb.eval(
            geometry::spherical(89.5f64.to_radians(), 0.0),
            geometry::spherical(30f64.to_radians(), 2.0),
            &mut f,
        );
        assert!((f[0] - 0.5).abs() < 0.02, "{f:?}");
    }

    #[test]
    fn physical_nodes_are_left_as_baked_and_only_fr_cos_cos_grids_are_filled() {
        let g = grid([9, 8, 5]);
        assert!(HorizonFill::new(&g.clone().with_quantity(Quantity::Fr).unwrap()).is_none());
        let mut h = HorizonFill::new(&g).unwrap();
        let l = g.layout();
        let mut v: Vec<f32> = (0..l.chunk_len(3)).map(|i| i as f32).collect();
        let before = v.clone();
        h.fill(3, &mut v);
        let c = l.channels;
        let [_, _, n2, n3] = l.shape;
        let mut filled = 0;
        for b in 0..n2 {
            for q in 0..n3 {
                let o = (b * n3 + q) * c;
                if h.physical([3, 0, b, q]) {
                    assert_eq!(v[o..o + c], before[o..o + c]);
                } else {
                    filled += 1;
                }
            }
        }
        assert!(filled > 0, "θh = 3/8·90° has nodes beyond the horizon");
        // The values are linear in b, so the continuation is the same line.
        assert_eq!(v, before);
    }
}
