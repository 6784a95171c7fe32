//! The tools' library functions the CLI is thin over (moved from the core library with the
//! preview renderer and the reports): one progress type through renders and the suite, the
//! suite's metrics.

use brdftab::Error;
use brdftab::bake::BakeRequest;
use brdftab::progress::Silent;
use brdftab::table::TabulatedBrdf;
use brdftab::table::presets::Preset;
use brdftab::{Channels, ModelSpec};
use brdftab_tools::preview::{
    self as render, EnvChoice, LightChoice, Mode, RenderOptions, Sampling,
};
use brdftab_tools::report::suite::{self, MetricOptions};

const LAMBERT: &str = r#"{"model": "lambert", "kd": 0.25}"#;

fn lambert() -> Box<dyn brdftab::Brdf + Send + Sync> {
    ModelSpec::parse(LAMBERT)
        .unwrap()
        .build(&Channels::Rgb)
        .unwrap()
}

use brdftab::testkit::ProgressLog as Log;

#[test]
fn render_reports_one_stage_counting_every_pixel() {
    let brdf = lambert();
    let opts = RenderOptions {
        width: 20,
        height: 10,
        spp: 1,
        mode: Mode::Lit,
        ..RenderOptions::default()
    };
    let log = Log::default();
    render::render(brdf.as_ref(), &opts, &log).unwrap();
    let calls = log.calls();
    assert_eq!(
        calls.first().map(String::as_str),
        Some("begin rendering 200")
    );
    assert_eq!(calls.last().map(String::as_str), Some("end"));
    assert!(calls.contains(&"set 200".to_owned()), "{calls:?}");
}

#[test]
fn suite_metrics_of_an_exact_table_are_zero_and_a_cap_is_honoured() {
    let src = lambert();
    let (t, _) = BakeRequest::new(LAMBERT)
        .preset(Preset::Small)
        .table(&Silent)
        .unwrap();
    let tab = TabulatedBrdf::from_table(t);
    let thetas = vec![0.2, 0.8];
    let src_albedo = suite::albedos(src.as_ref(), &thetas);
    for cap in [None, Some(80f64.to_radians())] {
        let opts = MetricOptions {
            pairs: 2000,
            seed: 3,
            albedo_thetas: thetas.clone(),
            cap,
            weight: Default::default(),
        };
        let m = suite::metrics(&tab, src.as_ref(), &src_albedo, &opts).unwrap();
        assert!(m.rel_rmse < 1e-6 && m.max_rel < 1e-5, "{m:?}");
        assert!(m.albedo_err < 1e-3, "{m:?}");
    }
}

#[test]
fn the_suite_reports_rows_through_progress() {
    let cfg = suite::SuiteConfig {
        sources: vec![suite::SourceDef::model("lambert", LAMBERT).unwrap()],
        presets: vec![Preset::Small],
        params: vec![brdftab::table::Param::HalfDiff],
        codecs: suite::default_codecs().into_iter().take(1).collect(),
        pairs: 500,
        albedo_thetas: vec![0.3],
        render: None,
        render_measured: false,
        seed: 1,
    };
    let log = Log::default();
    let report = suite::run(&cfg, &log).unwrap();
    assert_eq!(report.rows.len(), 1);
    assert_eq!(log.calls(), ["begin accuracy 1", "set 1", "end"]);
}

#[test]
fn render_argument_errors_name_settings_not_flags() {
    let errors = [
        Mode::parse("fast").unwrap_err(),
        Sampling::parse("random").unwrap_err(),
        LightChoice::parse("sun").unwrap_err(),
        EnvChoice::parse("dark").unwrap_err(),
    ];
    for e in errors {
        assert!(matches!(e, Error::InvalidArgument { .. }), "{e}");
        assert!(!e.to_string().contains("--"), "{e}");
    }
    assert_eq!(Mode::parse("lit").unwrap(), Mode::Lit);
    assert_eq!(Sampling::parse("fixed").unwrap(), Sampling::Fixed);
    assert_eq!(LightChoice::parse("area").unwrap(), LightChoice::Area);
    assert!(matches!(
        EnvChoice::parse("white").unwrap(),
        EnvChoice::Constant(_)
    ));
}
