//! The `Brdf` contract ([`brdftab::testkit::check_contract`]) on every model and every source
//! kind: each model's catalogue example (RGB and spectral), a table of each (halfdiff and inout
//! grids, f32 and log16, nearest and linear lookups), a MERL file and a table on its cells, and
//! the seven shipped RGL files, native and as tables.

use brdftab::request::{self, BakeSettings, ConvertSettings, OpenSettings};
use brdftab::spec::MODELS;
use brdftab::testkit::{Contract, TempDir, check_contract};
use brdftab::{Brdf, progress::Silent};

fn open(source: &str, interp: &str) -> Box<dyn Brdf + Send + Sync> {
    let s = OpenSettings {
        interp: Some(interp.into()),
        eager: Some(true),
        ..OpenSettings::default()
    };
    request::open(source, &s).unwrap_or_else(|e| panic!("{source}: {e}"))
}

/// Checks every source and fails once, listing every source that broke the contract.
fn check_all(sources: &[(String, Box<dyn Brdf + Send + Sync>)], opts: &Contract) {
    let failures: Vec<String> = sources
        .iter()
        .filter_map(|(name, b)| {
            check_contract(b.as_ref(), opts)
                .err()
                .map(|v| format!("{name}:\n  {}", v.join("\n  ")))
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} sources break the contract:\n{}",
        failures.len(),
        sources.len(),
        failures.join("\n")
    );
}

fn bake(source: &str, out: &str, settings: &str) -> String {
    let s: BakeSettings = request::from_json(settings).unwrap();
    request::bake(source, out, &s, &Silent).unwrap_or_else(|e| panic!("{source}: {e}"));
    out.to_owned()
}

#[test]
fn every_model_keeps_the_contract_in_rgb_and_spectral() {
    let mut sources = Vec::new();
    for m in MODELS {
        sources.push((m.example.to_owned(), open(m.example, "auto")));
        let spectral = OpenSettings {
            wavelengths: Some("420,500,580,660".parse().unwrap()),
            ..OpenSettings::default()
        };
        let b = request::open(m.example, &spectral).unwrap();
        sources.push((format!("{} at 4 wavelengths", m.example), b));
    }
    // Anisotropic and summed lobes, and the lecture's Fresnel kinds.
    for spec in [
        r#"{"model": "ggx", "alpha_x": 0.1, "alpha_y": 0.4, "fresnel": {"conductor": "Cu"}}"#,
        r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
        r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2}, {"model": "cook_torrance", "m": 0.2, "fresnel": {"eta": 1.5}}]}"#,
        // Parameters at the edges: a Fresnel term or k_s of 0 (0 times an f_r that overflows
        // at a subnormal cosine), an index-matched conductor (0/0 in the closed form at
        // grazing), a sharp pumped-up lobe (cos^n ψ underflows where X does).
        r#"{"model": "ggx", "alpha": 0.2, "fresnel": {"eta": 1.0}}"#,
        r#"{"model": "ggx", "alpha": 0.2, "ks": 0}"#,
        r#"{"model": "ggx", "alpha": 0.2, "fresnel": {"n": 1.0, "k": 0}}"#,
        r#"{"model": "mirror", "fresnel": {"n": 1.0, "k": 0}}"#,
        r#"{"model": "cook_torrance", "m": 0.2, "fresnel": {"schlick": 0}}"#,
        r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.01, "alpha_y": 0.01}"#,
        r#"{"model": "pumped_phong", "ks": 0.5, "n": 1e5, "x": "product"}"#,
        r#"{"model": "pumped_phong", "ks": 0.5, "n": 1e5, "x": "sqrt"}"#,
    ] {
        sources.push((spec.to_owned(), open(spec, "auto")));
    }
    check_all(&sources, &Contract::default());
}

#[test]
fn tables_of_every_non_delta_model_keep_the_contract() {
    let dir = TempDir::new("contract-tables");
    let mut sources = Vec::new();
    for (i, m) in MODELS.iter().enumerate() {
        if open(m.example, "auto").flags().delta {
            continue; // a delta lobe has no table (a bake refuses it)
        }
        let t = bake(
            m.example,
            &dir.file(&format!("m{i}.btdb")),
            r#"{"preset": "small"}"#,
        );
        for interp in ["linear", "nearest"] {
            sources.push((format!("{} table, {interp}", m.name), open(&t, interp)));
        }
    }
    // Other grids and codecs: inout, f32, an anisotropic model on a full 4D grid, spectral.
    let ggx = r#"{"model": "ggx", "alpha_x": 0.15, "alpha_y": 0.4}"#;
    let ct = r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#;
    for (name, source, settings) in [
        ("inout", ct, r#"{"param": "inout", "grid": "16x1x16x32"}"#),
        ("f32", ct, r#"{"preset": "small", "codec": "f32"}"#),
        ("anisotropic 4D", ggx, r#"{"grid": "24x48x24x48"}"#),
        (
            "spectral",
            ct,
            r#"{"preset": "small", "wavelengths": "450,550,650"}"#,
        ),
    ] {
        let t = bake(source, &dir.file(&format!("{name}.btdb")), settings);
        sources.push((format!("{name} table of {source}"), open(&t, "linear")));
    }
    check_all(&sources, &Contract::default());
}

#[test]
fn merl_files_and_tables_on_their_cells_keep_the_contract() {
    let dir = TempDir::new("contract-merl");
    let merl = dir.file("ct.binary");
    let ct = r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#;
    request::convert(ct, &merl, &ConvertSettings::default(), &Silent).unwrap();
    let cells = bake(&merl, &dir.file("cells.btdb"), "{}");
    let sources = vec![
        ("MERL file".to_owned(), open(&merl, "auto")),
        ("table on the MERL cells".to_owned(), open(&cells, "auto")),
    ];
    check_all(&sources, &Contract::default());
}

#[test]
fn the_shipped_rgl_files_keep_the_contract_native_and_as_tables() {
    let rgl = brdftab::measured::data::rgl_dir().expect("the RGL files ship in data/rgl");
    let dir = TempDir::new("contract-rgl");
    let mut files: Vec<_> = std::fs::read_dir(&rgl)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "bsdf"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 7, "{files:?}");
    let (mut native, mut sources) = (Vec::new(), Vec::new());
    for (i, f) in files.iter().enumerate() {
        let f = f.to_str().unwrap();
        native.push((format!("{f} native"), open(f, "auto")));
        // One of them as a calibrated adaptive table (the default bake's kind, on a small grid).
        if i == 0 {
            let t = bake(f, &dir.file("rgl.btdb"), r#"{"grid": "adaptive:48x24x13"}"#);
            sources.push((format!("{f} adaptive table"), open(&t, "auto")));
        }
    }
    check_all(&sources, &Contract::default());
    // The reader's warps are the file's f32 data: a sample's pdf and pdf() agree to f32
    // rounding through the warp and its inverse.
    let f32_warps = Contract {
        pdf_tolerance: 1e-6,
        ..Contract::default()
    };
    check_all(&native, &f32_warps);
}
