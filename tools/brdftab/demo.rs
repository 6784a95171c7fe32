//! `demo`: the README's main job in one command.
//!
//! 1. The plausibility table of the lecture's models (`--plausibility` prints only this).
//! 2. Bakes the lecture's tabulatable models and the RGL-EPFL materials into one database
//!    (`demo-out/demo.btdb`), reads every table back from it and prints one row per source:
//!    grid, stored bytes, size relative to the same values as plain f32, cosine-weighted
//!    relative RMSE against the source, albedo error, plausibility of the stored table.
//! 3. Preview renders (source | table | difference) as PNGs.
//! 4. A rate–distortion sweep (presets × codecs) of Cook-Torrance gold: `rd.csv` and `rd.svg`.
//!
//! Everything here is library calls; this file only chooses sources and prints.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use brdftab::analysis::{accuracy, albedo, plausibility};
use brdftab::codec::{self, Codec, Quant};
use brdftab::render::{self, EnvChoice, RenderOptions};
use brdftab::store::{self, Source};
use brdftab::table::presets::Preset;
use brdftab::table::{self, BakeOptions, Symmetry, Table, TabulatedBrdf};
use brdftab::{Brdf, Channels, Error, ModelSpec, Result, geometry};
use clap::Args;

use crate::analysis::emit;

/// Arguments of `brdftab demo`.
#[derive(Args)]
pub struct DemoArgs {
    /// Print only the plausibility table of the lecture's models.
    #[arg(long)]
    plausibility: bool,
    /// Output directory (created).
    #[arg(long, default_value = "demo-out")]
    out: PathBuf,
    /// Grid preset of every table: small, medium, large (default: medium for isotropic sources,
    /// small for anisotropic models).
    #[arg(long)]
    preset: Option<String>,
    /// Directory of RGL-EPFL `.bsdf` files (default: $BRDFTAB_RGL_DIR, else the shipped
    /// data/rgl, else ../shared/data/measured/rgl).
    #[arg(long)]
    rgl: Option<PathBuf>,
    /// Skip the preview renders and the rate–distortion sweep.
    #[arg(long)]
    quick: bool,
}

