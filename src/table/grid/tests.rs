//! Tests of grids: the lecture's node counts, the stored layout's order and offsets, MERL's
//! indices, coordinate round trips, the JSON form, and inconsistent grids refused.

use super::*;
use std::f64::consts::{FRAC_PI_2, PI};

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
