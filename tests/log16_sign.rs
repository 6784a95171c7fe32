//! A BRDF table stored with log16 never decodes to a negative value: the codec is
//! sign-preserving, so a table whose source is non-negative stays non-negative.

use brdftab::codec::{self, Codec, Quant};
use brdftab::table::presets::Preset;
use brdftab::table::{BakeOptions, Param, Symmetry, bake};
use brdftab::{Channels, ModelSpec};

#[test]
fn cook_torrance_gold_table_stays_non_negative_through_log16() {
    let src =
        ModelSpec::parse(r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#)
            .unwrap()
            .build(&Channels::Rgb)
            .unwrap();
    let grid = Preset::Small
        .grid(
            Some(Param::HalfDiff),
            Symmetry::from_flags(src.flags()),
            Channels::Rgb,
        )
        .unwrap();
    let (table, _) = bake(src.as_ref(), &grid, &BakeOptions::default()).unwrap();
    for tol in [1e-2, 1e-3] {
        let codec = Codec {
            quant: Quant::Log16 {
                tolerance: tol,
                floor: None,
            },
            ..Codec::default()
        };
        let mut checked = 0;
        for a in 0..grid.layout().chunk_count() {
            let chunk = table.chunk(a);
            let layout = brdftab::store::tables::chunk_layout(&grid, a);
            let bytes = codec::encode(chunk, layout, &codec).unwrap();
            let back = codec::decode(&bytes, chunk.len()).unwrap();
            for (v, b) in chunk.iter().zip(&back) {
                assert!(*v >= 0.0);
                assert!(*b >= 0.0, "tol {tol}, chunk {a}: {v} decoded as {b}");
                checked += 1;
            }
        }
        assert_eq!(checked, table.values().len());
    }
}
