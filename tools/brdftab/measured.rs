//! `info` for measured files and `slice` (any SOURCE).

use brdftab::analysis::slice;
use brdftab::measured::{MerlBrdf, RglBrdf, merl, tensor::TensorFile};
use brdftab::{Brdf, Channels, Error, Result};
use clap::{Args, ValueEnum};

use crate::source::{self, Kind};

/// Arguments of `brdftab info`.
#[derive(Args)]
pub struct InfoArgs {
    /// A MERL `.binary` or RGL `.bsdf` file.
    source: String,
}

/// `info` for a measured file named by path (used by the table `info` command's dispatch).
pub fn info_source(source: &str) -> Result<()> {
    info(InfoArgs {
        source: source.to_owned(),
    })
}

/// Prints what a measured file holds: description, dimensions, channels, sha256.
pub fn info(a: InfoArgs) -> Result<()> {
    match source::kind(&a.source) {
        Kind::Merl => info_merl(&a.source),
        Kind::Rgl => info_rgl(&a.source),
        _ => Err(Error::Unsupported(format!(
            "{}: `info` handles measured files (.binary, .bsdf) here",
            a.source
        ))),
    }
}

fn info_merl(path: &str) -> Result<()> {
    let sha = merl::sha256_file(path)?;
    let m = MerlBrdf::open(path)?;
    println!("file:        {path}");
    println!("format:      MERL BRDF database (.binary, Matusik et al. 2003)");
    match merl::material_of(&sha) {
        Some(name) => println!("material:    {name} (sha256 matches the published file)"),
        None => println!("material:    unknown (sha256 matches none of the 100 published files)"),
    }
    println!(
        "dims:        θh {} × θd {} × φd {} (sqrt θh axis), {} bytes",
        merl::RES_THETA_H,
        merl::RES_THETA_D,
        merl::RES_PHI_D,
        merl::FILE_SIZE
    );
    println!("channels:    R G B (scales 1/1500, 1.15/1500, 1.66/1500)");
    println!(
        "unmeasured:  {} of {} cells (negative, evaluated as 0)",
        m.invalid_cells(),
        merl::SAMPLES
    );
    println!("sha256:      {sha}");
    Ok(())
}

fn info_rgl(path: &str) -> Result<()> {
    let t = TensorFile::open(path)?;
    let b = RglBrdf::from_tensor(&t, None)?;
    let s = b.summary();
    println!("file:        {path}");
    println!(
        "format:      RGL-EPFL tensor file (.bsdf, Dupuy & Jakob 2018), {} bytes",
        t.size()
    );
    println!("description: {}", s.description);
    println!("kind:        {}", s.kind);
    println!(
        "dims:        φi {} × θi {}, table {}×{}, vndf {}×{}, {}",
        s.phi_i,
        s.theta_i,
        s.resolution.0,
        s.resolution.1,
        s.vndf_resolution.0,
        s.vndf_resolution.1,
        if s.isotropic {
            "isotropic".to_string()
        } else {
            format!("anisotropic, reduction {}", s.reduction)
        }
    );
    println!("channels:    {}", b.channels().names().join(" "));
    println!("fields:");
    for f in t.fields() {
        println!("  {:<12} {:<22} @ {}", f.name, f.describe(), f.offset);
    }
    println!("sha256:      {}", b.sha256());
    Ok(())
}

/// Which slice to draw.
#[derive(Clone, Copy, ValueEnum)]
pub enum SliceKind {
    /// θh (x) × θd (y) at a fixed φd, the MERL-style image.
    Halfdiff,
    /// f_r · cos θo over the outgoing hemisphere for one incident direction.
    Polar,
}

