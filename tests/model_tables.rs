//! Default tables of models whose f_r is unbounded at the horizon (Ward's 1/√(cos θi cos θo),
//! the original Phong's 1/cos θi, the pumped Phong over cos θi cos θo): the bake stores
//! f_r cos θi cos θo for them, which keeps the grazing band and the albedo near the source's,
//! and their samplers' weights near constant at every view (issue 24's bars).

use brdftab::Brdf;
use brdftab::analysis::fidelity::{self, FidelityOptions};
use brdftab::analysis::weights::weight_stats;
use brdftab::bake::BakeRequest;
use brdftab::table::{Quantity, TabulatedBrdf};

/// (spec, grazing-band bar, albedo bar): each table's whole-domain errors measured at the
/// default (session 37, the original Phong's table no longer calibrated: 0.14 % / 0.13 %; session 13: Ward 2.6 % / 3.7 % at 89°, pumped Phong 0.7 % /
/// 0.23 %), with a margin for the 20 000-pair estimate; as f_r tables they were 12.8 % / 14 %,
/// 13 % / 116 % and 22 % / 18 %.
const CASES: [(&str, f64, f64); 3] = [
    (r#"{"model": "phong", "ks": 0.5, "n": 20}"#, 0.01, 0.01),
    (
        r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
        0.03,
        0.05,
    ),
    (
        r#"{"model": "pumped_phong", "ks": 0.5, "n": 20, "x": "product"}"#,
        0.015,
        0.01,
    ),
];

fn default_table(spec: &str) -> (Box<dyn Brdf + Send + Sync>, TabulatedBrdf) {
    let req = BakeRequest::new(spec);
    let src = req.open_source().unwrap();
    let (table, _) = req.table(&brdftab::progress::Silent).unwrap();
    (src, TabulatedBrdf::from_table(table))
}

#[test]
fn unbounded_models_bake_bounded_quantities_faithful_to_the_horizon() {
    let opts = FidelityOptions {
        pairs: 20_000,
        albedo_thetas_deg: vec![1.0, 30.0, 60.0, 80.0, 85.0, 89.0],
        ..Default::default()
    };
    for (spec, grazing, albedo) in CASES {
        let (src, tab) = default_table(spec);
        assert!(src.grows_at_horizon(), "{spec}");
        assert_eq!(tab.grid().quantity(), Quantity::FrCosCos, "{spec}");
        let f = fidelity::measure(&tab, src.as_ref(), &opts).unwrap();
        assert!(f.whole <= 0.015, "{spec}: {}", f.summary());
        assert!(f.grazing <= grazing, "{spec}: {}", f.summary());
        assert!(f.albedo.worst <= albedo, "{spec}: {}", f.summary());
    }
    // A model's table is not calibrated for being non-reciprocal (that rule is a measurement's
    // f_r cos θo): the original Phong's medium table passes the preset check and stays plain
    // (calibrated, its factors were 0.68–1.01 and its error over random pairs 0.13 % for 0.09 %).
    let (_, tab) = default_table(CASES[0].0);
    assert!(!tab.grid().symmetry().reciprocal);
    assert!(tab.grid().calibration().is_none(), "{}", CASES[0].0);
    // A bounded model keeps f_r.
    let (src, tab) = default_table(r#"{"model": "ggx", "alpha": 0.3}"#);
    assert!(!src.grows_at_horizon());
    assert_eq!(tab.grid().quantity(), Quantity::Fr);
}

/// The coefficient of variation of the weights f_r cos θi / pdf of the default tables: ≤ 0.10
/// at views 3–75° and ≤ 0.2 at 85° (measured at most 0.09 and 0.18 on 40 000 samples at four
/// azimuths, `examples/sampling_cv`; an estimate of a CV near 0.1 on 20 000 samples has a
/// standard error near 0.001).
#[test]
fn unbounded_models_tables_sample_with_near_constant_weights() {
    let mut failures = Vec::new();
    for (spec, _, _) in CASES {
        let (_, tab) = default_table(spec);
        for deg in [3.0f64, 30.0, 60.0, 75.0, 85.0] {
            let bar = if deg <= 75.0 { 0.10 } else { 0.2 };
            for (k, phi) in [0.3f64, 1.9].into_iter().enumerate() {
                let wo = brdftab::geometry::spherical(deg.to_radians(), phi);
                let s = weight_stats(&tab, wo, 20_000, 70 + k as u64);
                if s.cv.is_nan() || s.cv > bar {
                    failures.push(format!("{spec} at {deg}°, φ {phi}: CV {:.3}", s.cv));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A model's default table is the medium preset where that is within 1 % of its albedo; a lobe
/// the preset cannot resolve gets the adaptive, calibrated table of a 0.2 % target (the bake's
/// note says why). On the preset GGX α = 0.02 was 2.4 % off in albedo at 89° and α = 0.002
/// 13.8 % (25.7 % within 80°); their default tables now meet the measured tables' bars (1 % in
/// albedo, 1.5 % over the whole hemisphere, 3 % grazing) but for α = 0.002's RMSE, which even
/// the largest adaptive grid leaves at 2.2–2.5 % (judged here against 3 %); and their
/// samplers meet the CV bars.
#[test]
fn sharp_lobes_default_to_a_table_that_resolves_them() {
    let opts = FidelityOptions {
        pairs: 20_000,
        albedo_thetas_deg: vec![1.0, 30.0, 60.0, 80.0, 85.0, 89.0],
        ..Default::default()
    };
    for (spec, whole) in [
        (r#"{"model": "ggx", "alpha": 0.02}"#, 0.015),
        (r#"{"model": "ggx", "alpha": 0.002}"#, 0.03),
    ] {
        let req = BakeRequest::new(spec);
        let src = req.open_source().unwrap();
        let (table, report) = req.table(&brdftab::progress::Silent).unwrap();
        let note = report.symmetry_note.clone().unwrap_or_default();
        assert!(note.contains("medium preset"), "{spec}: {note}");
        let tab = TabulatedBrdf::from_table(table);
        let f = fidelity::measure(&tab, src.as_ref(), &opts).unwrap();
        // The mirror-centred rule's figures: random pairs rarely meet a 0.1° lobe (their
        // estimate of α = 0.002's error scatters between 2 % and 30 %).
        assert!(f.rule.whole <= whole, "{spec}: {}", f.summary());
        assert!(f.rule.grazing <= 0.03, "{spec}: {}", f.summary());
        assert!(f.albedo.worst <= 0.01, "{spec}: {}", f.summary());
        // Their samplers follow the lobe (twice the θh nodes for α = 0.002: before, its
        // weights' CV was 0.85 at every view): the bars of the test above.
        for deg in [3.0f64, 30.0, 60.0, 75.0, 85.0] {
            let bar = if deg <= 75.0 { 0.10 } else { 0.2 };
            let wo = brdftab::geometry::spherical(deg.to_radians(), 0.3);
            let s = weight_stats(&tab, wo, 20_000, 90);
            assert!(s.cv <= bar, "{spec} at {deg}°: CV {:.3}", s.cv);
        }
    }
    // A lobe the preset serves keeps it (the medium preset's 90 θh nodes).
    let req = BakeRequest::new(r#"{"model": "ggx", "alpha": 0.3}"#);
    let (table, report) = req.table(&brdftab::progress::Silent).unwrap();
    assert!(report.symmetry_note.is_none(), "{:?}", report.symmetry_note);
    assert_eq!(table.grid().stored_shape()[0], 90);
}

/// A preset table can meet the albedo and still blur a lobe a degree or two wide: the
/// reciprocal Phong at n = 1000 was 0.61 % off over random pairs (f_r cos θi cos θo), the
/// Blinn-Phong at n = 1000 0.33 %, where their adaptive tables of the fallback's 0.2 % target
/// are 0.06 % and 0.22 % (`bake::PRESET_RMSE_TOLERANCE`, 0.3 %). Their default tables are
/// those, judged here on other pairs than the check's; a broad lobe keeps its preset. Both
/// default tables sample within the bars up to 85°.
#[test]
fn lobes_the_preset_blurs_default_to_the_adaptive_table() {
    use brdftab::analysis::accuracy::{Region, Weight, compare_region};
    use brdftab::table::presets::Preset;
    let whole = Region::Cap(std::f64::consts::FRAC_PI_2);
    for spec in [
        r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 1000}"#,
        r#"{"model": "blinn_phong", "ks": 0.5, "n": 1000}"#,
    ] {
        let req = BakeRequest::new(spec);
        let src = req.open_source().unwrap();
        let (table, report) = req.table(&brdftab::progress::Silent).unwrap();
        let note = report.symmetry_note.clone().unwrap_or_default();
        assert!(note.contains("off over random pairs"), "{spec}: {note}");
        let (preset, _) = BakeRequest::new(spec)
            .preset(Preset::Medium)
            .table(&brdftab::progress::Silent)
            .unwrap();
        let err = |t: &TabulatedBrdf| {
            compare_region(t, src.as_ref(), 100_000, 7, whole, Weight::CosInCosOut)
                .unwrap()
                .rel_rmse
        };
        let table = TabulatedBrdf::from_table(table);
        let (d, p) = (err(&table), err(&TabulatedBrdf::from_table(preset)));
        assert!(d < p, "{spec}: default {d:.4} against the preset's {p:.4}");
        // Their samplers meet the bars up to 85° — 84.1° is midway between the reciprocal
        // Phong's conditioning views, whose lobe there is a crescent in the half vector
        // (CV 0.25 on the default views, `TableSampler::for_source` gives it finer ones).
        for deg in [3.0f64, 30.0, 60.0, 75.0, 84.1, 85.0] {
            let bar = if deg <= 75.0 { 0.10 } else { 0.2 };
            let wo = brdftab::geometry::spherical(deg.to_radians(), 0.3);
            let s = weight_stats(&table, wo, 20_000, 91);
            assert!(s.cv <= bar, "{spec} at {deg}°: CV {:.3}", s.cv);
        }
    }
    let (_, report) = BakeRequest::new(r#"{"model": "blinn_phong", "ks": 0.5, "n": 100}"#)
        .table(&brdftab::progress::Silent)
        .unwrap();
    assert!(report.symmetry_note.is_none(), "{:?}", report.symmetry_note);
}

/// The two defaults the preset check left off in session 22, and what it does for them now.
/// Ward anisotropic (the demo's spec) was never checked — its medium table, of f_r cos θi
/// cos θo, was 4.8 % off in albedo at 89° (the mean over the light's azimuths; 3.4 % at
/// φ′ = 0): that quantity has a √cos θi edge at the horizon, which the halfdiff cells cut
/// obliquely and linear interpolation does not follow (16× the nodes: still 2.2 % off). The
/// max-Phong at n = 50 kept its preset, 1.5 % off at 89°, because its adaptive table is 6 % off
/// over random pairs. Both now get the preset's own table, calibrated: within
/// [`PRESET_ALBEDO_TOLERANCE`] at [`PRESET_CHECK_THETAS_DEG`] — for Ward the mean over
/// [`ANISOTROPIC_AZIMUTHS`], what a factor of θ can pin — on a finer rule than the one the
/// check and the calibration integrate on (256 azimuths and 12 nodes a segment against 64 and
/// 6: Ward's mean at 89° is 0.06 % on the calibration's own rule, 0.31–0.35 % on this one and
/// on 512 × 16, 0.76 % on 128 × 8, whose nodes meet the table's kinks), and no worse over
/// random pairs than the preset's table beyond the check's 1 %. Written to a file, the table
/// keeps its calibration.
#[test]
fn ward_and_the_max_phong_default_to_their_calibrated_presets() {
    use brdftab::analysis::accuracy::{Region, Weight, compare_region};
    use brdftab::bake::{BakeTarget, PRESET_ALBEDO_TOLERANCE, PRESET_CHECK_THETAS_DEG};
    use brdftab::table::calibration::ANISOTROPIC_AZIMUTHS;
    use brdftab::table::presets::Preset;

    let dir = brdftab::testkit::TempDir::new("model-tables-calibrated-presets");
    for (k, (spec, weight)) in [
        (
            r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
            // f_r ∝ 1/√(cos θi cos θo): weighted by cos θi alone it has no finite RMS.
            Weight::CosInCosOut,
        ),
        (
            r#"{"model": "max_phong", "ks": 0.5, "n": 50}"#,
            Weight::CosIn,
        ),
        (
            // Its calibrated table is 1.67 % off over random pairs against the preset's 1.59 %:
            // the check refused it on "no larger" and kept the preset, 5.3 % off at 89°.
            r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.05, "alpha_y": 0.2}"#,
            Weight::CosInCosOut,
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let req = BakeRequest::new(spec);
        let src = req.open_source().unwrap();
        let opts = FidelityOptions {
            albedo_thetas_deg: PRESET_CHECK_THETAS_DEG.to_vec(),
            albedo_phi: 256,
            albedo_order: 12,
            albedo_azimuths: if src.flags().isotropic {
                1
            } else {
                ANISOTROPIC_AZIMUTHS
            },
            ..Default::default()
        };
        let path = dir.file(&format!("t{k}.btdb"));
        let report = req.run(&BakeTarget::file(&path)).unwrap();
        let table = brdftab::open(&path).unwrap();
        let (preset, _) = req
            .clone()
            .preset(Preset::Medium)
            .table(&brdftab::progress::Silent)
            .unwrap();
        assert!(preset.grid().calibration().is_none(), "{spec}");
        let preset = TabulatedBrdf::from_table(preset);
        let a = fidelity::albedo_error(table.as_ref(), src.as_ref(), &opts).unwrap();
        assert!(a.worst <= PRESET_ALBEDO_TOLERANCE, "{spec}: {a:?}");
        // The old default, on the same rule: why this test exists.
        let old = fidelity::albedo_error(&preset, src.as_ref(), &opts).unwrap();
        assert!(old.worst > PRESET_ALBEDO_TOLERANCE, "{spec}: {old:?}");
        let note = report.symmetry_note.clone().unwrap_or_default();
        assert!(note.contains("calibrated it"), "{spec}: {note}");
        let whole = Region::Cap(std::f64::consts::FRAC_PI_2);
        let rmse = |t: &dyn Brdf| {
            compare_region(t, src.as_ref(), 20_000, 7, whole, weight)
                .unwrap()
                .rel_rmse
        };
        let (now, before) = (rmse(table.as_ref()), rmse(&preset));
        let bound = (before * (1.0 + brdftab::bake::PRESET_CHECK_RMSE_SLACK)).max(0.01);
        assert!(now <= bound, "{spec}: {now} against {before}");
    }
}

/// A model the medium preset serves gets exactly the preset's table from its default bake —
/// the table the preset's check baked, not baked again — in memory and written to a file (the
/// check's table takes the whole-table writer, an explicit preset the streaming one).
#[test]
fn a_default_bake_the_preset_serves_is_the_presets_table() {
    use brdftab::bake::BakeTarget;
    use brdftab::table::presets::Preset;
    let spec = r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#;
    let silent = &brdftab::progress::Silent;
    let (default, report) = BakeRequest::new(spec).table(silent).unwrap();
    let (preset, _) = BakeRequest::new(spec)
        .preset(Preset::Medium)
        .table(silent)
        .unwrap();
    assert_eq!(default.grid(), preset.grid());
    assert_eq!(default.values(), preset.values());
    assert!(report.symmetry_note.is_none_or(|n| !n.contains("missed")));
    let d = brdftab::testkit::TempDir::new("model-default");
    let files = ["default.btdb", "preset.btdb"].map(|f| d.join(f).to_str().unwrap().to_owned());
    BakeRequest::new(spec)
        .run(&BakeTarget::file(&files[0]))
        .unwrap();
    BakeRequest::new(spec)
        .preset(Preset::Medium)
        .run(&BakeTarget::file(&files[1]))
        .unwrap();
    let [a, b] = files.map(|f| brdftab::open(&f).unwrap());
    let mut pairs = 0;
    for k in 0..2000 {
        let t = (k as f64 * 0.618).fract() * 1.5;
        let p = (k as f64 * 0.377).fract() * std::f64::consts::TAU;
        let wi = glam::DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
        let wo = glam::DVec3::new(-0.3, 0.2, 0.93).normalize();
        let (mut x, mut y) = ([0f32; 3], [0f32; 3]);
        a.eval(wi, wo, &mut x);
        b.eval(wi, wo, &mut y);
        assert_eq!(x, y, "{wi}");
        pairs += (x[0] > 0.0) as usize;
    }
    assert!(pairs > 1000);
}
