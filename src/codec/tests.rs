//! Tests of the codec pipeline: round trips within each quantizer's bound (property tests on
//! adversarial values), and damaged or garbage chunks refused, never a panic.

use super::*;
use proptest::prelude::*;

fn codec(quant: Quant) -> Codec {
    Codec {
        quant,
        level: 1,
        ..Codec::default()
    }
}

/// A log16 tolerance or floor out of range is an argument error when the codec is named,
/// not an encode error after the bake (`codec="log16:0"` failed only once the table was
/// baked).
#[test]
fn log16_settings_are_checked_when_parsed() {
    let named = |r: Result<Quant>| match r {
        Err(Error::InvalidArgument { name, .. }) => name,
        other => panic!("{other:?}"),
    };
    for t in [0.0, -1e-3, 0.6, f64::NAN, f64::INFINITY] {
        assert_eq!(
            named(Quant::parse("log16", Some(t), None)),
            "codec_tolerance"
        );
    }
    for f in [0.0, -1.0, f64::NAN] {
        assert_eq!(named(Quant::parse("log16", None, Some(f))), "floor");
    }
    assert!(Quant::parse("log16", Some(log16::MIN_TOL), Some(1e-9)).is_ok());
    assert!(Quant::parse("log16", Some(0.5), None).is_ok());
    let req = crate::request::BakeSettings {
        codec: Some("log16:0".into()),
        ..Default::default()
    };
    // A tolerance written into the codec is the codec field's error.
    assert!(matches!(
        req.request("x.json"),
        Err(Error::InvalidArgument { ref name, .. }) if name == "codec"
    ));
}

/// Adversarial values: tiny, huge, zeros, negatives, spikes, constants.
fn adversarial() -> impl Strategy<Value = Vec<f32>> {
    let value = prop_oneof![
        Just(0.0f32),
        Just(-0.0f32),
        1e-38f32..1e-30,
        1e-8f32..1e-3,
        0.0f32..10.0,
        1e3f32..1e30,
        -1e3f32..0.0,
        Just(f32::MIN_POSITIVE),
        Just(f32::MAX),
        Just(1e-45f32),
    ];
    prop_oneof![
        proptest::collection::vec(value, 0..300),
        (
            any::<f32>().prop_filter("finite", |v| v.is_finite()),
            0usize..300
        )
            .prop_map(|(v, n)| vec![v; n]),
        (0usize..300, 0usize..300, 1e-3f32..1e6).prop_map(|(n, at, s)| {
            let mut v: Vec<f32> = (0..n)
                .map(|i| 0.1 + (i as f32 * 0.05).sin().abs())
                .collect();
            if at < n {
                v[at] = s;
            }
            v
        }),
    ]
}