/// Arguments of `brdftab slice`.
#[derive(Args)]
pub struct SliceArgs {
    /// Any SOURCE (spec, table, .binary, .bsdf).
    source: String,
    /// Output image: `.exr` (linear f32) or `.png` (log scale, viridis, colorbar).
    #[arg(short, long)]
    output: String,
    /// Which slice.
    #[arg(long, value_enum, default_value = "halfdiff")]
    kind: SliceKind,
    /// Incident polar angle in degrees (polar slice).
    #[arg(long, default_value_t = 45.0)]
    theta_in: f64,
    /// Incident azimuth in degrees (polar slice).
    #[arg(long, default_value_t = 0.0)]
    phi_in: f64,
    /// Difference azimuth φd in degrees (halfdiff slice).
    #[arg(long, default_value_t = 90.0)]
    phi_d: f64,
    /// Channel to show in PNGs (and grey EXRs): a name (R, G, B, 550nm) or index; default
    /// luminance for RGB, the channel mean otherwise.
    #[arg(long)]
    channel: Option<String>,
    /// Image size in pixels.
    #[arg(long, default_value_t = 256)]
    size: usize,
    /// Evaluate at these wavelengths in nm (comma separated) instead of RGB.
    #[arg(long)]
    wavelengths: Option<String>,
}

/// Renders a slice image.
pub fn slice(a: SliceArgs) -> Result<()> {
    if a.size == 0 || a.size > 8192 {
        return Err(Error::arg("--size", "must be 1..=8192"));
    }
    let channels = source::channels(a.wavelengths.as_deref())?;
    let brdf = source::open(&a.source, &channels)?;
    let names = brdf.channels().names();
    let channel = match &a.channel {
        None => None,
        Some(c) => Some(
            names
                .iter()
                .position(|n| n.eq_ignore_ascii_case(c))
                .or_else(|| c.parse::<usize>().ok().filter(|&i| i < names.len()))
                .ok_or_else(|| {
                    Error::arg("--channel", format!("`{c}` is none of {}", names.join(" ")))
                })?,
        ),
    };
    let img = match a.kind {
        SliceKind::Halfdiff => slice::halfdiff(&*brdf, a.size, a.phi_d.to_radians()),
        SliceKind::Polar => slice::polar(
            &*brdf,
            a.size,
            slice::incident(a.theta_in.to_radians(), a.phi_in.to_radians()),
        ),
    };
    let what = match a.kind {
        SliceKind::Halfdiff => format!(
            "f_r, x = θh 0..90°, y = θd 0..90° (top to bottom), φd = {}°",
            a.phi_d
        ),
        SliceKind::Polar => format!(
            "f_r·cos θo over the outgoing hemisphere (radius ∝ θo, +x right, +y up), θi = {}°, φi = {}°",
            a.theta_in, a.phi_in
        ),
    };
    let legend = slice::write(&img, channel, &a.output)?;
    println!("{}: {what}; {legend}", a.output);
    Ok(())
}

/// Grid and accuracy options shared by `convert` and `db add`.
#[derive(Args, Clone)]
pub struct TabulateArgs {
    /// Grid size preset for the table: small, medium or large (default: the native MERL grid
    /// for MERL files, medium otherwise).
    #[arg(long)]
    preset: Option<String>,
    /// Full grid sizes θ1xφ1xθ2xφ2 (e.g. 90x360x90x360), or `merl`; overrides --preset.
    #[arg(long)]
    grid: Option<String>,
    /// Parameterization: halfdiff (default) or inout.
    #[arg(long)]
    param: Option<String>,
    /// Symmetry reduction: auto (detect), none, or a list of isotropic,reciprocal,bilateral.
    #[arg(long, default_value = "auto")]
    symmetry: String,
    /// Bake even if the source breaks the symmetry.
    #[arg(long)]
    force: bool,
    /// Interpolation for the reported accuracy: nearest or linear.
    #[arg(long, default_value = "linear")]
    interp: String,
    /// Random pairs for the reported accuracy (0 = skip).
    #[arg(long, default_value_t = 200_000)]
    pairs: usize,
    /// Store codec: f32, f16 or log16 (database outputs). Measured f_r can exceed the f16
    /// range at grazing angles (RGL stores f_r·cos θo), hence log16 (relative error bound).
    #[arg(long, default_value = "log16")]
    codec: String,
    /// Codec tolerance (log16).
    #[arg(long)]
    tolerance: Option<f64>,
    /// Replace an existing table of that name (database outputs).
    #[arg(long)]
    replace: bool,
}

