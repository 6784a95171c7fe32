//! log16's unit tests: zeros, escapes, NaN, negatives, the log mapping, rough and smooth data.

use super::*;
use crate::codec::filter::{self, Layout, Word};
use proptest::prelude::*;

fn decoded(q: &Encoded, layout: Layout) -> Vec<f32> {
    let mut out = vec![0.0; q.codes.len()];
    decode(
        &q.codes, &q.params, layout, q.filter, &q.escapes, &q.anchors, &mut out,
    );
    out
}

proptest! {
    /// Without escapes, log16's prediction loop is the integer filter of the same id applied
    /// to the grid indices: the chooser's proxy is exact, and the two implementations agree.
    #[test]
    fn codes_are_the_filter_residuals_of_the_grid_indices(
        n in 0usize..400, ch in 1usize..5, inner in 1usize..12, next in 1usize..4,
        f in 0u8..8, freq in 0.01f32..0.5, tol in prop_oneof![Just(1e-3), Just(1e-2)],
    ) {
        let data: Vec<f32> = (0..n).map(|k| 1.0 + 0.5 * (k as f32 * freq).sin()).collect();
        let layout = Layout::new(ch, inner, next);
        let filter = Filter::from_u8(f).unwrap();
        let q = encode(&data, layout, tol, None, Some(filter)).unwrap();
        prop_assert!(q.escapes.is_empty());
        let k: Vec<u16> = data
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                let lo = q.anchors[i % ch];
                ((to_log(v as f64, q.params.floor) - lo) / q.params.step).round() as i64 as u16
            })
            .collect();
        let mut want = filter::forward(&k, layout, filter);
        if filter == Filter::None {
            want.iter_mut().for_each(|w| *w = w.zigzag());
        }
        prop_assert_eq!(&q.codes, &want);
        for (a, b) in data.iter().zip(decoded(&q, layout)) {
            prop_assert!((a - b).abs() as f64 <= tol * (*a as f64));
        }
    }

    /// Every filter keeps the bound and the sign, on data with zeros, tiny values of both
    /// signs around the floor, and jumps larger than 16-bit residuals (tolerance 1e-5).
    #[test]
    fn every_filter_keeps_the_bound_and_the_sign(
        data in proptest::collection::vec(prop_oneof![
            Just(0.0f32), -1e-6f32..1e-6, 0.5f32..2.0, 1e20f32..1e30, -1e3f32..-1e-3,
        ], 0..200),
        ch in 1usize..4, inner in 1usize..10, f in 0u8..8,
        tol in prop_oneof![Just(1e-5), Just(1e-3), Just(0.1)],
    ) {
        let layout = Layout::new(ch, inner, 3);
        let filter = Filter::from_u8(f).unwrap();
        let q = match encode(&data, layout, tol, Some(1e-4), Some(filter)) {
            Ok(q) => q,
            Err(e) => {
                prop_assert!(e.to_string().contains("exactly"), "{}", e);
                return Ok(());
            }
        };
        for (a, b) in data.iter().zip(decoded(&q, layout)) {
            let (a, b) = (*a as f64, b as f64);
            prop_assert!((a - b).abs() <= tol * a.abs().max(1e-4), "{} -> {}", a, b);
            prop_assert!(a * b >= 0.0, "{} -> {} changed sign", a, b);
        }
    }
}

#[test]
fn zero_and_values_far_below_the_floor_decode_to_exactly_zero_without_escapes() {
    let v: Vec<f32> = (0..300)
        .map(|i| match i % 3 {
            0 => 0.0,
            1 => 1e-14 * (i as f32),
            _ => 1.0 + (i as f32 * 0.01).sin(),
        })
        .collect();
    let layout = Layout::new(3, 20, 5);
    for filter in Filter::ALL {
        let q = encode(&v, layout, 1e-3, None, Some(filter)).unwrap();
        assert!(q.escapes.is_empty(), "{filter:?}: {:?}", q.escapes);
        let out = decoded(&q, layout);
        for (i, (a, b)) in v.iter().zip(&out).enumerate() {
            if i % 3 != 2 {
                assert_eq!(*b, 0.0, "{filter:?} [{i}]: {a} -> {b}");
            }
        }
    }
}