/// The lecture's models, in its order, as (label, spec).
pub const LECTURE_MODELS: &[(&str, &str)] = &[
    ("lambert kd=0.3", r#"{"model": "lambert", "kd": 0.3}"#),
    ("lambert kd=0.5", r#"{"model": "lambert", "kd": 0.5}"#),
    (
        "phong (original) n=20",
        r#"{"model": "phong", "ks": 0.5, "n": 20}"#,
    ),
    (
        "reciprocal phong n=20",
        r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 20}"#,
    ),
    (
        "reciprocal phong n=1000",
        r#"{"model": "reciprocal_phong", "ks": 1, "n": 1000}"#,
    ),
    (
        "max phong n=20",
        r#"{"model": "max_phong", "ks": 0.5, "n": 20}"#,
    ),
    (
        "pumped phong X=mean",
        r#"{"model": "pumped_phong", "ks": 0.5, "n": 20, "x": "mean"}"#,
    ),
    (
        "pumped phong X=product",
        r#"{"model": "pumped_phong", "ks": 0.5, "n": 20, "x": "product"}"#,
    ),
    (
        "pumped phong X=sqrt",
        r#"{"model": "pumped_phong", "ks": 0.5, "n": 20, "x": "sqrt"}"#,
    ),
    (
        "mirror gold",
        r#"{"model": "mirror", "fresnel": {"conductor": "Au"}}"#,
    ),
    (
        "cook-torrance m=0.3 F=1",
        r#"{"model": "cook_torrance", "m": 0.3}"#,
    ),
    (
        "cook-torrance m=0.3 gold",
        r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#,
    ),
    (
        "ggx alpha=0.3 copper",
        r#"{"model": "ggx", "alpha": 0.3, "fresnel": {"conductor": "Cu"}}"#,
    ),
    (
        "blinn-phong n=100",
        r#"{"model": "blinn_phong", "ks": 0.5, "n": 100}"#,
    ),
    (
        "ward 0.1 x 0.3",
        r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
    ),
    (
        "oren-nayar sigma=0.3",
        r#"{"model": "oren_nayar", "kd": 0.3, "sigma": 0.3}"#,
    ),
];

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
    (
        "cook_torrance_gold",
        r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#,
    ),
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
const CT_GOLD: &str = r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#;

/// Pairs of the accuracy comparison (per source).
const ACCURACY_PAIRS: usize = 50_000;

/// Runs the demo.
pub fn demo(a: DemoArgs) -> Result<()> {
    let t0 = Instant::now();
    plausibility_table()?;
    eprintln!("[{:.1} s] plausibility table", t0.elapsed().as_secs_f64());
    if a.plausibility {
        return Ok(());
    }
    let preset = a.preset.as_deref().map(Preset::parse).transpose()?;
    std::fs::create_dir_all(&a.out).map_err(|e| Error::io(&a.out, e))?;
    let out = a.out.canonicalize().map_err(|e| Error::io(&a.out, e))?;
    let db = out.join("demo.btdb");
    if db.exists() {
        std::fs::remove_file(&db).map_err(|e| Error::io(&db, e))?;
    }

    // Sources: the models, then the RGL materials found on disk.
    let mut sources: Vec<(String, Box<dyn Brdf + Send + Sync>, Source)> = Vec::new();
    for (name, spec) in BAKED_MODELS {
        let s = ModelSpec::parse(spec)?;
        let b = s.build(&Channels::Rgb)?;
        sources.push((name.to_string(), b, Source::model(&s)));
    }
    let rgl_dir = crate::source::rgl_dir(a.rgl.as_deref());
    let mut rgl_files = Vec::new();
    match &rgl_dir {
        Some(d) => {
            for e in std::fs::read_dir(d).map_err(|e| Error::io(d, e))? {
                let p = e.map_err(|e| Error::io(d, e))?.path();
                if p.extension().is_some_and(|x| x == "bsdf") {
                    rgl_files.push(p);
                }
            }
            rgl_files.sort();
        }
        None => eprintln!(
            "note: no RGL directory found (--rgl DIR or $BRDFTAB_RGL_DIR); baking the models only"
        ),
    }
    for p in &rgl_files {
        let b = brdftab::measured::RglBrdf::open(p)?;
        let stem = p.file_stem().map(|s| s.to_string_lossy().into_owned());
        let name = format!("rgl_{}", stem.unwrap_or_default().trim_end_matches("_rgb"));
        sources.push((name, Box::new(b), Source::measured(p)?));
    }

    // Bake every source into the database, one progress bar over all values.
    let grids: Vec<table::Grid> = sources
        .iter()
        .map(|(_, b, _)| {
            let small = !b.flags().isotropic;
            let p = preset.unwrap_or(if small { Preset::Small } else { Preset::Medium });
            p.grid(None, Symmetry::from_flags(b.flags()), Channels::Rgb)
        })
        .collect::<Result<_>>()?;
    let total: u64 = grids.iter().map(|g| g.stored_values() as u64).sum();
    emit(&format!(
        "\nBaking {} sources ({} preset, {:.1} M stored values) into {}\n",
        sources.len(),
        a.preset.as_deref().unwrap_or("medium/small"),
        total as f64 / 1e6,
        db.display()
    ))?;
    let bar = progress_bar(total);
    let mut base = 0u64;
    // log16: every value within 1e-3 relative (f16 overflows on sharp lobes like GGX α = 0.1).
    let codec = Codec {
        quant: Quant::Log16 {
            tolerance: 1e-3,
            floor: None,
        },
        ..Codec::default()
    };
    let mut rows = Vec::new();
    for ((name, src, source), grid) in sources.iter().zip(&grids) {
        if let Some(b) = &bar {
            b.set_message(name.clone());
        }
        let progress = |done: u64, _: u64| {
            if let Some(b) = &bar {
                b.set_position(base + done);
            }
        };
        let opts = BakeOptions {
            // Measured data is not exactly isotropic; the grid takes what the file declares.
            force: matches!(source, Source::Measured { .. }),
            progress: Some(&progress),
            ..Default::default()
        };
        let (t, report) = table::bake(src.as_ref(), grid, &opts)?;
        base += grid.stored_values() as u64;
        store::tables::save(&db, name, source.clone(), &t, codec, false)?;
        rows.push((name.clone(), report.seconds));
    }
    if let Some(b) = bar {
        b.finish_and_clear();
    }

    // Read every table back from the database and measure it against its source.
    eprintln!("[{:.1} s] baked", t0.elapsed().as_secs_f64());
    let st = store::Store::open(&db)?;
    emit(&format!(
        "\n{:<24} {:<30} {:>9} {:>7} {:>9} {:>8} {:<13} {:>6}\n",
        "source",
        "grid (stored)",
        "bytes",
        "vs f32",
        "rel RMSE",
        "albedo",
        "pos/rec/energy",
        "bake s"
    ))?;
    let mut previews: Vec<(String, &dyn Brdf, TabulatedBrdf)> = Vec::new();
    for ((name, src, _), (_, bake_s)) in sources.iter().zip(&rows) {
        let stored = st.table(name)?;
        let bytes = stored.compressed_bytes();
        let tab = TabulatedBrdf::from_table(stored.to_table()?);
        let f32_bytes = tab.grid().stored_values() as f64 * 4.0;
        // Measured data (stored as f_r·cos θo) has f_r ∝ 1/cos θo at grazing: compare within 80°
        // of the normal, as Ngan et al. (2005) do; models over the whole hemisphere.
        let measured = name.starts_with("rgl_");
        let acc = if measured {
            accuracy::compare_cap(&tab, src.as_ref(), ACCURACY_PAIRS, 1, 80f64.to_radians())?
        } else {
            accuracy::compare(&tab, src.as_ref(), ACCURACY_PAIRS, 1)?
        };
        let alb = albedo_error(&tab, src.as_ref());
        let r = plausibility::check(&FastAlbedo(&tab), &fast_plausibility());
        let yn = |b: bool| if b { "y" } else { "N" };
        let s = tab.grid().stored_shape();
        emit(&format!(
            "{:<24} {:<30} {:>9} {:>6.2}% {:>8.3}% {:>7.3}% {:<13} {:>6.2}\n",
            name,
            format!("{} {}", param_name(tab.grid()), shape(s)),
            bytes,
            100.0 * bytes as f64 / f32_bytes,
            100.0 * acc.rel_rmse,
            100.0 * alb,
            format!(
                "{}/{}/{}",
                yn(r.positive),
                yn(r.reciprocal),
                yn(r.energy_conserving)
            ),
            bake_s
        ))?;
        let name: &str = name;
        if matches!(
            name,
            "cook_torrance_gold" | "ward_aniso" | "rgl_satin_rosaline"
        ) {
            previews.push((name.to_string(), src.as_ref(), tab));
        }
    }
    emit(
        "\nbytes: compressed size in the database (log16 ≤ 1e-3 relative + predictor + zstd); vs f32: that size \
         relative to the stored values as plain f32;\nrel RMSE: cosine-weighted relative RMSE of \
         the table read back from the database vs its source (50k random pairs;\nmeasured rows (rgl_*): both directions within 80° of the normal, since their f_r grows like 1/cos θo at grazing — see BENCHMARKS.md);\nalbedo: max \
         relative albedo error at θ′ = 0, 30, 60, 80°; pos/rec/energy: plausibility of the stored \
         table (y = yes, N = no;\nmeasured data is not reciprocal, and the lecture's Lambert \
         kd = 0.5 is not energy conserving).\n",
    )?;

    eprintln!("[{:.1} s] tables measured", t0.elapsed().as_secs_f64());
    let mut outputs = vec![db.clone()];
    if !a.quick {
        outputs.extend(preview_renders(&out, &previews)?);
        eprintln!("[{:.1} s] renders done", t0.elapsed().as_secs_f64());
        outputs.extend(rate_distortion(&out)?);
    }
    let mut text = format!("\nDone in {:.1} s. Outputs:\n", t0.elapsed().as_secs_f64());
    for p in outputs {
        text += &format!("  {}\n", p.display());
    }
    emit(&text)
}

/// A progress bar over `total` values on a terminal; `None` (quiet) otherwise.
fn progress_bar(total: u64) -> Option<indicatif::ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return None;
    }
    let b = indicatif::ProgressBar::new(total);
    b.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {percent:>3}% {human_pos}/{human_len} values, eta {eta} {msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    Some(b)
}

