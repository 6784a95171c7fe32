//! The accuracy suite: how much a stored table costs and how far it is from its source.
//!
//! For every source × grid preset × parameterization × codec the suite
//!
//! 1. bakes the source on the preset grid (symmetry reduced as the source's flags declare; the
//!    bake verifies it, and a source that fails the check is baked without reduction);
//! 2. encodes every chunk with the codec exactly as the store writer does (same per-chunk
//!    predictor layout, [`store::tables::chunk_layout`](brdftab::store::tables::chunk_layout),
//!    zstd level 3) and counts the bytes — the sum of the chunk sizes, which is what a `.btdb`
//!    file holds for the table apart from its small JSON header and chunk index;
//! 3. decodes those bytes back into a [`TabulatedBrdf`] (linear interpolation): every metric is
//!    measured on the *decoded* table, quantization error included;
//! 4. measures, against the source:
//!    - `rel_rmse`, `max_rel`: [`analysis::accuracy::compare`](brdftab::analysis::accuracy::compare) over `pairs` random pairs
//!      (the figure of uniform pairs, half drawn near the mirror direction and weighted back;
//!      cosine-weighted relative RMSE; max relative error with a 1 %-of-RMS floor), weighted
//!      and capped as [`rmse_weighting`] says: by cos θi cos θo (f_r cos θi has no finite RMS
//!      for measured data, Ward or Cook-Torrance), measured data within 80°;
//!    - `albedo_err`: max over the incidence angles `albedo_thetas` and channels of
//!      |a_table − a_source| / a_source (denominator floored at 1e-3 × the largest source
//!      albedo), both albedos by the same adaptive quadrature ([`albedo::integrate`]) with
//!      [`ALBEDO_OPTIONS`], so quadrature error cancels as far as possible;
//!    - `render_rel_rmse`: [`render::compare`](fn@crate::preview::compare) of a small lit-sphere render of the table against
//!      the same render of the source, both with [`Sampling::Fixed`] and the same seed, so the
//!      sampled directions coincide and the difference is (nearly) free of Monte Carlo noise.
//!
//! **Undefined metrics.** Every number in a row is finite. A metric that was not measured is
//! written as `-1` (all real metrics are ≥ 0) and the `status` / `render` columns say why:
//! `render = skipped` when renders are off for that kind of source (e.g. measured data with
//! `render_measured = false`), `status = encode failed: ...` when a codec refuses the data
//! (f16 beyond 65504), `status = bake failed: ...` when the source cannot be baked.
//!
//! **Channels.** Every source is evaluated in RGB (the renderer works in RGB, and RGB keeps
//! tables of every source the same size). The spectral gold conductor of Cook-Torrance is
//! evaluated at the RGB channel wavelengths (645, 526, 444 nm), i.e. three samples of the
//! measured n + ik of gold.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;

use crate::preview::{self, LightChoice, Mode, RenderOptions, Sampling};
use brdftab::analysis::{accuracy, albedo, fidelity};
use brdftab::bake::{BakeRequest, SymmetryChoice};
use brdftab::brdf::Brdf;
use brdftab::codec::{self, Codec, Quant};
use brdftab::error::{Error, Result};
use brdftab::geometry;
use brdftab::progress::{Progress, Silent, Stage};
use brdftab::spec::ModelSpec;
use brdftab::spectrum::{Channels, MAX_CHANNELS};
use brdftab::table::presets::Preset;
use brdftab::table::{Param, Symmetry, Table, TabulatedBrdf};

/// Quadrature settings of the albedo metric: the library's settings for data (a 1e-4 target
/// with bounded interval counts, so a piecewise-linear table, whose kinks defeat a 1e-6
/// target, costs at most ~30 000 evaluations per angle).
pub const ALBEDO_OPTIONS: albedo::Options = albedo::Options::DATA;

/// Written where a metric was not measured (see the module docs).
pub const NOT_MEASURED: f64 = -1.0;

/// Where a source comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum Origin {
    /// An analytic model (evaluated in RGB).
    Model(ModelSpec),
    /// An RGL-EPFL `.bsdf` file.
    Rgl(PathBuf),
}

/// One source of the suite: a short name (used in file names and the CSV) and what it is.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceDef {
    /// Short name, e.g. `reciprocal_phong_n100`.
    pub name: String,
    /// The model spec or measured file.
    pub kind: Origin,
}

