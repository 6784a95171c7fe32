//! The demo's other parts: the plausibility table of the lecture's models, the preview renders
//! and the rate–distortion sweep (through the accuracy suite and its plot).

use std::path::{Path, PathBuf};

use brdftab::analysis::plausibility;
use brdftab::progress::Silent;
use brdftab::table::presets::Preset;
use brdftab::table::{Param, TabulatedBrdf};
use brdftab::{Brdf, Error, Result};
use brdftab_tools::preview::{self, EnvChoice, RenderOptions};
use brdftab_tools::report::{plot, suite};

use brdftab_tools::text::print_out;

/// The models the demo bakes, as (table name, spec). Delta models (the mirror) cannot be
/// tabulated and are left out.
pub const BAKED_MODELS: &[(&str, &str)] = &[
    ("lambert", r#"{"model": "lambert", "kd": 0.5}"#),
    (
        "reciprocal_phong_n50",
        r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 50}"#,
    ),
    (
        "max_phong_n50",
        r#"{"model": "max_phong", "ks": 0.5, "n": 50}"#,
    ),
    ("cook_torrance_gold", CT_GOLD),
    (
        "ggx_0.1_copper",
        r#"{"model": "ggx", "alpha": 0.1, "fresnel": {"conductor": "Cu"}}"#,
    ),
    (
        "ward_aniso",
        r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
    ),
    (
        "oren_nayar",
        r#"{"model": "oren_nayar", "kd": 0.5, "sigma": 0.3}"#,
    ),
];

/// The spec of the rate–distortion sweep and of the render acceptance figure.
pub const CT_GOLD: &str = r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#;

/// Prints the plausibility table of the lecture's models ([`plausibility::lecture_table`]).
pub fn plausibility_table() -> Result<()> {
    print_out(&plausibility::lecture_table())
}

/// Renders source | table | difference for each preview, small, and writes PNGs.
pub fn preview_renders(
    out: &Path,
    previews: &[(String, &dyn Brdf, TabulatedBrdf)],
) -> Result<Vec<PathBuf>> {
    let opts = RenderOptions {
        width: 96,
        height: 96,
        spp: 16,
        max_depth: 3,
        // Material-independent directions: the difference shows the materials, not the noise.
        sampling: preview::Sampling::Fixed,
        env: EnvChoice::Sky,
        ..Default::default()
    };
    print_out(&format!(
        "\nPreview renders ({}×{}, {} spp, path tracer ≤ 3 bounces, sky, fixed sampling; same seed for both):\n",
        opts.width, opts.height, opts.spp
    ))?;
    let mut files = Vec::new();
    for (name, src, tab) in previews {
        let a = preview::render(*src, &opts, &Silent)?;
        let b = preview::render(tab, &opts, &Silent)?;
        let cmp = preview::compare(&b, &a)?;
        let (diff, _legend) = preview::difference_image(&b, &a)?;
        let side = preview::image::Image::hstack(&[&a, &b, &diff.to_rgb()?], 4, 0.0)?;
        let path = out.join(format!("render_{name}.png"));
        preview::image::write_png(&side, &path, 0.0)?;
        print_out(&format!(
            "  {:<24} rendered rel RMSE table vs source {:.3}%\n",
            name,
            100.0 * cmp.rel_rmse
        ))?;
        files.push(path);
    }
    Ok(files)
}

/// Cook-Torrance gold on the small and medium presets × f32, f16 and log16 ≤ 1e-2, through the
/// accuracy suite: compressed bytes vs rel RMSE. Writes `rd.csv` (the suite's columns) and the
/// suite's rate–distortion plot `rd.png`.
pub fn rate_distortion(out: &Path) -> Result<Vec<PathBuf>> {
    let name = "cook_torrance_gold";
    let cfg = suite::SuiteConfig {
        sources: vec![suite::SourceDef::model(name, CT_GOLD)?],
        presets: vec![Preset::Small, Preset::Medium],
        params: vec![Param::HalfDiff],
        codecs: suite::default_codecs()
            .into_iter()
            .filter(|c| ["f32", "f16", "log16@1e-2"].contains(&c.name))
            .collect(),
        pairs: 20_000,
        albedo_thetas: Vec::new(),
        render: None,
        render_measured: false,
        seed: 2,
    };
    let report = suite::run(&cfg, &Silent)?;
    print_out(
        "\nRate–distortion, Cook-Torrance m = 0.3 gold (bytes vs cosine-weighted rel RMSE):\n",
    )?;
    for r in &report.rows {
        // f16 cannot hold the sharpest peaks of some grids: that row says why.
        let point = match r.status.as_str() {
            "ok" => format!("{:>10} bytes  {:.3}%", r.bytes, 100.0 * r.rel_rmse),
            s => format!(
                "no table: {}",
                s.rsplit("cannot encode: ").next().unwrap_or(s)
            ),
        };
        print_out(&format!("  {:<7} {:<11} {point}\n", r.preset, r.codec))?;
    }
    let csv_path = out.join("rd.csv");
    std::fs::write(&csv_path, report.csv()).map_err(|e| Error::io(&csv_path, e))?;
    let png_path = out.join("rd.png");
    let rows: Vec<&suite::Row> = report.rows.iter().collect();
    plot::rate_distortion(name, &rows, &png_path)?;
    Ok(vec![csv_path, png_path])
}