fn fast_plausibility() -> plausibility::Options {
    plausibility::Options {
        pairs: 4000,
        thetas_deg: vec![0.0, 30.0, 60.0, 85.0],
        ..Default::default()
    }
}

/// Albedo accuracy of the demo: 1e-4 relative, bounded work (a piecewise-linear table would drive
/// the default 1e-6 adaptive quadrature to its interval limits).
const FAST_ALBEDO: albedo::Options = albedo::Options {
    rel_tol: 1e-4,
    max_outer: 32,
    max_inner: 64,
};

/// A `Brdf` whose albedo uses [`FAST_ALBEDO`] (for the plausibility check of tables).
struct FastAlbedo<'a>(&'a dyn Brdf);

impl Brdf for FastAlbedo<'_> {
    fn channels(&self) -> &Channels {
        self.0.channels()
    }
    fn eval(&self, wi: glam::DVec3, wo: glam::DVec3, out: &mut [f32]) {
        self.0.eval(wi, wo, out)
    }
    fn flags(&self) -> brdftab::Flags {
        self.0.flags()
    }
    fn describe(&self) -> String {
        self.0.describe()
    }
    fn albedo(&self, wi: glam::DVec3, out: &mut [f64]) {
        let e = albedo::integrate(self.0, wi, &FAST_ALBEDO);
        let c = e.value.len().min(out.len());
        out[..c].copy_from_slice(&e.value[..c]);
    }
}

