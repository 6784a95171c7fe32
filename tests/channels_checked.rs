//! A channel set built from its public variant (`Channels::Wavelengths(vec![])`) is checked at
//! every door that takes one, as `Channels::wavelengths` checks its list: an empty list built
//! a model of no channels, and a bake with it wrote a table that made the whole database
//! unreadable (`db list`, `verify`, opening its other tables).

use brdftab::bake::{BakeRequest, BakeTarget};
use brdftab::table::presets::Preset;
use brdftab::testkit::TempDir;
use brdftab::{Brdf, Channels, Error, Flags, ModelSpec, OpenOptions, Silent};
use glam::DVec3;

const LAMBERT: &str = r#"{"model": "lambert", "kd": 0.5}"#;

/// Channel sets `Channels::wavelengths` refuses.
fn bad() -> Vec<Channels> {
    vec![
        Channels::Wavelengths(vec![]),
        Channels::Wavelengths(vec![0.0]),
        Channels::Wavelengths(vec![f64::NAN, 500.0]),
        Channels::Wavelengths(vec![600.0, 500.0]),
        Channels::Wavelengths((0..65).map(|i| 400.0 + i as f64).collect()),
    ]
}

fn is_wavelengths_arg(e: &Error) -> bool {
    matches!(e, Error::InvalidArgument { name, .. } if name == "wavelengths")
}

#[test]
fn validate_agrees_with_the_constructor() {
    for c in bad() {
        let Channels::Wavelengths(nm) = &c else {
            unreachable!()
        };
        assert!(Channels::wavelengths(nm.clone()).is_err());
        assert!(c.validate().is_err(), "{c:?}");
    }
    assert!(Channels::Rgb.validate().is_ok());
    assert!(
        Channels::linspace(400.0, 700.0, 64)
            .unwrap()
            .validate()
            .is_ok()
    );
}

#[test]
fn models_and_opens_refuse_bad_channels() {
    let spec = ModelSpec::parse(LAMBERT).unwrap();
    for c in bad() {
        let e = spec.build(&c).unwrap_err();
        assert!(is_wavelengths_arg(&e), "{c:?}: {e}");
        let opts = OpenOptions {
            channels: Some(c.clone()),
            ..OpenOptions::default()
        };
        let e = brdftab::open_with(LAMBERT, &opts).unwrap_err();
        assert!(is_wavelengths_arg(&e), "{c:?}: {e}");
    }
}

#[test]
fn a_bad_bake_leaves_the_database_readable() {
    let d = TempDir::new("channels-checked");
    let db = d.file("m.btdb");
    BakeRequest::new(LAMBERT)
        .preset(Preset::Small)
        .run(&BakeTarget::db(&db, "good"))
        .unwrap();
    for (k, c) in bad().into_iter().enumerate() {
        let e = BakeRequest::new(LAMBERT)
            .preset(Preset::Small)
            .channels(c.clone())
            .run(&BakeTarget::db(&db, format!("bad{k}")))
            .unwrap_err();
        assert!(is_wavelengths_arg(&e), "{c:?}: {e}");
    }
    let names: Vec<String> = brdftab::store::db::list(&db)
        .unwrap()
        .into_iter()
        .map(|(t, _)| t.name)
        .collect();
    assert_eq!(names, ["good"]);
    brdftab::store::db::verify(&db).unwrap();
}

/// A `Brdf` of a caller's own that declares the channels it is given.
struct Own(Channels);

impl Brdf for Own {
    fn channels(&self) -> &Channels {
        &self.0
    }
    fn eval(&self, _wi: DVec3, _wo: DVec3, out: &mut [f32]) {
        out.fill(0.1);
    }
    fn flags(&self) -> Flags {
        Flags::SMOOTH_SYMMETRIC
    }
    fn describe(&self) -> String {
        "own".into()
    }
}

#[test]
fn a_bake_of_an_own_brdf_refuses_bad_channels() {
    for c in bad() {
        let e = BakeRequest::new("{}")
            .preset(Preset::Small)
            .table_of(&Own(c.clone()), &Silent)
            .unwrap_err();
        assert!(is_wavelengths_arg(&e), "{c:?}: {e}");
    }
    let (t, _) = BakeRequest::new("{}")
        .preset(Preset::Small)
        .table_of(&Own(Channels::Rgb), &Silent)
        .unwrap();
    assert!(t.values().iter().all(|&v| (v - 0.1).abs() < 1e-3));
}

