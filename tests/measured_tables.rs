//! Tables of measured materials with the defaults: an RGL file bakes on an adaptive grid, into
//! a file no larger than the measurement, within 1 % of the measurement's own evaluation inside
//! 80°, faithful over the whole hemisphere, in the grazing band and in albedo, passing a white
//! furnace, continuous at the normal, held in under 4 MB while evaluating — and the warps
//! survive the file round trip.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use brdftab::analysis::accuracy::{Weight, compare_weighted};
use brdftab::analysis::fidelity::{self, FidelityOptions};
use brdftab::bake::{BakeRequest, BakeTarget, GridChoice};
use brdftab::source::{self, OpenOptions};
use brdftab::table::{Mapping, kernel::Kernel};
use brdftab::testkit::TempDir;
use brdftab::{Brdf, Error, measured};
use glam::DVec3;

/// Bakes `file` with the defaults into `dir`; returns (table path, report).
fn bake_default(dir: &Path, file: &str) -> (String, brdftab::bake::BakeReport) {
    let rgl = measured::data::rgl_file(file).unwrap_or_else(|e| panic!("{e}"));
    let out = dir
        .join(format!("{file}.btdb"))
        .to_string_lossy()
        .into_owned();
    let r = BakeRequest::new(&rgl)
        .run(&BakeTarget::File(out.clone().into()))
        .unwrap();
    (out, r)
}

/// One shipped RGL file and its default table.
struct Baked {
    name: String,
    rgl: PathBuf,
    table: String,
    report: brdftab::bake::BakeReport,
}

/// Every shipped RGL file baked with the defaults, once for all the tests of this file.
fn baked() -> &'static [Baked] {
    // The tests open the tables by path, so the directory outlives each of them: a static is
    // never dropped, so it is removed when the test process exits.
    static DIR: OnceLock<TempDir> = OnceLock::new();
    static BAKED: OnceLock<Vec<Baked>> = OnceLock::new();
    extern "C" fn remove_dir() {
        if let Some(d) = DIR.get() {
            let _ = std::fs::remove_dir_all(d.path());
        }
    }
    BAKED.get_or_init(|| {
        let out = DIR.get_or_init(|| {
            // SAFETY: registers a function that takes nothing and returns nothing.
            assert_eq!(unsafe { libc::atexit(remove_dir) }, 0, "atexit");
            TempDir::new("measured-tables")
        });
        let dir = measured::data::rgl_dir().expect("the shipped data/rgl");
        let files = brdftab::measured::data::rgl_files(&dir).unwrap();
        assert_eq!(files.len(), 7, "the seven shipped RGL files");
        files
            .into_iter()
            .map(|rgl| {
                let name = rgl.file_name().unwrap().to_string_lossy().into_owned();
                let (table, report) = bake_default(out.path(), &name);
                Baked {
                    name,
                    rgl,
                    table,
                    report,
                }
            })
            .collect()
    })
}

impl Baked {
    fn native(&self) -> Box<dyn Brdf + Send + Sync> {
        source::open(&self.rgl).unwrap()
    }
    fn table(&self) -> brdftab::table::TabulatedBrdf {
        source::open_table(&self.table, &OpenOptions::default()).unwrap()
    }
}

