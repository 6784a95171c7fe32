//! `--target-error`: a bake picks the smallest adaptive grid that meets an error target, for
//! model specs and MERL files as for RGL files, and refuses requests it cannot serve.

use brdftab::analysis::accuracy::{Weight, compare_weighted};
use brdftab::bake::{BakeRequest, BakeTarget, GridChoice};
use brdftab::measured::MerlBrdf;
use brdftab::progress::Silent;
use brdftab::table::presets::Preset;
use brdftab::table::target::LADDER;
use brdftab::table::{Mapping, TabulatedBrdf};
use brdftab::testkit::TempDir;
use brdftab::{Error, source};

fn error_of(t: &TabulatedBrdf, src: &dyn brdftab::Brdf, seed: u64) -> f64 {
    compare_weighted(
        t,
        src,
        100_000,
        seed,
        80f64.to_radians(),
        Weight::CosInCosOut,
    )
    .unwrap()
    .rel_rmse
}

#[test]
fn a_model_spec_gets_the_smallest_grid_within_the_target() {
    let spec = r#"{"model": "ggx", "alpha": 0.1}"#;
    let (t, r) = BakeRequest::new(spec)
        .target_error(0.005)
        .table(&Silent)
        .unwrap();
    let s = r.target.expect("searched");
    assert!(s.met, "{}", s.summary());
    assert!(matches!(
        t.grid().stored_axes()[0].mapping,
        Mapping::Warp(_)
    ));
    assert_eq!(t.grid().stored_shape()[0], s.nodes[0]);
    // On other pairs than the search's, the table is within the target up to the estimate's
    // scatter (a smooth lobe: a few percent of it).
    let src = source::open(spec).unwrap();
    let tb = TabulatedBrdf::from_table(t);
    let e = error_of(&tb, src.as_ref(), 3);
    assert!(e <= 0.005 * 1.2, "{e}");
    // The next smaller grid of the ladder was tried and missed (unless this is the smallest).
    let k = LADDER.iter().position(|&n| n == s.nodes).unwrap();
    if k > 0 {
        let below = s
            .tried
            .iter()
            .find(|(n, _, _)| *n == LADDER[k - 1])
            .unwrap();
        assert!(below.1 > 0.005, "{}", s.summary());
    }
    // A looser target never picks a larger grid.
    let (_, r2) = BakeRequest::new(spec)
        .target_error(0.02)
        .table(&Silent)
        .unwrap();
    let n2 = r2.target.unwrap().nodes;
    let k2 = LADDER.iter().position(|&n| n == n2).unwrap();
    assert!(k2 <= k);
}

#[test]
fn a_merl_file_with_a_target_is_resampled_onto_an_adaptive_grid() {
    let dir = TempDir::new("target-error-merl");
    let path = dir.file("ct.binary");
    let model = source::open(r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2}, {"model": "cook_torrance", "m": 0.2}]}"#).unwrap();
    MerlBrdf::from_brdf(model.as_ref()).write(&path).unwrap();
    // Without a target the file keeps its own cells...
    let (_, r) = BakeRequest::new(path.as_str()).table(&Silent).unwrap();
    assert!(r.merl_cells && r.target.is_none());
    // ...with one, it gets the adaptive grid that meets it, against the MERL evaluation. That
    // is the reader's nearest lookup, a staircase over its cells: a smooth (linear) table of
    // any size stays about 2 % from it on this material, so the target here is 3 %.
    let out = dir.file("ct.btdb");
    let r = BakeRequest::new(path.as_str())
        .target_error(0.03)
        .run(&BakeTarget::file(&out))
        .unwrap();
    let s = r.target.expect("searched");
    assert!(s.met && !r.merl_cells, "{}", s.summary());
    let merl = source::open(&path).unwrap();
    let t = source::open_table(&out, &Default::default()).unwrap();
    let e = error_of(&t, merl.as_ref(), 4);
    assert!(e <= 0.03 * 1.2, "{e}");
    // Far smaller than the MERL file's 1.46 M cells × 3.
    assert!(t.grid().stored_values() < 1_000_000);
}

#[test]
fn requests_a_target_cannot_serve_are_refused() {
    let ggx = r#"{"model": "ggx", "alpha": 0.2}"#;
    let refused = |r: BakeRequest| match r.table(&Silent) {
        Err(Error::InvalidArgument { name, msg }) => {
            assert_eq!(name, "target_error", "{msg}");
        }
        other => panic!("{:?}", other.map(|x| x.1.grid.summary())),
    };
    // A fixed grid, given node counts, an anisotropic source, a non-positive target.
    refused(
        BakeRequest::new(ggx)
            .preset(Preset::Small)
            .target_error(0.01),
    );
    refused(
        BakeRequest::new(ggx)
            .grid(GridChoice::Adaptive(Some([16, 8, 5])))
            .target_error(0.01),
    );
    refused(
        BakeRequest::new(r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#)
            .target_error(0.01),
    );
    refused(BakeRequest::new(ggx).target_error(-1.0));
}

/// A model's adaptive table is judged where the model is used: over the whole hemisphere.
/// Issue 22's bars for measured tables (cos θi cos θo-weighted relative RMSE within 1.5 % over
/// the whole hemisphere and 3 % in the grazing band, directional albedo within 1 % at every θ′
/// from 1° to 89°) hold for bounded models' tables baked to a 0.1 % target. Before the grids
/// reached the horizon (θh nodes stopped at 85°, the search judged within 80° only) these
/// tables met the target inside the cap and were 5.6 % (GGX copper), 11 % (Cook-Torrance gold)
/// and 18 % (Oren-Nayar) off in the grazing band, up to 18 % in albedo.
#[test]
fn a_model_table_to_a_target_is_faithful_over_the_whole_hemisphere() {
    use brdftab::analysis::fidelity::{self, FidelityOptions};
    let opts = FidelityOptions {
        pairs: 100_000,
        seed: 7,
        ..Default::default()
    };
    for spec in [
        r#"{"model": "ggx", "alpha": 0.1, "fresnel": {"conductor": "Cu"}}"#,
        r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#,
        r#"{"model": "oren_nayar", "kd": 0.25, "sigma": 0.3}"#,
    ] {
        let (t, r) = BakeRequest::new(spec)
            .target_error(0.001)
            .table(&Silent)
            .unwrap();
        // The search judged the grazing band too (3× the target; Cook-Torrance's rule error
        // there stays at 0.5 % on the ladder's largest grid, which is then what it gets).
        let s = r.target.expect("searched");
        assert_eq!(s.grazing_target, Some(0.003), "{spec}: {}", s.summary());
        let src = source::open(spec).unwrap();
        let tb = TabulatedBrdf::from_table(t);
        let f = fidelity::measure(&tb, src.as_ref(), &opts).unwrap();
        let msg = format!("{spec}: {}", f.summary());
        assert!(f.whole <= 0.015, "{msg}");
        assert!(f.grazing <= 0.03, "{msg}");
        assert!(f.albedo.worst <= 0.01, "{msg}");
    }
}