/// Max over θ′ ∈ {0, 30, 60, 80}° and channels of |a_table − a_source| / a_source.
fn albedo_error(table: &dyn Brdf, source: &dyn Brdf) -> f64 {
    let c = source.channels().len();
    let mut worst = 0.0f64;
    for t in [0.0f64, 30.0, 60.0, 80.0] {
        let wi = geometry::spherical(t.to_radians(), 0.0);
        let at = albedo::integrate(table, wi, &FAST_ALBEDO).value;
        let as_ = albedo::integrate(source, wi, &FAST_ALBEDO).value;
        for k in 0..c {
            if as_[k] > 1e-9 {
                worst = worst.max((at[k] - as_[k]).abs() / as_[k]);
            }
        }
    }
    worst
}

fn param_name(g: &table::Grid) -> &'static str {
    match g.param() {
        table::Param::HalfDiff => "halfdiff",
        table::Param::InOut => "inout",
    }
}

fn shape(s: [usize; 4]) -> String {
    s.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join("×")
}

/// Renders source | table | difference for each preview, small, and writes PNGs.
fn preview_renders(
    out: &Path,
    previews: &[(String, &dyn Brdf, TabulatedBrdf)],
) -> Result<Vec<PathBuf>> {
    let opts = RenderOptions {
        width: 96,
        height: 96,
        spp: 16,
        max_depth: 3,
        // Material-independent directions: the difference shows the materials, not the noise.
        sampling: render::Sampling::Fixed,
        env: EnvChoice::Sky,
        ..Default::default()
    };
    emit(&format!(
        "\nPreview renders ({}×{}, {} spp, path tracer ≤ 3 bounces, sky, fixed sampling; same seed for both):\n",
        opts.width, opts.height, opts.spp
    ))?;
    let mut files = Vec::new();
    for (name, src, tab) in previews {
        let a = render::render(*src, &opts, None)?;
        let b = render::render(tab, &opts, None)?;
        let cmp = render::compare(&b, &a)?;
        let (diff, _legend) = render::difference_image(&b, &a)?;
        let side = render::image::Image::hstack(&[&a, &b, &diff.to_rgb()?], 4, 0.0)?;
        let path = out.join(format!("render_{name}.png"));
        render::image::write_png(&side, &path, 0.0)?;
        emit(&format!(
            "  {:<24} rendered rel RMSE table vs source {:.3}%\n",
            name,
            100.0 * cmp.rel_rmse
        ))?;
        files.push(path);
    }
    Ok(files)
}