fn layouts() -> impl Strategy<Value = Layout> {
    (1usize..4, 1usize..20, 1usize..6).prop_map(|(c, i, n)| Layout::new(c, i, n))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn f32_round_trip_is_bit_exact(data in adversarial(), layout in layouts(),
                                   f in proptest::option::of(0u8..Filter::ALL.len() as u8)) {
        let c = Codec { filter: f.and_then(Filter::from_u8), ..codec(Quant::F32) };
        let b = encode(&data, layout, &c).unwrap();
        let back = decode(&b, data.len()).unwrap();
        prop_assert_eq!(
            back.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            data.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
    }

    #[test]
    fn f16_round_trip_within_one_step(data in adversarial(), layout in layouts()) {
        let data: Vec<f32> = data.into_iter().filter(|v| v.abs() <= 65504.0).collect();
        let b = encode(&data, layout, &codec(Quant::F16)).unwrap();
        let back = decode(&b, data.len()).unwrap();
        for (a, b) in data.iter().zip(&back) {
            // Half of an f16 ulp relative (2^-11) or the subnormal step 2^-24 / 2.
            let bound = (a.abs() * 2f32.powi(-11)).max(2f32.powi(-25));
            prop_assert!((a - b).abs() <= bound, "{} -> {}", a, b);
        }
    }

    #[test]
    fn log16_within_bound_for_every_value(data in adversarial(), layout in layouts(),
                                           tol in prop_oneof![Just(1e-3), 1e-4f64..0.1]) {
        let c = codec(Quant::Log16 { tolerance: tol, floor: None });
        let b = match encode(&data, layout, &c) {
            Ok(b) => b,
            Err(e) => { prop_assert!(e.to_string().contains("exactly"), "{}", e); return Ok(()); }
        };
        let info = chunk_info(&b).unwrap();
        let floor = info.log16.unwrap().floor;
        let back = decode(&b, data.len()).unwrap();
        for (a, b) in data.iter().zip(&back) {
            let (a, b) = (*a as f64, *b as f64);
            prop_assert!((a - b).abs() <= tol * a.abs().max(floor),
                         "{} -> {} (tol {}, floor {})", a, b, tol, floor);
        }
    }

    #[test]
    fn bit_shuffle_round_trips(data in adversarial(), layout in layouts()) {
        let data: Vec<f32> = data.into_iter().filter(|v| v.abs() <= 65504.0).collect();
        for q in [Quant::F32, Quant::F16] {
            let c = Codec { shuffle: Some(Shuffle::Bit), ..codec(q) };
            let b = encode(&data, layout, &c).unwrap();
            let back = decode(&b, data.len()).unwrap();
            let again = decode(&encode(&back, layout, &c).unwrap(), data.len()).unwrap();
            prop_assert_eq!(back, again);
        }
    }

    /// Valid chunks of every quantizer and filter with any header byte set to anything and
    /// payload bytes flipped: decoding returns an error or values, never panics.
    #[test]
    fn damaged_chunks_never_panic(data in adversarial(), layout in layouts(),
                                  q in 0usize..3, f in 0u8..Filter::ALL.len() as u8,
                                  edits in proptest::collection::vec(
                                      (any::<usize>(), any::<u8>()), 1..4)) {
        let quant = [Quant::F32, Quant::F16, Quant::Log16 { tolerance: 1e-2, floor: None }][q];
        let data: Vec<f32> = data.into_iter().filter(|v| v.abs() <= 65504.0).collect();
        let c = Codec { filter: Filter::from_u8(f), ..codec(quant) };
        let Ok(mut b) = encode(&data, layout, &c) else { return Ok(()) };
        for (at, v) in edits {
            let at = if at % 2 == 0 { at % CHUNK_HEADER_LEN } else { at % b.len() };
            b[at] = v;
        }
        let _ = decode(&b, data.len());
    }

    #[test]
    fn decode_never_panics_on_garbage(bytes in proptest::collection::vec(any::<u8>(), 0..200),
                                      n in 0usize..1000) {
        let _ = decode(&bytes, n);
    }
}

#[test]
fn smooth_data_picks_a_predictor_and_compresses() {
    let (ch, inner, next) = (3, 180, 90);
    let data: Vec<f32> = (0..next * inner * ch)
        .map(|k| {
            let (j, i, c) = (k / (inner * ch), (k / ch) % inner, k % ch);
            (1.0 + c as f32) * (-((i as f32 - 90.0).powi(2) + (j as f32).powi(2)) / 800.0).exp()
        })
        .collect();
    let b = encode(&data, Layout::new(ch, inner, next), &Codec::default()).unwrap();
    let info = chunk_info(&b).unwrap();
    assert_ne!(info.filter, Filter::None);
    assert!(b.len() * 5 < data.len() * 4, "{} bytes", b.len());
}

#[test]
fn chunk_versions_outside_the_readable_range_are_refused() {
    let mut b = encode(&[1.0, 2.0], Layout::FLAT, &Codec::default()).unwrap();
    assert_eq!(chunk_info(&b).unwrap().version, CHUNK_VERSION);
    for v in [0, CHUNK_VERSION + 1, 255] {
        b[2] = v;
        let e = decode(&b, 2).unwrap_err().to_string();
        assert!(e.contains("chunk version"), "{e}");
    }
    b[2] = CHUNK_VERSION_MIN;
    assert_eq!(decode(&b, 2).unwrap(), [1.0, 2.0]);
}

#[test]
fn wrong_expected_length_is_refused_before_allocating() {
    let b = encode(&[1.0, 2.0], Layout::FLAT, &Codec::default()).unwrap();
    let e = decode(&b, usize::MAX / 8).unwrap_err().to_string();
    assert!(e.contains("expected"), "{e}");
}