#[test]
fn a_grid_refuses_bad_channels() {
    use brdftab::table::grid::{Grid, Mapping, Param};
    use brdftab::table::symmetry::Symmetry;
    let grid = |c: Channels| {
        Grid::with_sizes(
            Param::InOut,
            [4, 8, 4, 8],
            [Mapping::Uniform, Mapping::Uniform],
            c,
            Symmetry::NONE,
        )
    };
    for c in bad() {
        // A grid of no channels made `Table::from_fn` panic (a chunk size of 0).
        let e = grid(c.clone()).unwrap_err();
        assert!(is_wavelengths_arg(&e), "{c:?}: {e}");
    }
    let t =
        brdftab::table::Table::from_fn(grid(Channels::Rgb).unwrap(), "ones", |_, _, o| o.fill(1.0));
    assert_eq!(t.values().len(), 4 * 8 * 4 * 8 * 3);
}

#[test]
fn model_constructors_refuse_bad_channels() {
    use brdftab::fresnel::FresnelSpec;
    use brdftab::models::{
        blinn_phong::BlinnPhong, cook_torrance::CookTorrance, ggx::Ggx, lambert::Lambert,
        mirror::Mirror, mirror::Refractor, oren_nayar::OrenNayar, phong::Phong, ward::Ward,
    };
    use brdftab::spectrum::Value;
    type Built = brdftab::Result<Box<dyn Brdf + Send + Sync>>;
    type Ctor<'a> = Box<dyn Fn(&Channels) -> Built + 'a>;
    fn boxed<B: Brdf + Send + Sync + 'static>(b: brdftab::Result<B>) -> Built {
        b.map(|b| Box::new(b) as Box<dyn Brdf + Send + Sync>)
    }
    let g = || Value::Grey(0.5);
    let au = FresnelSpec::Conductor("Au".into());
    let ctors: Vec<(&str, Ctor<'_>)> = vec![
        ("lambert", Box::new(|c| boxed(Lambert::new(g(), c)))),
        ("phong", Box::new(|c| boxed(Phong::original(g(), 20.0, c)))),
        (
            "blinn_phong",
            Box::new(|c| boxed(BlinnPhong::new(g(), 20.0, c))),
        ),
        (
            "oren_nayar",
            Box::new(|c| boxed(OrenNayar::new(g(), 0.3, c))),
        ),
        ("ward", Box::new(|c| boxed(Ward::new(g(), 0.2, 0.3, c)))),
        (
            "cook_torrance",
            Box::new(|c| boxed(CookTorrance::new(0.3, g(), &au, c))),
        ),
        (
            "ggx",
            Box::new(|c| boxed(Ggx::isotropic(0.3, g(), au.clone(), c))),
        ),
        ("mirror", Box::new(|c| boxed(Mirror::new(&au, c)))),
        (
            "refractor",
            Box::new(|c| boxed(Refractor::new(Value::Grey(1.5), c))),
        ),
    ];
    for (name, ctor) in &ctors {
        for c in bad() {
            // 65 channels built a model whose `sample_wavelengths` (a buffer of 64 weights)
            // panicked; none built a model of no channels.
            let e = ctor(&c)
                .err()
                .unwrap_or_else(|| panic!("{name} built with {c:?}"));
            assert!(is_wavelengths_arg(&e), "{name} {c:?}: {e}");
        }
        let m = ctor(&Channels::linspace(400.0, 700.0, 64).unwrap()).unwrap();
        let v = m.eval_wavelength(DVec3::new(0.3, 0.0, 0.9), DVec3::new(-0.3, 0.0, 0.9), 550.0);
        assert!(v.is_finite() && v >= 0.0, "{name}: {v}");
        let mut w = [0.0f32; 2];
        let wo = DVec3::new(0.3, 0.1, 0.9);
        let s = m.sample_wavelengths(wo, glam::DVec2::new(0.3, 0.6), &[450.0, 650.0], &mut w);
        assert!(s.is_some(), "{name}");
    }
}