/// One point of the rate–distortion sweep.
struct RdPoint {
    preset: &'static str,
    codec: &'static str,
    bytes: u64,
    rel_rmse: f64,
}

/// Cook-Torrance gold on every preset × codec: compressed bytes vs rel RMSE. Writes `rd.csv` and
/// a dependency-free log–log plot `rd.svg`.
fn rate_distortion(out: &Path) -> Result<Vec<PathBuf>> {
    let spec = ModelSpec::parse(CT_GOLD)?;
    let src = spec.build(&Channels::Rgb)?;
    let codecs: [(&str, Quant); 3] = [
        ("f32", Quant::F32),
        ("f16", Quant::F16),
        (
            "log16 1e-2",
            Quant::Log16 {
                tolerance: 1e-2,
                floor: None,
            },
        ),
    ];
    let mut points = Vec::new();
    for (pname, preset) in [("small", Preset::Small), ("medium", Preset::Medium)] {
        let grid = preset.grid(None, Symmetry::from_flags(src.flags()), Channels::Rgb)?;
        let (t, _) = table::bake(src.as_ref(), &grid, &BakeOptions::default())?;
        for (cname, quant) in &codecs {
            let c = Codec {
                quant: *quant,
                ..Codec::default()
            };
            // f16 cannot hold the sharpest peaks of some grids: skip that point, say so.
            let (back, bytes) = match roundtrip(&t, &c) {
                Ok(r) => r,
                Err(e) => {
                    eprintln!("note: rate–distortion {pname} {cname} skipped: {e}");
                    continue;
                }
            };
            let acc = accuracy::compare(&TabulatedBrdf::from_table(back), src.as_ref(), 20_000, 2)?;
            points.push(RdPoint {
                preset: pname,
                codec: cname,
                bytes,
                rel_rmse: acc.rel_rmse,
            });
        }
    }
    let mut csv = String::from("preset,codec,bytes,rel_rmse\n");
    emit("\nRate–distortion, Cook-Torrance m = 0.3 gold (bytes vs cosine-weighted rel RMSE):\n")?;
    for p in &points {
        csv += &format!("{},{},{},{:.6e}\n", p.preset, p.codec, p.bytes, p.rel_rmse);
        emit(&format!(
            "  {:<7} {:<11} {:>10} bytes  {:.3}%\n",
            p.preset,
            p.codec,
            p.bytes,
            100.0 * p.rel_rmse
        ))?;
    }
    let csv_path = out.join("rd.csv");
    std::fs::write(&csv_path, csv).map_err(|e| Error::io(&csv_path, e))?;
    let svg_path = out.join("rd.svg");
    std::fs::write(&svg_path, rd_svg(&points)).map_err(|e| Error::io(&svg_path, e))?;
    Ok(vec![csv_path, svg_path])
}

/// Encodes every chunk of `t` with `codec` and decodes it again: (decoded table, bytes).
fn roundtrip(t: &Table, c: &Codec) -> Result<(Table, u64)> {
    let g = t.grid();
    let mut bytes = 0u64;
    let mut values = Vec::with_capacity(t.values().len());
    for a in 0..g.layout().chunk_count() {
        let chunk = t.chunk(a);
        let enc = codec::encode(chunk, store::tables::chunk_layout(g, a), c)?;
        bytes += enc.len() as u64;
        values.extend(codec::decode(&enc, chunk.len())?);
    }
    Ok((Table::new(g.clone(), values, t.description())?, bytes))
}

