//! The anchored grids' unit tests (chunk version 3): constant channels and the most common
//! value decode exactly, and how the most common value is counted.

use super::encoder::most_common;
use super::*;
use crate::codec::filter::Layout;

fn round_trip(data: &[f32], layout: Layout, tol: f64) -> (Encoded, Vec<f32>) {
    let q = encode(data, layout, tol, None, None).unwrap();
    let mut out = vec![0.0; data.len()];
    decode(
        &q.codes, &q.params, layout, q.filter, &q.escapes, &q.anchors, &mut out,
    );
    (q, out)
}

/// A constant chunk per channel (a Lambert table) decodes bit for bit, without escapes, at
/// every tolerance, for channels up to 10^7 apart (the floor is 10^-7 of the largest value;
/// far below it the bound is absolute and a value may decode to 0).
#[test]
fn constant_channels_decode_exactly() {
    for kd in [[0.1f32, 0.2, 0.3], [1e-6, 3.0e-5, 7.5], [4.0e4, 0.5, 1e-3]] {
        let data: Vec<f32> = (0..3 * 90 * 46).map(|i| kd[i % 3]).collect();
        for tol in [1e-3, 1e-2, 0.1] {
            let (q, out) = round_trip(&data, Layout::new(3, 46, 90), tol);
            assert!(q.escapes.is_empty(), "{kd:?} {tol}");
            for (a, b) in data.iter().zip(&out) {
                assert_eq!(a.to_bits(), b.to_bits(), "{kd:?} tol {tol}");
            }
        }
    }
}

/// The value a channel repeats most decodes exactly amid others (here 40 % of the values;
/// Misra–Gries with 4 counters finds anything above 20 %), zeros stay exactly 0, and every
/// other value keeps the bound.
#[test]
fn the_most_common_value_and_zero_decode_exactly() {
    let mut rng = crate::rng::Pcg32::new(9);
    let rec = 0.123_456_79f32;
    let data: Vec<f32> = (0..5000)
        .map(|_| match rng.next_u32() % 10 {
            0..=3 => rec,
            4 => 0.0,
            _ => 1e-3 + rng.next_f64() as f32,
        })
        .collect();
    let tol = 1e-3;
    let (q, out) = round_trip(&data, Layout::new(1, 100, 50), tol);
    assert_ne!(q.anchors[0], 0.0);
    for (a, b) in data.iter().zip(&out) {
        if *a == rec || *a == 0.0 {
            assert_eq!(a.to_bits(), b.to_bits());
        } else {
            assert!(((a - b).abs() as f64) <= tol * (*a as f64), "{a} {b}");
        }
    }
}

#[test]
fn most_common_counts_exactly_and_needs_a_repeat() {
    assert_eq!(most_common(&[1.0, 2.0, 3.0], 0, 1), None);
    assert_eq!(
        most_common(&[1.0, 2.0, 1.0, 2.0, 1.0], 0, 1),
        Some((1.0, 3))
    );
    // Channel 1 of an interleaved pair.
    assert_eq!(
        most_common(&[5.0, 7.0, 6.0, 7.0, 5.0, 8.0], 1, 2),
        Some((7.0, 2))
    );
    assert_eq!(most_common(&[], 0, 1), None);
}