/// Arguments of `brdftab convert`.
#[derive(Args)]
pub struct ConvertArgs {
    /// Any SOURCE: a MERL `.binary`, an RGL `.bsdf`, a spec, a table.
    input: String,
    /// The output: an RGL `.bsdf` (loads in Mitsuba 3 and pbrt-v4), a MERL `.binary` (the
    /// source resampled at the MERL cell centres), a table
    /// database entry `DB#NAME` (or a `.btdb` file, named after the input), or a raw table file.
    output: String,
    /// Evaluate spec sources at these wavelengths (nm); MERL output uses the RGB wavelengths.
    #[arg(long)]
    wavelengths: Option<String>,
    #[command(flatten)]
    tab: TabulateArgs,
    #[command(flatten)]
    rgl: RglArgs,
}

/// Options of `.bsdf` outputs (defaults: the library's; a `.bsdf` input keeps its own layout
/// unless --theta-i, --phi-i or --ndf-resolution is given).
#[derive(Args, Clone)]
pub struct RglArgs {
    /// .bsdf output: reflectance table resolution N (default 64, a .bsdf input's own).
    #[arg(long)]
    resolution: Option<usize>,
    /// .bsdf output: number of incident elevations θi (default 16; 8 = the RGL database's spacing).
    #[arg(long)]
    theta_i: Option<usize>,
    /// .bsdf output: number of incident azimuths φi (default 1 if isotropic, else 17).
    #[arg(long)]
    phi_i: Option<usize>,
    /// .bsdf output: NDF, σ and VNDF grid resolution (default 128).
    #[arg(long)]
    ndf_resolution: Option<usize>,
}