impl SourceDef {
    /// A model source from its JSON spec.
    pub fn model(name: &str, json: &str) -> Result<SourceDef> {
        Ok(SourceDef {
            name: name.to_owned(),
            kind: Origin::Model(ModelSpec::parse(json)?),
        })
    }

    /// `model` or `measured`.
    pub fn kind_name(&self) -> &'static str {
        match self.kind {
            Origin::Model(_) => "model",
            Origin::Rgl(_) => "measured",
        }
    }

    /// The source as a SOURCE ([`brdftab::source`]): the spec's JSON or the file's path (as
    /// the bytes it is: a directory whose name is not UTF-8 is found).
    pub fn source(&self) -> std::ffi::OsString {
        match &self.kind {
            Origin::Model(spec) => spec.to_json().into(),
            Origin::Rgl(path) => path.clone().into_os_string(),
        }
    }

    /// Opens the source as a `Brdf` (RGB).
    pub fn open(&self) -> Result<Box<dyn Brdf + Send + Sync>> {
        match &self.kind {
            Origin::Model(spec) => spec.build(&Channels::Rgb),
            Origin::Rgl(path) => Ok(Box::new(brdftab::measured::RglBrdf::open(path)?)),
        }
    }
}

/// The lecture's models and the extra microfacet models, in RGB:
/// Lambert; original / reciprocal / max Phong at n = 10, 100, 1000 (k_s = ½(n+2)/2π, so the
/// normal-incidence albedo of reciprocal Phong is about ½); Cook-Torrance m = 0.1, 0.3, 0.5 with
/// a gold conductor; GGX α = 0.1, 0.3; Ward anisotropic (α_x = 0.1, α_y = 0.3).
pub fn lecture_sources() -> Vec<SourceDef> {
    let mut v = vec![(
        "lambert".to_owned(),
        r#"{"model": "lambert", "kd": [0.2, 0.15, 0.1]}"#.to_owned(),
    )];
    for (model, short) in [
        ("phong", "phong"),
        ("reciprocal_phong", "reciprocal_phong"),
        ("max_phong", "max_phong"),
    ] {
        for n in [10, 100, 1000] {
            let ks = 0.5 * (n as f64 + 2.0) / (2.0 * PI);
            v.push((
                format!("{short}_n{n}"),
                format!(r#"{{"model": "{model}", "ks": {ks}, "n": {n}}}"#),
            ));
        }
    }
    for x in ["mean", "product", "sqrt"] {
        for n in [10, 100, 1000] {
            let ks = 0.5 * (n as f64 + 2.0) / (2.0 * PI);
            v.push((
                format!("pumped_phong_{x}_n{n}"),
                format!(r#"{{"model": "pumped_phong", "ks": {ks}, "n": {n}, "x": "{x}"}}"#),
            ));
        }
    }
    for m in ["0.1", "0.3", "0.5"] {
        v.push((
            format!("cook_torrance_m{m}"),
            format!(r#"{{"model": "cook_torrance", "m": {m}, "fresnel": {{"conductor": "Au"}}}}"#),
        ));
    }
    for a in ["0.1", "0.3"] {
        v.push((
            format!("ggx_a{a}"),
            format!(r#"{{"model": "ggx", "alpha": {a}}}"#),
        ));
    }
    v.push((
        "ward_aniso".to_owned(),
        r#"{"model": "ward", "ks": 0.5, "alpha_x": 0.1, "alpha_y": 0.3}"#.to_owned(),
    ));
    v.into_iter()
        .map(|(name, json)| {
            SourceDef::model(&name, &json).expect("the built-in source specs are valid")
        })
        .collect()
}

/// The RGL `.bsdf` files in `dir`, sorted by name (source name = file stem).
pub fn rgl_sources(dir: impl AsRef<Path>) -> Result<Vec<SourceDef>> {
    let dir = dir.as_ref();
    let mut v: Vec<SourceDef> = std::fs::read_dir(dir)
        .map_err(|e| Error::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.extension()
                .is_some_and(|x| x.eq_ignore_ascii_case("bsdf"))
        })
        .map(|p| SourceDef {
            name: p
                .file_stem()
                .map_or_else(String::new, |s| s.to_string_lossy().into_owned()),
            kind: Origin::Rgl(p),
        })
        .collect();
    v.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(v)
}

/// A named codec configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CodecDef {
    /// Name in the CSV, e.g. `log16@1e-3`.
    pub name: &'static str,
    /// The codec.
    pub codec: Codec,
}

/// f32, f16, log16 at 1e-2 and at 1e-3 (zstd level 3, filter chosen per chunk).
pub fn default_codecs() -> Vec<CodecDef> {
    let with = |quant| Codec {
        quant,
        ..Codec::default()
    };
    vec![
        CodecDef {
            name: "f32",
            codec: with(Quant::F32),
        },
        CodecDef {
            name: "f16",
            codec: with(Quant::F16),
        },
        CodecDef {
            name: "log16@1e-2",
            codec: with(Quant::Log16 {
                tolerance: 1e-2,
                floor: None,
            }),
        },
        CodecDef {
            name: "log16@1e-3",
            codec: with(Quant::Log16 {
                tolerance: 1e-3,
                floor: None,
            }),
        },
    ]
}

/// What the suite runs.
#[derive(Debug, Clone)]
pub struct SuiteConfig {
    /// The sources.
    pub sources: Vec<SourceDef>,
    /// Grid presets.
    pub presets: Vec<Preset>,
    /// Parameterizations.
    pub params: Vec<Param>,
    /// Codecs.
    pub codecs: Vec<CodecDef>,
    /// Random direction pairs of the BRDF-space metrics.
    pub pairs: usize,
    /// Incidence angles (radians) of the albedo metric.
    pub albedo_thetas: Vec<f64>,
    /// The preview render (`None`: no render metric). Use `Sampling::Fixed`.
    pub render: Option<RenderOptions>,
    /// Whether measured sources are rendered too.
    pub render_measured: bool,
    /// Seed of the random pairs.
    pub seed: u64,
}

fn preview(size: usize, spp: usize) -> RenderOptions {
    RenderOptions {
        width: size,
        height: size,
        spp,
        seed: 7,
        max_depth: 1,
        mode: Mode::Lit,
        sampling: Sampling::Fixed,
        light: LightChoice::Area,
        ..RenderOptions::default()
    }
}

impl SuiteConfig {
    /// The full suite: every lecture source and every RGL file in `rgl_dir` (if given), all three
    /// presets, both parameterizations, the four codecs, 200 000 pairs, 8 albedo angles, 64×64
    /// renders at 16 spp (measured sources included).
    pub fn full(rgl_dir: Option<&Path>) -> Result<SuiteConfig> {
        let mut sources = lecture_sources();
        if let Some(d) = rgl_dir {
            sources.extend(rgl_sources(d)?);
        }
        Ok(SuiteConfig {
            sources,
            presets: vec![Preset::Small, Preset::Medium, Preset::Large],
            params: vec![Param::HalfDiff, Param::InOut],
            codecs: default_codecs(),
            pairs: 200_000,
            albedo_thetas: (0..8)
                .map(|i| (5.0 + 10.0 * i as f64).to_radians())
                .collect(),
            render: Some(preview(64, 16)),
            render_measured: true,
            seed: 1,
        })
    }

    /// The quick suite (about a minute on 2 cores): Lambert, the lecture's Phong family at
    /// n = 100 — the original Phong (`phong`), the reciprocal (`reciprocal_phong_n100`), the max
    /// (`max_phong`) and the pumped-up Phong with X = mean, product and sqrt
    /// (`pumped_phong_mean`, `pumped_phong_product`, `pumped_phong_sqrt`) —, Cook-Torrance
    /// m = 0.3 (gold), GGX α = 0.3, Ward, and the first RGL file; the small preset; 20 000
    /// pairs; 3 albedo angles; 24×24 renders at 4 spp.
    pub fn quick(rgl_dir: Option<&Path>) -> Result<SuiteConfig> {
        // (name in the full suite, name in the quick one: the model's name where only one
        // variant of it runs).
        let keep = [
            ("lambert", "lambert"),
            ("phong_n100", "phong"),
            ("reciprocal_phong_n100", "reciprocal_phong_n100"),
            ("max_phong_n100", "max_phong"),
            ("pumped_phong_mean_n100", "pumped_phong_mean"),
            ("pumped_phong_product_n100", "pumped_phong_product"),
            ("pumped_phong_sqrt_n100", "pumped_phong_sqrt"),
            ("cook_torrance_m0.3", "cook_torrance_m0.3"),
            ("ggx_a0.3", "ggx_a0.3"),
            ("ward_aniso", "ward_aniso"),
        ];
        let mut sources: Vec<SourceDef> = lecture_sources()
            .into_iter()
            .filter_map(|mut s| {
                let (_, quick) = keep.iter().find(|(full, _)| *full == s.name)?;
                s.name = (*quick).to_owned();
                Some(s)
            })
            .collect();
        if let Some(d) = rgl_dir {
            sources.extend(rgl_sources(d)?.into_iter().take(1));
        }
        Ok(SuiteConfig {
            sources,
            presets: vec![Preset::Small],
            params: vec![Param::HalfDiff, Param::InOut],
            codecs: default_codecs(),
            pairs: 20_000,
            albedo_thetas: [10.0f64, 45.0, 75.0]
                .iter()
                .map(|d| d.to_radians())
                .collect(),
            render: Some(preview(24, 4)),
            render_measured: true,
            seed: 1,
        })
    }

    /// Number of rows the suite will produce.
    pub fn row_count(&self) -> usize {
        self.sources.len() * self.presets.len() * self.params.len() * self.codecs.len()
    }
}

/// One row: a source on one grid with one codec.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Source name.
    pub source: String,
    /// `model` or `measured`.
    pub kind: String,
    /// `small`, `medium` or `large`.
    pub preset: String,
    /// `halfdiff` or `inout`.
    pub param: String,
    /// The grid's symmetry reduction.
    pub symmetry: String,
    /// Codec name.
    pub codec: String,
    /// Stored values (nodes × channels).
    pub values: u64,
    /// Compressed bytes (sum of chunk sizes).
    pub bytes: u64,
    /// bytes / bytes of the f32 codec on the same grid (−1 if that is unknown).
    pub ratio_f32: f64,
    /// Bits per stored value.
    pub bits_per_value: f64,
    /// Cosine-weighted relative RMSE.
    pub rel_rmse: f64,
    /// Max relative error.
    pub max_rel: f64,
    /// Max relative albedo error.
    pub albedo_err: f64,
    /// Relative RMSE of f_r cos θi cos θo with both directions within 80°, on the mirror-centred
    /// product rule ([`fidelity`]: no heavy tail on near-mirror materials).
    pub rmse_80: f64,
    /// The same over the whole hemisphere of both directions.
    pub rmse_whole: f64,
    /// The same over the grazing band (a direction beyond 80°).
    pub rmse_grazing: f64,
    /// The worst directional-albedo error over θ′ = 1..89° (odd degrees and 89°) and the
    /// channels, a channel darker than 0.02 judged against 0.02.
    pub albedo_worst: f64,
    /// Where that is (degrees).
    pub albedo_worst_deg: f64,
    /// Relative RMSE of the preview render.
    pub render_rel_rmse: f64,
    /// `ok` or `skipped`.
    pub render: String,
    /// `ok` or what went wrong.
    pub status: String,
    /// Seconds spent on this row (encode, decode, metrics; the bake is shared by the codecs of
    /// a grid and not included).
    pub seconds: f64,
}

/// The CSV header (column names of [`Row`], in order).
pub const CSV_HEADER: &str = "source,kind,preset,param,symmetry,codec,values,bytes,ratio_f32,bits_per_value,rel_rmse,max_rel,albedo_err,rmse_80,rmse_whole,rmse_grazing,albedo_worst,albedo_worst_deg,render_rel_rmse,render,status,seconds";

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

fn num(x: f64) -> String {
    if !x.is_finite() {
        // Never reached for measured metrics (they are made finite before); kept as a guard.
        return "-1".into();
    }
    format!("{x:.6e}")
}

impl Row {
    /// The row as a CSV line (no newline).
    pub fn csv(&self) -> String {
        [
            csv_field(&self.source),
            csv_field(&self.kind),
            csv_field(&self.preset),
            csv_field(&self.param),
            csv_field(&self.symmetry),
            csv_field(&self.codec),
            self.values.to_string(),
            self.bytes.to_string(),
            num(self.ratio_f32),
            num(self.bits_per_value),
            num(self.rel_rmse),
            num(self.max_rel),
            num(self.albedo_err),
            num(self.rmse_80),
            num(self.rmse_whole),
            num(self.rmse_grazing),
            num(self.albedo_worst),
            num(self.albedo_worst_deg),
            num(self.render_rel_rmse),
            csv_field(&self.render),
            csv_field(&self.status),
            format!("{:.3}", self.seconds),
        ]
        .join(",")
    }
}

/// The result of [`run`].
#[derive(Debug, Clone)]
pub struct Report {
    /// One row per source × preset × parameterization × codec.
    pub rows: Vec<Row>,
    /// Wall-clock seconds of the whole run.
    pub seconds: f64,
    /// A one-line description of the configuration.
    pub config: String,
}

impl Report {
    /// The CSV text (header and rows).
    pub fn csv(&self) -> String {
        let mut s = String::from(CSV_HEADER);
        s.push('\n');
        for r in &self.rows {
            s.push_str(&r.csv());
            s.push('\n');
        }
        s
    }

    /// A Markdown report: configuration, run time and one table row per CSV row.
    pub fn markdown(&self) -> String {
        let mut s = String::from("# brdftab accuracy suite\n\n");
        s.push_str(&format!(
            "{}\n\nRun time: {:.1} s, {} rows. Metrics are measured on the decoded table \
             (quantization included) against the source; `-1` = not measured (see the `render` \
             and `status` columns). rel RMSE is cosine-weighted; albedo error is the max \
             relative error over the incidence angles; 80° / whole / grazing are relative RMSEs \
             of f_r cos θi cos θo within 80°, over the whole hemisphere and in the band beyond \
             80°, on a mirror-centred product rule; albedo worst is the largest albedo error over \
             θ′ = 1..89°; render error is the relative RMSE of a lit-sphere preview (fixed \
             sampling, same seed).\n\n",
            self.config,
            self.seconds,
            self.rows.len()
        ));
        s.push_str(
            "| source | preset | param | sym | codec | bytes | ×f32 | bits/value | rel RMSE | max rel | albedo err | 80° / whole / grazing | albedo worst (θ′) | render err | status |\n\
             |---|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n",
        );
        let md = |x: f64| {
            if x == NOT_MEASURED {
                "–".to_owned()
            } else {
                format!("{x:.2e}")
            }
        };
        for r in &self.rows {
            s.push_str(&format!(
                "| {} | {} | {} | {} | {} | {} | {:.3} | {:.2} | {} | {} | {} | {} / {} / {} | {} ({}°) | {} | {} |\n",
                r.source,
                r.preset,
                r.param,
                r.symmetry,
                r.codec,
                r.bytes,
                r.ratio_f32,
                r.bits_per_value,
                md(r.rel_rmse),
                md(r.max_rel),
                md(r.albedo_err),
                md(r.rmse_80),
                md(r.rmse_whole),
                md(r.rmse_grazing),
                md(r.albedo_worst),
                r.albedo_worst_deg,
                if r.render == "ok" {
                    md(r.render_rel_rmse)
                } else {
                    r.render.clone()
                },
                r.status.replace('|', "/"),
            ));
        }
        s
    }
}

/// A name made safe for a file name (letters, digits, `-`, `_`, `.`).
pub fn file_safe(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Albedo per θ and channel by [`albedo::integrate`] with [`ALBEDO_OPTIONS`].
pub fn albedos(brdf: &dyn Brdf, thetas: &[f64]) -> Vec<Vec<f64>> {
    brdftab::par::install(|| {
        thetas
            .par_iter()
            .map(|&t| albedo::integrate(brdf, geometry::spherical(t, 0.0), &ALBEDO_OPTIONS).value)
            .collect()
    })
}

/// Max over θ and channels of |a − a_ref| / max(a_ref, 1e-3 · max a_ref).
pub fn albedo_error(a: &[Vec<f64>], reference: &[Vec<f64>]) -> f64 {
    let top = reference
        .iter()
        .flatten()
        .fold(0.0f64, |m, &x| m.max(x.abs()));
    let floor = (1e-3 * top).max(1e-12);
    let mut worst = 0.0f64;
    for (ra, rr) in a.iter().zip(reference) {
        for (&x, &y) in ra.iter().zip(rr) {
            let e = (x - y).abs() / y.abs().max(floor);
            if e.is_finite() {
                worst = worst.max(e);
            }
        }
    }
    worst
}

/// Encodes every chunk of `table` with `codec` (as the store writer does) and decodes it again:
/// (compressed bytes, decoded table).
pub fn round_trip(table: &Table, codec: &Codec) -> Result<(u64, Table)> {
    let grid = table.grid();
    let n = grid.layout().chunk_count();
    let parts: Vec<(usize, Vec<f32>)> = brdftab::par::install(|| {
        (0..n)
            .into_par_iter()
            .map(|a| {
                let bytes = codec::encode(
                    table.chunk(a),
                    brdftab::store::tables::chunk_layout(grid, a),
                    codec,
                )?;
                let back = codec::decode(&bytes, grid.layout().chunk_len(a))?;
                Ok((bytes.len(), back))
            })
            .collect::<Result<_>>()
    })?;
    let bytes = parts.iter().map(|p| p.0 as u64).sum();
    let mut values = Vec::with_capacity(grid.stored_values());
    for (_, v) in parts {
        values.extend_from_slice(&v);
    }
    Ok((
        bytes,
        Table::new(grid.clone(), values, table.description())?,
    ))
}

/// Bakes `src` (opened from `sd`) through [`BakeRequest`] with the symmetry it declares; a
/// source that breaks it (within tolerance) is baked with isotropy only if that holds, else
/// without reduction.
fn bake_table(sd: &SourceDef, src: &dyn Brdf, preset: Preset, param: Param) -> Result<Table> {
    let declared = Symmetry::from_flags(src.flags());
    let iso = Symmetry {
        isotropic: declared.isotropic,
        ..Symmetry::NONE
    };
    let mut last = None;
    for sym in [declared, iso, Symmetry::NONE] {
        let req = BakeRequest::new(sd.source())
            .preset(preset)
            .param(param)
            .channels(Channels::Rgb)
            .symmetry(SymmetryChoice::Exactly(sym));
        match req.table_of(src, &Silent) {
            Ok((t, _)) => return Ok(t),
            Err(e @ Error::Symmetry { .. }) => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| Error::Unsupported("no symmetry to bake with".into())))
}

/// The BRDF-space metrics of one table against its source.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Metrics {
    /// Cosine-weighted relative RMSE ([`accuracy::compare`]).
    pub rel_rmse: f64,
    /// Max relative error.
    pub max_rel: f64,
    /// Max relative albedo error ([`albedo_error`]; 0 with no angles).
    pub albedo_err: f64,
}

/// What [`metrics`] measures: random pairs (and their seed), the albedo angles, and an optional
/// cap on both directions' polar angle (radians; measured data is compared within 80° of the
/// normal, where its f_r does not grow like 1/cos θo).
#[derive(Debug, Clone, PartialEq)]
pub struct MetricOptions {
    /// Random direction pairs.
    pub pairs: usize,
    /// Seed of the pairs.
    pub seed: u64,
    /// Incidence angles (radians) of the albedo error.
    pub albedo_thetas: Vec<f64>,
    /// Largest polar angle of both directions (`None`: the whole hemisphere).
    pub cap: Option<f64>,
    /// The cosine weight of the relative RMSE (default f_r cos θi; measured tables are judged
    /// with f_r cos θi cos θo, as `brdftab bench --measured` does).
    pub weight: accuracy::Weight,
}

/// The cap and weight of a table's `rel_rmse` (the suite's rows and the demo's): weighted by
/// cos θi cos θo, over the whole hemisphere — measured data (stored as f_r cos θo, f_r ∝
/// 1/cos θo at grazing) within 80° of the normal, as `brdftab bench --measured` (Ngan et al.
/// 2005). Weighted by cos θi alone the RMS is infinite for measured data, for Ward
/// (f_r ∝ 1/√(cos θi cos θo)) and for Cook-Torrance (f_r ∝ 1/cos² θ on the grazing mirror):
/// ∫ dcos θo / cos θo diverges, and the pairs nearest the horizon set the figure (Ward's small
/// table read 115 % where its whole-domain error is 2 %; Cook-Torrance gold's medium table
/// 0.45–21 % over three seeds of uniform pairs, 5–8 % of the mirror mixture, where its
/// whole-domain error is 0.14 %).
pub fn rmse_weighting(measured: bool) -> (Option<f64>, accuracy::Weight) {
    (
        measured.then(|| 80f64.to_radians()),
        accuracy::Weight::CosInCosOut,
    )
}

/// `table` against `source`: the suite's metrics, for one table (the demo's rows use it too).
/// `source_albedo` is [`albedos`] of the source at `opts.albedo_thetas` (computed once by
/// callers that measure several tables of one source).
pub fn metrics(
    table: &dyn Brdf,
    source: &dyn Brdf,
    source_albedo: &[Vec<f64>],
    opts: &MetricOptions,
) -> Result<Metrics> {
    let a = match (opts.cap, opts.weight) {
        (None, accuracy::Weight::CosIn) => accuracy::compare(table, source, opts.pairs, opts.seed)?,
        (cap, w) => accuracy::compare_weighted(
            table,
            source,
            opts.pairs,
            opts.seed,
            cap.unwrap_or(std::f64::consts::FRAC_PI_2),
            w,
        )?,
    };
    Ok(Metrics {
        rel_rmse: finite_or(a.rel_rmse, NOT_MEASURED),
        max_rel: finite_or(a.max_rel, NOT_MEASURED),
        albedo_err: albedo_error(&albedos(table, &opts.albedo_thetas), source_albedo),
    })
}

/// The suite's whole-domain figures ([`fidelity::FidelityReference`]): `pairs` random pairs,
/// the albedo at odd degrees 1..89° and 89° on a 64-azimuth rule.
fn fidelity_options(pairs: usize) -> fidelity::FidelityOptions {
    fidelity::FidelityOptions {
        pairs,
        albedo_thetas_deg: (0..45).map(|k| (2 * k + 1) as f64).chain([89.0]).collect(),
        albedo_phi: 64,
        albedo_order: 6,
        ..Default::default()
    }
}

fn finite_or(x: f64, alt: f64) -> f64 {
    if x.is_finite() { x } else { alt }
}

/// Runs the suite. `progress` sees one stage, `"accuracy"`, counting rows (set after each
/// grid, with a note naming it).
pub fn run(cfg: &SuiteConfig, progress: &dyn Progress) -> Result<Report> {
    let start = Instant::now();
    if cfg.pairs == 0 {
        return Err(Error::arg("pairs", "must be at least 1"));
    }
    let total = cfg.row_count();
    let _stage = Stage::begin(progress, "accuracy", total as u64);
    let metric_opts = MetricOptions {
        pairs: cfg.pairs,
        seed: cfg.seed,
        albedo_thetas: cfg.albedo_thetas.clone(),
        cap: None,
        weight: accuracy::Weight::CosIn,
    };
    let mut rows = Vec::with_capacity(total);
    for sd in &cfg.sources {
        let src = sd.open()?;
        let c = src.channels().len();
        if c == 0 || c > MAX_CHANNELS {
            return Err(Error::arg("source", format!("{}: {c} channels", sd.name)));
        }
        let measured = matches!(sd.kind, Origin::Rgl(_));
        let render_opts = cfg
            .render
            .as_ref()
            .filter(|_| !measured || cfg.render_measured);
        let src_albedo = albedos(src.as_ref(), &cfg.albedo_thetas);
        let fid_opts = fidelity_options(cfg.pairs);
        let fid_ref = fidelity::FidelityReference::new(src.as_ref(), &fid_opts)?;
        let src_image = match render_opts {
            Some(o) => Some(preview::render(src.as_ref(), o, &Silent)?),
            None => None,
        };
        for &preset in &cfg.presets {
            for &param in &cfg.params {
                let base = |codec: &str| Row {
                    source: sd.name.clone(),
                    kind: sd.kind_name().to_owned(),
                    preset: preset.name().to_owned(),
                    param: param.name().to_owned(),
                    symmetry: String::new(),
                    codec: codec.to_owned(),
                    values: 0,
                    bytes: 0,
                    ratio_f32: NOT_MEASURED,
                    bits_per_value: NOT_MEASURED,
                    rel_rmse: NOT_MEASURED,
                    max_rel: NOT_MEASURED,
                    albedo_err: NOT_MEASURED,
                    rmse_80: NOT_MEASURED,
                    rmse_whole: NOT_MEASURED,
                    rmse_grazing: NOT_MEASURED,
                    albedo_worst: NOT_MEASURED,
                    albedo_worst_deg: NOT_MEASURED,
                    render_rel_rmse: NOT_MEASURED,
                    render: "skipped".to_owned(),
                    status: "ok".to_owned(),
                    seconds: 0.0,
                };
                let table = match bake_table(sd, src.as_ref(), preset, param) {
                    Ok(t) => t,
                    Err(e) => {
                        for cd in &cfg.codecs {
                            rows.push(Row {
                                status: format!("bake failed: {e}"),
                                ..base(cd.name)
                            });
                        }
                        continue;
                    }
                };
                let sym = table.grid().symmetry().to_string();
                let values = table.grid().stored_values() as u64;
                let mut group: Vec<Row> = brdftab::par::install(|| {
                    cfg.codecs
                        .par_iter()
                        .map(|cd| {
                            let t0 = Instant::now();
                            let mut row = Row {
                                symmetry: sym.clone(),
                                values,
                                ..base(cd.name)
                            };
                            let (bytes, decoded) = match round_trip(&table, &cd.codec) {
                                Ok(x) => x,
                                Err(e) => {
                                    row.status = format!("encode failed: {e}");
                                    return row;
                                }
                            };
                            row.bytes = bytes;
                            row.bits_per_value = 8.0 * bytes as f64 / values.max(1) as f64;
                            let tab = TabulatedBrdf::from_table(decoded);
                            let (cap, weight) = rmse_weighting(measured);
                            let opts = MetricOptions {
                                cap,
                                weight,
                                ..metric_opts.clone()
                            };
                            match metrics(&tab, src.as_ref(), &src_albedo, &opts) {
                                Ok(m) => {
                                    row.rel_rmse = m.rel_rmse;
                                    row.max_rel = m.max_rel;
                                    row.albedo_err = m.albedo_err;
                                }
                                Err(e) => row.status = format!("accuracy failed: {e}"),
                            }
                            match fid_ref.measure(&tab) {
                                Ok(f) => {
                                    row.rmse_80 = finite_or(f.rule.cap, NOT_MEASURED);
                                    row.rmse_whole = finite_or(f.rule.whole, NOT_MEASURED);
                                    row.rmse_grazing = finite_or(f.rule.grazing, NOT_MEASURED);
                                    row.albedo_worst = finite_or(f.albedo.worst, NOT_MEASURED);
                                    row.albedo_worst_deg = f.albedo.theta_deg;
                                }
                                Err(e) => row.status = format!("fidelity failed: {e}"),
                            }
                            if let (Some(o), Some(reference)) = (render_opts, &src_image) {
                                match preview::render(&tab, o, &Silent)
                                    .and_then(|img| preview::compare(&img, reference))
                                {
                                    Ok(r) if r.rel_rmse.is_finite() => {
                                        row.render_rel_rmse = r.rel_rmse;
                                        row.render = "ok".to_owned();
                                    }
                                    Ok(_) => row.render = "undefined (black reference)".to_owned(),
                                    Err(e) => row.render = format!("failed: {e}"),
                                }
                            }
                            row.seconds = t0.elapsed().as_secs_f64();
                            row
                        })
                        .collect()
                });
                let f32_bytes = group
                    .iter()
                    .zip(&cfg.codecs)
                    .find(|(r, cd)| cd.codec.quant == Quant::F32 && r.bytes > 0)
                    .map(|(r, _)| r.bytes);
                if let Some(fb) = f32_bytes {
                    for r in &mut group {
                        if r.bytes > 0 {
                            r.ratio_f32 = r.bytes as f64 / fb as f64;
                        }
                    }
                }
                rows.extend(group);
                progress.note(&format!("{} {} {}", sd.name, preset.name(), param.name()));
                progress.set(rows.len() as u64);
            }
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    let config = format!(
        "{} sources × presets [{}] × params [{}] × codecs [{}]; {} pairs; albedo at θ = [{}]°; {}",
        cfg.sources.len(),
        cfg.presets
            .iter()
            .map(|&p| p.name())
            .collect::<Vec<_>>()
            .join(", "),
        cfg.params
            .iter()
            .map(|&p| p.name())
            .collect::<Vec<_>>()
            .join(", "),
        cfg.codecs
            .iter()
            .map(|c| c.name)
            .collect::<Vec<_>>()
            .join(", "),
        cfg.pairs,
        cfg.albedo_thetas
            .iter()
            .map(|t| format!("{:.0}", t.to_degrees()))
            .collect::<Vec<_>>()
            .join(", "),
        match &cfg.render {
            Some(o) => format!(
                "renders {}×{} at {} spp (lit sphere, fixed sampling){}",
                o.width,
                o.height,
                o.spp,
                if cfg.render_measured {
                    ""
                } else {
                    ", measured sources not rendered"
                }
            ),
            None => "no renders".to_owned(),
        }
    );
    Ok(Report {
        rows,
        seconds,
        config,
    })
}
