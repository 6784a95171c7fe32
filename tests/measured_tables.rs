//! Tables of measured materials with the defaults (issue: measured data in dense tables): an
//! RGL file bakes on an adaptive grid, into a file no larger than the measurement, within 1%
//! of the measurement's own evaluation, held in under 4 MB while evaluating — and the warps
//! survive the file round trip.

use brdftab::analysis::accuracy::{Weight, compare_weighted};
use brdftab::bake::{BakeRequest, BakeTarget, GridChoice};
use brdftab::source::{self, OpenOptions};
use brdftab::table::{Mapping, kernel::Kernel};
use brdftab::{Brdf, Error, measured};

fn tmp(name: &str) -> String {
    let d = std::env::temp_dir().join(format!("brdftab-measured-tables-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name).to_string_lossy().into_owned()
}

/// Bakes `file` with the defaults; returns (table path, report).
fn bake_default(file: &str) -> (String, brdftab::bake::BakeReport) {
    let rgl = measured::data::rgl_file(file).unwrap_or_else(|e| panic!("{e}"));
    let out = tmp(&format!("{file}.btdb"));
    let r = BakeRequest::new(rgl.to_string_lossy())
        .run(&BakeTarget::File(out.clone()))
        .unwrap();
    (out, r)
}

#[test]
fn rgl_defaults_meet_size_error_and_memory_bars() {
    // Every shipped RGL file: the bars of the issue, on the metric it states.
    let dir = measured::data::rgl_dir().expect("the shipped data/rgl");
    let files = brdftab::report::measured::rgl_files(&dir).unwrap();
    assert_eq!(files.len(), 7, "the seven shipped RGL files");
    for f in files {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        let (out, report) = bake_default(&name);
        assert!(
            matches!(report.grid.stored_axes()[0].mapping, Mapping::Warp(_)),
            "{name}: the default grid of an RGL file is adaptive"
        );
        // Its node counts come from the default error target, which the search met.
        let t = report.target.as_ref().expect("the default bake searched");
        assert_eq!(t.target, brdftab::bake::MEASURED_TARGET_ERROR);
        assert!(t.met && t.error <= t.target, "{name}: {}", t.summary());
        assert_eq!(report.grid.stored_shape()[0], t.nodes[0]);
        let rgl_bytes = std::fs::metadata(&f).unwrap().len();
        let table_bytes = std::fs::metadata(&out).unwrap().len();
        assert!(
            table_bytes <= rgl_bytes,
            "{name}: {table_bytes} > {rgl_bytes} bytes"
        );
        let native = source::open(&f.to_string_lossy()).unwrap();
        let table = source::open_table(&out, &OpenOptions::default()).unwrap();
        // 100 000 pairs, as the search estimates it: on the near-mirror `cg_sunflower` one pair
        // on the 0.4°-wide peak can carry most of a 20 000-pair figure (draws of 20 000 pairs
        // on one table scatter from 0.3 % to 4.6 %; BENCHMARKS.md).
        let e = compare_weighted(
            &table,
            native.as_ref(),
            100_000,
            1,
            80f64.to_radians(),
            Weight::CosInCosOut,
        )
        .unwrap();
        assert!(
            e.rel_rmse <= 0.01,
            "{name}: error {:.3}%",
            e.rel_rmse * 100.0
        );
        assert!(
            table.resident_bytes() <= 4 << 20,
            "{name}: {} bytes",
            table.resident_bytes()
        );
        assert!(table.resident_bytes() > 0, "{name}: evaluated, so loaded");
    }
}

#[test]
fn rgl_defaults_are_faithful_over_the_whole_hemisphere() {
    // Issue #22's figures beyond the 80° cap, each file's default table against the native
    // reader. The whole-hemisphere bar (1.5 %) is met; the grazing-band (3 %) and albedo (1 %)
    // bars are not yet met on every file (see BENCHMARKS.md, "Measured tables at every angle"):
    // until they are, this pins today's levels — far below where the defaults were before
    // (grazing 6–186 %, albedo 3–19 %) — so that no change can slide back unnoticed.
    let dir = measured::data::rgl_dir().expect("the shipped data/rgl");
    for f in brdftab::report::measured::rgl_files(&dir).unwrap() {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        let (out, _) = bake_default(&name);
        let native = source::open(&f.to_string_lossy()).unwrap();
        let table = source::open_table(&out, &OpenOptions::default()).unwrap();
        let opts = brdftab::analysis::fidelity::FidelityOptions {
            pairs: 100_000,
            ..Default::default()
        };
        let fi = brdftab::analysis::fidelity::measure(&table, native.as_ref(), &opts).unwrap();
        let s = fi.summary();
        assert!(fi.cap <= 0.01, "{name}: {s}");
        assert!(fi.whole <= 0.015, "{name}: {s}");
        assert!(fi.grazing <= 0.06, "{name}: {s}");
        assert!(fi.albedo.worst <= 0.05, "{name}: {s}");
    }
}

#[test]
fn the_warps_survive_the_file_and_select_the_fast_lookup() {
    let (out, report) = bake_default("paper_white_rgb.bsdf");
    let table = source::open_table(&out, &OpenOptions::default()).unwrap();
    assert_eq!(
        table.grid(),
        &report.grid,
        "the grid reads back equal, warps included"
    );
    assert!(Kernel::new(table.grid()).is_some());
    // Nearest lookups on the same table take the general path and stay close to linear.
    let near = source::open_table(
        &out,
        &OpenOptions {
            interp: brdftab::table::Interp::Nearest,
            ..Default::default()
        },
    )
    .unwrap();
    let wi = glam::DVec3::new(0.3, 0.1, (1.0f64 - 0.1).sqrt());
    let wo = glam::DVec3::new(-0.2, -0.1, (1.0f64 - 0.05).sqrt());
    let (mut a, mut b) = ([0f32; 3], [0f32; 3]);
    table.eval(wi, wo, &mut a);
    near.eval(wi, wo, &mut b);
    for k in 0..3 {
        assert!(
            a[k] > 0.0 && (a[k] - b[k]).abs() <= 0.1 * a[k],
            "{a:?} {b:?}"
        );
    }
}

#[test]
fn adaptive_grids_need_bilateral_isotropy_and_model_specs_keep_the_preset() {
    // A model spec's default grid is the preset, not adaptive.
    let r = BakeRequest::new(r#"{"model": "ggx", "alpha": 0.2}"#)
        .table(&brdftab::progress::Silent)
        .unwrap()
        .1;
    assert!(!matches!(r.grid.stored_axes()[0].mapping, Mapping::Warp(_)));
    // Asked for, an adaptive grid serves a model too.
    let (t, r) = BakeRequest::new(r#"{"model": "ggx", "alpha": 0.2}"#)
        .grid(GridChoice::Adaptive(Some([16, 12, 7])))
        .table(&brdftab::progress::Silent)
        .unwrap();
    assert!(matches!(r.grid.stored_axes()[0].mapping, Mapping::Warp(_)));
    assert_eq!(t.grid().stored_shape(), [16, 1, 12, 7]);
    // An anisotropic source cannot have one.
    let e = BakeRequest::new(r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#)
        .grid(GridChoice::Adaptive(None))
        .table(&brdftab::progress::Silent)
        .unwrap_err();
    assert!(matches!(e, Error::InvalidArgument { .. }), "{e}");
}