/// Converts between formats.
pub fn convert(a: ConvertArgs) -> Result<()> {
    let channels = source::channels(a.wavelengths.as_deref())?;
    match source::kind(&a.output) {
        Kind::Merl => {
            let brdf = source::open(&a.input, &channels)?;
            let t = std::time::Instant::now();
            let m = MerlBrdf::from_brdf(&*brdf);
            m.write(&a.output)?;
            println!(
                "{}: {} resampled on the MERL grid (90 × 90 × 180 cell centres) in {:.2} s",
                a.output,
                brdf.describe(),
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
        Kind::Rgl => {
            use brdftab::measured::rgl_write;
            let brdf = source::open(&a.input, &channels)?;
            let opts = rgl_write::Options {
                resolution: a.rgl.resolution,
                theta_i: a.rgl.theta_i,
                phi_i: a.rgl.phi_i,
                ndf_resolution: a.rgl.ndf_resolution,
                ..Default::default()
            }
            .reuse_source_file(&a.input)?;
            let t = std::time::Instant::now();
            let w = rgl_write::write(&*brdf, &a.output, &opts, None)?;
            let f = &w.fields;
            println!(
                "{}: {} as an RGL tensor file ({} φi × {} θi, {}×{} table, {} bytes, {:.2} s)",
                a.output,
                brdf.describe(),
                f.phi_i.len(),
                f.theta_i.len(),
                f.n,
                f.n,
                w.bytes,
                t.elapsed().as_secs_f64()
            );
            if a.tab.pairs > 0 {
                let back = RglBrdf::open(&a.output)?;
                let r = rgl_write::report(&back, &*brdf, a.tab.pairs, 1)?;
                println!(
                    "  error vs source (read back, {} pairs within 80°): relative RMSE of f_r weighted by cos θi cos θo {:.3e}, max relative {:.3e}",
                    r.pairs, r.rel_rmse, r.max_rel
                );
            }
            Ok(())
        }
        _ => tabulate_into(&a.input, &a.output, &channels, &a.tab),
    }
}

fn stem(path: &str) -> String {
    std::path::Path::new(path)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "table".into())
}

/// Tabulates `input` and writes it to `output` (`DB#NAME`, `.btdb`, or a raw table file);
/// reports the tabulated-vs-native accuracy.
fn tabulate_into(input: &str, output: &str, channels: &Channels, o: &TabulateArgs) -> Result<()> {
    use brdftab::table::presets::Preset;
    use brdftab::table::{BakeOptions, Grid, Interp, Mapping, Param, Symmetry, TabulatedBrdf};

    let interp = Interp::parse(&o.interp)?;
    let src = source::open(input, channels)?;
    let t0 = std::time::Instant::now();
    let native_merl = source::kind(input) == Kind::Merl && o.preset.is_none() && o.grid.is_none();
    let table = if native_merl {
        // Exact: the measurement's own cells on the MERL grid (nearest = the reader).
        MerlBrdf::open(input)?.to_table()
    } else {
        let sym = match o.symmetry.trim() {
            "auto" => brdftab::table::symmetry::detect(src.as_ref(), 1e-3),
            s => Symmetry::parse(s)?,
        };
        let param = o.param.as_deref().map(Param::parse).transpose()?;
        let ch = src.channels().clone();
        let grid = match o.grid.as_deref() {
            Some("merl") => Grid::merl(ch).with_symmetry(sym)?,
            Some(g) => {
                let sizes: Vec<usize> = g
                    .split(['x', 'X', '×'])
                    .map(|t| {
                        t.trim()
                            .parse()
                            .map_err(|_| Error::arg("--grid", format!("`{t}` is not a size")))
                    })
                    .collect::<Result<_>>()?;
                let sizes: [usize; 4] = sizes
                    .try_into()
                    .map_err(|_| Error::arg("--grid", "expected four sizes θ1xφ1xθ2xφ2"))?;
                let p = param.unwrap_or(Param::HalfDiff);
                let m = match p {
                    Param::HalfDiff => [Mapping::Sqrt, Mapping::Uniform],
                    Param::InOut => [Mapping::Uniform, Mapping::Uniform],
                };
                Grid::with_sizes(p, sizes, m, ch, sym)?
            }
            None => Preset::parse(o.preset.as_deref().unwrap_or("medium"))?.grid(param, sym, ch)?,
        };
        let opts = BakeOptions {
            force: o.force,
            ..Default::default()
        };
        brdftab::table::bake(src.as_ref(), &grid, &opts)?.0
    };
    let secs = t0.elapsed().as_secs_f64();
    let (path, name) = brdftab::store::db::split_source(output);
    let is_db = name.is_some() || path.to_ascii_lowercase().ends_with(".btdb");
    if is_db {
        let name = name.map(str::to_owned).unwrap_or_else(|| stem(input));
        let provenance = match source::kind(input) {
            Kind::Merl | Kind::Rgl => brdftab::store::Source::measured(input)?,
            Kind::Spec => brdftab::store::Source::model(&source::spec(input)?),
            Kind::Table => brdftab::store::Source::Other {
                description: src.describe(),
            },
        };
        let codec = brdftab::codec::Codec {
            quant: brdftab::codec::Quant::parse(&o.codec, o.tolerance, None)?,
            ..Default::default()
        };
        brdftab::store::tables::save(path, &name, provenance, &table, codec, o.replace)?;
        println!("{path}#{name}: {}", src.describe());
    } else {
        table.save_raw(path)?;
        println!("{path}: {}", src.describe());
    }
    println!(
        "  grid: {}{} ({} values, {:.2} s)",
        table.grid().summary(),
        if native_merl {
            ", the file's own cells"
        } else {
            ""
        },
        table.values().len(),
        secs
    );
    if o.pairs > 0 {
        let tab = TabulatedBrdf::from_table(table).with_interp(interp);
        let acc = brdftab::analysis::accuracy::compare(&tab, src.as_ref(), o.pairs, 1)?;
        println!(
            "  accuracy vs native ({:?}, {} pairs): cosine-weighted relative RMSE {:.3e}, max relative {:.3e}",
            interp, acc.pairs, acc.rel_rmse, acc.max_rel
        );
        let cap = brdftab::analysis::accuracy::compare_cap(
            &tab,
            src.as_ref(),
            o.pairs,
            1,
            80f64.to_radians(),
        )?;
        println!(
            "  within 80° of the normal (Ngan et al.'s cut; grazing f_r of measured data ∝ 1/cos θo): relative RMSE {:.3e}, max relative {:.3e}",
            cap.rel_rmse, cap.max_rel
        );
    }
    Ok(())
}