/// A small log–log scatter plot (bytes → rel RMSE), one colour per codec.
fn rd_svg(points: &[RdPoint]) -> String {
    let (w, h, m) = (560.0, 380.0, 60.0);
    let lx: Vec<f64> = points
        .iter()
        .map(|p| (p.bytes.max(1) as f64).log10())
        .collect();
    let ly: Vec<f64> = points
        .iter()
        .map(|p| p.rel_rmse.max(1e-7).log10())
        .collect();
    let (x0, x1) = (
        lx.iter().cloned().fold(f64::INFINITY, f64::min).floor(),
        lx.iter().cloned().fold(f64::NEG_INFINITY, f64::max).ceil(),
    );
    let (y0, y1) = (
        ly.iter().cloned().fold(f64::INFINITY, f64::min).floor(),
        ly.iter().cloned().fold(f64::NEG_INFINITY, f64::max).ceil(),
    );
    let sx = |x: f64| m + (x - x0) / (x1 - x0).max(1e-9) * (w - 2.0 * m);
    let sy = |y: f64| h - m - (y - y0) / (y1 - y0).max(1e-9) * (h - 2.0 * m);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{}\" y=\"20\" text-anchor=\"middle\">Cook-Torrance m=0.3 gold: size vs accuracy</text>\n",
        w / 2.0
    );
    s += &format!(
        "<rect x=\"{m}\" y=\"{m}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>\n",
        w - 2.0 * m,
        h - 2.0 * m
    );
    for d in (x0 as i32)..=(x1 as i32) {
        let x = sx(d as f64);
        s += &format!(
            "<text x=\"{x}\" y=\"{}\" text-anchor=\"middle\">1e{d}</text>\n",
            h - m + 16.0
        );
    }
    for d in (y0 as i32)..=(y1 as i32) {
        let y = sy(d as f64);
        s += &format!(
            "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">1e{d}</text>\n",
            m - 4.0,
            y + 4.0
        );
    }
    s += &format!(
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">compressed bytes</text>\n<text x=\"14\" y=\"{}\" transform=\"rotate(-90 14 {})\" text-anchor=\"middle\">cos-weighted rel RMSE</text>\n",
        w / 2.0,
        h - 20.0,
        h / 2.0,
        h / 2.0
    );
    let colours = ["#1f77b4", "#d62728", "#2ca02c"];
    let mut codecs: Vec<&str> = Vec::new();
    for p in points {
        if !codecs.contains(&p.codec) {
            codecs.push(p.codec);
        }
    }
    for (i, c) in codecs.iter().enumerate() {
        let col = colours[i % colours.len()];
        let pts: Vec<(f64, f64)> = points
            .iter()
            .zip(lx.iter().zip(&ly))
            .filter(|(p, _)| p.codec == *c)
            .map(|(_, (x, y))| (sx(*x), sy(*y)))
            .collect();
        let path: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
        s += &format!(
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{col}\"/>\n",
            path.join(" ")
        );
        for (x, y) in &pts {
            s += &format!("<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"4\" fill=\"{col}\"/>\n");
        }
        s += &format!(
            "<text x=\"{}\" y=\"{}\" fill=\"{col}\">{c}</text>\n",
            w - m - 80.0,
            m + 16.0 + 16.0 * i as f64
        );
    }
    s + "</svg>\n"
}

/// Prints the plausibility table of [`LECTURE_MODELS`].
fn plausibility_table() -> Result<()> {
    emit(&format!(
        "Physical plausibility of the lecture's BRDF models (RGB; albedo at θ′ = 0..89°)\n\n{:<26} {:<9} {:<22} energy conserving (max albedo @ θ′)\n",
        "model", "positive", "reciprocal (max err)"
    ))?;
    let mut skipped = Vec::new();
    for (label, spec) in LECTURE_MODELS {
        let brdf = match ModelSpec::parse(spec).and_then(|s| s.build(&Channels::Rgb)) {
            Ok(b) => b,
            Err(e) => {
                skipped.push(format!("{label}: {e}"));
                continue;
            }
        };
        let r = plausibility::check(&*brdf, &plausibility::Options::default());
        emit(&format!("{}\n", row(label, &r)))?;
    }
    if !skipped.is_empty() {
        let mut text = "\nskipped (not available in this build):\n".to_string();
        for s in skipped {
            text += &format!("  {s}\n");
        }
        emit(&text)?;
    }
    Ok(())
}

fn row(label: &str, r: &plausibility::Report) -> String {
    let yn = |b: bool| if b { "yes" } else { "NO" };
    format!(
        "{:<26} {:<9} {:<22} {} ({:.4} @ {}°)",
        label,
        yn(r.positive),
        format!("{} ({:.1e})", yn(r.reciprocal), r.max_reciprocity_error),
        yn(r.energy_conserving),
        r.max_albedo,
        r.max_albedo_theta_deg
    )
}