#[test]
fn rgl_defaults_meet_size_error_and_memory_bars() {
    // Every shipped RGL file: the bars of the measured-table issue, on the metric it states.
    for b in baked() {
        let (name, report) = (&b.name, &b.report);
        assert!(
            matches!(report.grid.stored_axes()[0].mapping, Mapping::Warp(_)),
            "{name}: the default grid of an RGL file is adaptive"
        );
        // Its node counts come from the default error target, which the search met, in the
        // grazing band too.
        let t = report.target.as_ref().expect("the default bake searched");
        assert_eq!(t.target, brdftab::bake::MEASURED_TARGET_ERROR);
        let band = t.grazing_target.expect("measured: the band is judged");
        assert!(
            t.met && t.error <= t.target && t.grazing <= band,
            "{name}: {}",
            t.summary()
        );
        assert_eq!(report.grid.stored_shape()[0], t.nodes[0]);
        assert!(report.grid.calibration().is_some(), "{name}: calibrated");
        let rgl_bytes = std::fs::metadata(&b.rgl).unwrap().len();
        let table_bytes = std::fs::metadata(&b.table).unwrap().len();
        assert!(
            table_bytes <= rgl_bytes,
            "{name}: {table_bytes} > {rgl_bytes} bytes"
        );
        let native = b.native();
        let table = b.table();
        // 100 000 pairs: on the near-mirror `cg_sunflower` one pair on the 0.4°-wide peak can
        // carry most of a 20 000-pair figure (BENCHMARKS.md).
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
fn rgl_defaults_are_faithful_at_every_angle() {
    // The measured-fidelity issue's bars beyond the 80° cap, each file's default table against
    // the native reader: relative RMSE of f_r cos θi cos θo within 80° ≤ 1 %, over the whole
    // hemisphere ≤ 1.5 %, in the grazing band (a direction beyond 80°) ≤ 3 % — on 100 000
    // random pairs (half drawn near the mirror direction and weighted back to uniform, so that
    // `cg_sunflower`'s peak does not decide the figure: with uniform pairs its band read 1.5 %
    // with this seed and 3.9–5.0 % with three of four others) and on the deterministic
    // mirror-centred rule — and
    // the directional albedo within 1 % per channel at every θ′ = 1..89° (a channel darker than
    // 0.02 judged against 0.02). Before the issue: grazing 6–186 %, albedo 3–19 %.
    for b in baked() {
        let opts = FidelityOptions {
            pairs: 100_000,
            ..Default::default()
        };
        let fi = fidelity::measure(&b.table(), b.native().as_ref(), &opts).unwrap();
        let (name, s) = (&b.name, fi.summary());
        assert!(fi.cap <= 0.01 && fi.rule.cap <= 0.01, "{name}: {s}");
        assert!(fi.whole <= 0.015 && fi.rule.whole <= 0.015, "{name}: {s}");
        assert!(fi.grazing <= 0.03 && fi.rule.grazing <= 0.03, "{name}: {s}");
        assert!(fi.albedo.worst <= 0.01, "{name}: {s}");
    }
}

#[test]
fn rgl_defaults_pass_a_white_furnace() {
    // Under uniform unit radiance a view at θo sees the viewer's albedo ∫ f_r cos θi dωi, and a
    // light at θi deposits its albedo ∫ f_r cos θo dωo; a measurement is not reciprocal, so the
    // two differ, and a renderer meets both. Each must equal the source's within 1 % (a channel
    // darker than 0.02 judged against 0.02) at every angle up to 88°, both integrated on the same
    // mirror-centred rule (it resolves `cg_sunflower`'s 0.4° peak, which random or tabulated
    // importance sampling does not yet: that is the sampling issue's). The source is the one
    // the table was baked from: the file made continuous at the normal (`BakeSource::bake_view`; the
    // native reader's own values near the normal depend on the azimuth from which wi nears it,
    // README "Measured data"). At 89° the files' viewer albedo climbs steeply (satin_rosaline:
    // 0.99 at 88°, 1.59 at 89°, as f_r ∝ 1/cos θo) and the table is within 1.5 % there.
    let thetas: Vec<f64> = (0..=17)
        .map(|k| (5 * k).max(1) as f64)
        .chain([88.0])
        .collect();
    for b in baked() {
        let native = b.native();
        let view = native.bake_source().and_then(|b| b.bake_view());
        let source: &dyn Brdf = view.as_deref().unwrap_or(native.as_ref());
        let table = b.table();
        let sides: [(&str, &dyn Brdf, &dyn Brdf); 2] = [
            ("light", &table, source),
            (
                "viewer",
                &fidelity::Reversed(&table),
                &fidelity::Reversed(source),
            ),
        ];
        for (side, t, src) in sides {
            for &deg in &thetas {
                let a = fidelity::mirror_albedo(t, deg.to_radians(), 128, 8);
                let r = fidelity::mirror_albedo(src, deg.to_radians(), 128, 8);
                for k in 0..3 {
                    assert!(
                        (a[k] - r[k]).abs() <= 0.01 * r[k].max(0.02),
                        "{}: {side}'s albedo at {deg}°, channel {k}: table {:.5}, source {:.5}",
                        b.name,
                        a[k],
                        r[k]
                    );
                }
            }
        }
    }
}

#[test]
fn lookups_at_the_normal_give_the_continuous_limit() {
    // Either direction at the normal, or within a hair of it from any azimuth: one value, the
    // limit of the source made continuous there (the azimuthal mean of the file's normal
    // slice; the native reader's own limit depends on the approach, README "Measured data").
    for b in baked() {
        let table = b.table();
        let native = b.native();
        let view = native.bake_source().and_then(|b| b.bake_view());
        let source: &dyn Brdf = view.as_deref().unwrap_or(native.as_ref());
        // The limit: the whole slice at the normal — each side's albedo at exactly θ = 0, which
        // evaluates the table at the normal itself — within 1 % of the source's (a channel
        // darker than 0.02 judged against 0.02).
        let sides: [(&dyn Brdf, &dyn Brdf); 2] = [
            (&table, source),
            (&fidelity::Reversed(&table), &fidelity::Reversed(source)),
        ];
        for (t, s) in sides {
            let a = fidelity::mirror_albedo(t, 0.0, 128, 8);
            let r = fidelity::mirror_albedo(s, 0.0, 128, 8);
            for k in 0..3 {
                assert!(
                    (a[k] - r[k]).abs() <= 0.01 * r[k].max(0.02),
                    "{}: {} at the normal, channel {k}: table {:.5}, source {:.5}",
                    b.name,
                    t.describe(),
                    a[k],
                    r[k]
                );
            }
        }
        for deg in [10.0f64, 25.0, 50.0] {
            let t = deg.to_radians();
            let other = DVec3::new(t.sin() * 0.6, t.sin() * 0.8, t.cos());
            let (mut at, mut near) = ([0f32; 3], [0f32; 3]);
            for incident_at_normal in [true, false] {
                let pair = |n: DVec3| {
                    if incident_at_normal {
                        (n, other)
                    } else {
                        (other, n)
                    }
                };
                let (wi, wo) = pair(DVec3::Z);
                table.eval(wi, wo, &mut at);
                for k in 0..8 {
                    let phi = k as f64 * std::f64::consts::TAU / 8.0;
                    for eps in [1e-9, 1e-6, 1e-4] {
                        let n = DVec3::new(eps * phi.cos(), eps * phi.sin(), 1.0).normalize();
                        let (wi, wo) = pair(n);
                        table.eval(wi, wo, &mut near);
                        let top = at.iter().fold(1e-3f32, |m, &x| m.max(x));
                        for c in 0..3 {
                            // Continuous: the change vanishes with the distance (a cell of the
                            // table is ≥ 0.5° wide and a value changes by less than the pair's
                            // brightest channel across one: below 120 per radian), plus f32
                            // rounding.
                            let bound = (120.0 * eps as f32 + 1e-5) * top;
                            assert!(
                                (near[c] - at[c]).abs() <= bound,
                                "{}: {deg}° {incident_at_normal} {eps}: {near:?} vs {at:?}",
                                b.name
                            );
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn the_warps_survive_the_file_and_select_the_fast_lookup() {
    let dir = TempDir::new("measured-tables-warps");
    let (out, report) = bake_default(dir.path(), "paper_white_rgb.bsdf");
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
            interp: Some(brdftab::table::Interp::Nearest),
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

/// Importance sampling as good as the measurement's own (#24): the coefficient of variation of
/// the weights f_r cos θi / pdf stays ≤ 0.10 at views 3–75° and ≤ 0.2 at 85°, natively and for
/// the default tables (the figures of `examples/sampling_cv`, on 20 000 samples at two view
/// azimuths; the measured CVs are at most 0.09 at 3–75° and 0.18 at 85°, and the estimate of a
/// CV near 0.1 on 20 000 samples has a standard error near 0.001).
#[test]
fn rgl_sampling_weights_are_near_constant() {
    use brdftab::analysis::weights::weight_stats;
    let mut failures = Vec::new();
    for b in baked() {
        let native = b.native();
        let table = b.table();
        for (kind, brdf) in [("native", native.as_ref()), ("table", &table as &dyn Brdf)] {
            for deg in [3.0f64, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0] {
                let bar = if deg <= 75.0 { 0.10 } else { 0.2 };
                for (k, phi) in [0.3f64, 3.4].into_iter().enumerate() {
                    let wo = brdftab::geometry::spherical(deg.to_radians(), phi);
                    let s = weight_stats(brdf, wo, 20_000, 50 + k as u64);
                    if s.cv.is_nan() || s.cv > bar {
                        failures.push(format!(
                            "{} {kind} at {deg}°, φ {phi}: CV {:.3}",
                            b.name, s.cv
                        ));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The bars of the test above hold at every view, not only at the seven it draws at: the CV
/// predicted from each sampler's density (`TableSampler::predicted_cv`, the weights' exact CV up
/// to its quadrature) at the views midway between its conditioning views — where the mixture of
/// two neighbours serves a view worst — and at 85°, natively and for the default tables, at the
/// resolution each chooses (`TableSampler::for_source`, what the reader and the table build).
/// Session 28's figures: at most 0.091 (cc_ibiza_sunset native, 74.4°) up to 75° and 0.158
/// (cc_iris_purple_gem native, 84.6°) beyond.
#[test]
fn rgl_samplers_meet_the_bars_between_their_views() {
    use brdftab::table::TableSampler;
    let mut failures = Vec::new();
    for b in baked() {
        let native = b.native();
        let table = b.table();
        let samplers = [
            (
                "native",
                native.as_ref(),
                TableSampler::for_source(native.as_ref(), true, false),
            ),
            ("table", &table as &dyn Brdf, table.sampler().clone()),
        ];
        for (kind, brdf, s) in samplers {
            let nt = s.resolution().theta_o;
            let midway = (0..nt - 1).map(|k| {
                let t = (k as f64 + 0.5) / (nt - 1) as f64;
                (1.0 - t * t).acos().to_degrees()
            });
            for deg in midway.filter(|d| (3.0..=85.0).contains(d)).chain([85.0]) {
                let bar = if deg <= 75.0 { 0.10 } else { 0.2 };
                let wo = brdftab::geometry::spherical(deg.to_radians(), 1.1);
                let cv = s.predicted_cv(brdf, wo);
                if cv.is_nan() || cv > bar {
                    failures.push(format!("{} {kind} at {deg:.1}°: CV {cv:.3}", b.name));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
