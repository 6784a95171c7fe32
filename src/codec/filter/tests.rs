//! The filters' unit tests: every filter inverts on any words, shuffles round-trip.

use super::*;
use proptest::prelude::*;

proptest! {
    #[test]
    fn filters_invert_u16(words in proptest::collection::vec(any::<u16>(), 0..400),
                          ch in 1usize..4, inner in 1usize..9, next in 1usize..5) {
        let layout = Layout::new(ch, inner, next);
        for f in Filter::ALL {
            let mut r = forward(&words, layout, f);
            inverse(&mut r, layout, f);
            prop_assert_eq!(&r, &words);
        }
    }

    #[test]
    fn filters_invert_u32(words in proptest::collection::vec(any::<u32>(), 0..400),
                          ch in 1usize..4, inner in 1usize..9, next in 1usize..5) {
        let layout = Layout::new(ch, inner, next);
        for f in Filter::ALL {
            let mut r = forward(&words, layout, f);
            inverse(&mut r, layout, f);
            prop_assert_eq!(&r, &words);
        }
    }

    /// Smooth rows with spikes and extreme words (where wrapping matters), channels up to
    /// 5, rows up to 40 points, partial trailing rows.
    #[test]
    fn filters_invert_smooth_data_with_spikes(
        n in 0usize..700, ch in 1usize..6, inner in 1usize..40, next in 1usize..6,
        spikes in proptest::collection::vec((any::<usize>(), any::<u16>()), 0..8),
        slope in -300i32..300, curve in -9i32..9,
    ) {
        let mut words: Vec<u16> = (0..n)
            .map(|k| {
                let x = ((k / ch) % inner) as i32;
                (30000 + (k % ch) as i32 * 700 + slope * x + curve * x * x) as u16
            })
            .collect();
        for (at, w) in spikes {
            if n > 0 {
                words[at % n] = w;
            }
        }
        let layout = Layout::new(ch, inner, next);
        for f in Filter::ALL {
            let mut r = forward(&words, layout, f);
            inverse(&mut r, layout, f);
            prop_assert_eq!(&r, &words, "{:?}", f);
        }
    }

    #[test]
    fn sample_is_the_residuals_of_the_sampled_rows(
        words in proptest::collection::vec(any::<u16>(), 0..500),
        ch in 1usize..4, inner in 1usize..9, next in 1usize..5, every in 1usize..6,
    ) {
        let layout = Layout::new(ch, inner, next);
        let row = ch * inner;
        let nrows = words.len().div_ceil(row);
        for f in Filter::ALL {
            let full = forward(&words, layout, f);
            let want: Vec<u16> = full
                .chunks(row)
                .enumerate()
                .filter(|(k, _)| nrows <= every || k % every == 1)
                .flat_map(|(_, r)| r.iter().copied())
                .collect();
            let mut got = vec![];
            forward_sample(&words, layout, f, every, &mut got);
            prop_assert_eq!(got, want, "{:?}", f);
        }
    }

    #[test]
    fn bitshuffle_inverts(words in proptest::collection::vec(any::<u16>(), 0..100)) {
        let mut b = vec![];
        bitshuffle(&words, &mut b);
        let mut back = vec![0u16; words.len()];
        unbitshuffle(&b, &mut back);
        prop_assert_eq!(back, words);
    }

    #[test]
    fn shuffle_inverts(words in proptest::collection::vec(any::<u32>(), 0..100)) {
        let mut b = vec![7u8];
        shuffle(&words, &mut b);
        let mut back = vec![0u32; words.len()];
        unshuffle(&b[1..], &mut back);
        prop_assert_eq!(back, words);
    }
}

#[test]
fn zigzag_maps_small_signed_to_small() {
    assert_eq!(0u16.zigzag(), 0);
    assert_eq!(u16::MAX.zigzag(), 1); // -1
    assert_eq!(1u16.zigzag(), 2);
    for w in [0u32, 1, 5, u32::MAX, 1 << 31] {
        assert_eq!(w.zigzag().unzigzag(), w);
    }
}

#[test]
fn linear_predicts_ramps_along_rows_exactly() {
    // w = 3 + 7 i (+ 1000 per channel) on rows of 6 points, 2 channels: from the third point
    // of every row on, all residuals are zero.
    let words: Vec<u16> = (0..4)
        .flat_map(|_| (0..6).flat_map(|i| (0..2).map(move |c| (3 + 7 * i + 1000 * c) as u16)))
        .collect();
    for f in [
        Filter::Linear,
        Filter::LinearChannel,
        Filter::LinearDeltaChannel,
    ] {
        let r = forward(&words, Layout::new(2, 6, 4), f);
        for row in r.chunks(12) {
            assert!(row[4..].iter().all(|&x| x == 0), "{f:?}: {row:?}");
        }
    }
}

#[test]
fn linear_delta_channel_predicts_a_curved_first_channel_with_a_constant_offset() {
    // Channel 0 a parabola along the row, channel 1 = channel 0 + an offset that varies by
    // row only: channel 0 leaves its second difference (2, zigzagged 4) from the third point
    // on, channel 1 leaves zero from the second point on (its difference to channel 0 is
    // constant along the row).
    let words: Vec<u16> = (0..3u16)
        .flat_map(|j| {
            (0..8u16).flat_map(move |i| {
                let a = 100 + 9 * i + i * i + 50 * j;
                [a, a + 17 * j * j]
            })
        })
        .collect();
    let layout = Layout::new(2, 8, 3);
    let r = forward(&words, layout, Filter::LinearDeltaChannel);
    for row in r.chunks(16) {
        assert!(row[4..].chunks(2).all(|p| p == [4, 0]), "{row:?}");
        assert_eq!(row[3], 0, "{row:?}");
    }
    let mut back = r.clone();
    inverse(&mut back, layout, Filter::LinearDeltaChannel);
    assert_eq!(back, words);
}

#[test]
fn stored_filter_bytes_keep_their_meaning() {
    for (b, f) in Filter::ALL.iter().enumerate() {
        assert_eq!(*f as usize, b);
        assert_eq!(Filter::from_u8(b as u8), Some(*f));
    }
    assert_eq!(Filter::from_u8(Filter::ALL.len() as u8), None);
    assert_eq!(Filter::from_u8(255), None);
    assert_eq!(Filter::from_u8(4), Some(Filter::PlaneChannel));
}

#[test]
fn plane_predicts_linear_ramps_exactly() {
    // w = 3 i + 5 j on a 4x6 grid, 1 channel: all residuals but the first row/col are zero.
    let words: Vec<u16> = (0..4)
        .flat_map(|j| (0..6).map(move |i| (3 * i + 5 * j) as u16))
        .collect();
    let r = forward(&words, Layout::new(1, 6, 4), Filter::Plane);
    assert!(r[7..12].iter().all(|&x| x == 0), "{r:?}");
}