#[test]
fn an_overflowing_residual_escapes_and_later_values_recover() {
    // Tolerance 1e-5 and an explicit floor of 1e-30: the first value (predicted from 0) and
    // the jumps to and from 1e30 are millions of steps, far beyond a 16-bit residual. Those
    // three are escaped; the decoder recovers their exact grid index, so the rest is coded.
    let mut v = vec![1.0f32; 60];
    v[30] = 1e30;
    let q = encode(&v, Layout::FLAT, 1e-5, Some(1e-30), Some(Filter::Delta)).unwrap();
    let at: Vec<u32> = q.escapes.iter().map(|e| e.0).collect();
    assert_eq!(at, [0, 30, 31]);
    assert!(q.codes[1..30].iter().all(|&c| c == 0));
    let out = decoded(&q, Layout::FLAT);
    for (a, b) in v.iter().zip(&out) {
        assert!(((a - b).abs() as f64) <= 1e-5 * *a as f64, "{a} -> {b}");
    }
}

#[test]
fn nan_is_refused_naming_the_index() {
    let e = encode(&[0.0, 0.0, f32::NAN], Layout::FLAT, 1e-3, None, None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("index 2") && e.contains("NaN"), "{e}");
}

#[test]
fn negatives_are_coded_within_the_bound() {
    let v = [1.0, -0.5, 2.0, -1e-9, -3e5];
    let q = encode(&v, Layout::FLAT, 1e-3, None, None).unwrap();
    let mut out = [0.0; 5];
    decode(
        &q.codes,
        &q.params,
        Layout::FLAT,
        q.filter,
        &q.escapes,
        &q.anchors,
        &mut out,
    );
    for (a, b) in v.iter().zip(&out) {
        assert!(
            ((a - b).abs() as f64) <= 1e-3 * (a.abs() as f64).max(q.params.floor),
            "{a} {b}"
        );
    }
}

#[test]
fn mapping_is_monotone_and_inverts() {
    let f = 1e-3;
    let mut prev = f64::NEG_INFINITY;
    for k in -2000..2000 {
        let v = (k as f64 / 100.0).sinh() * 1e-3;
        let y = to_log(v, f);
        assert!(y > prev);
        prev = y;
        assert!((from_log(y, f) as f64 - v).abs() <= 1e-6 * v.abs().max(f));
    }
}

#[test]
fn rough_data_fails_clearly() {
    // Alternating ±1e30 / tiny at a tight tolerance: residuals overflow 16 bits.
    let v: Vec<f32> = (0..100)
        .map(|i| if i % 2 == 0 { 1e30 } else { -1e30 })
        .collect();
    let e = encode(&v, Layout::FLAT, 1e-6, Some(1e-30), Some(Filter::Delta))
        .unwrap_err()
        .to_string();
    assert!(e.contains("exactly"), "{e}");
}

#[test]
fn smooth_data_gives_small_residuals() {
    let v: Vec<f32> = (0..1000)
        .map(|i| (-(i as f32 - 500.0).powi(2) / 5e4).exp())
        .collect();
    let q = encode(&v, Layout::new(1, 100, 10), 1e-3, None, None).unwrap();
    let small = q.codes.iter().filter(|&&c| c <= 8).count();
    assert!(small > 850, "{small}");
    let mut out = vec![0.0; v.len()];
    decode(
        &q.codes,
        &q.params,
        Layout::new(1, 100, 10),
        q.filter,
        &q.escapes,
        &q.anchors,
        &mut out,
    );
    for (a, b) in v.iter().zip(&out) {
        assert!((a - b).abs() as f64 <= 1e-3 * (*a as f64).max(q.params.floor));
    }
}
