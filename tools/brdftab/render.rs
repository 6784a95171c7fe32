//! `render`: preview images of a SOURCE on a sphere, and comparisons of two sources.

use std::path::{Path, PathBuf};
use std::time::Instant;

use brdftab::{Error, Result};
use brdftab_tools::preview::{self, EnvChoice, Image, LightChoice, Mode, RenderOptions, Sampling};
use clap::Args;

use crate::bake::flag_named;
use brdftab_tools::outln;

/// Arguments of `brdftab render`.
#[derive(Args)]
pub struct RenderArgs {
    /// The material: a model spec (inline JSON or .json), a table, a MERL or RGL file.
    source: brdftab_tools::args::PathArg,
    /// Output image, .png (8-bit sRGB) or .exr (linear f32).
    #[arg(short, long)]
    output: PathBuf,
    /// Samples per pixel.
    #[arg(long, default_value_t = 64)]
    spp: usize,
    /// Image size, WxH.
    #[arg(long, default_value = "256x256")]
    size: String,
    /// Random seed (same seed → identical image).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// `path` (full path tracing) or `lit` (direct lighting only, fast).
    #[arg(long, default_value = "path")]
    mode: String,
    /// Maximum path length in bounces (path mode; default 8).
    #[arg(long)]
    max_depth: Option<usize>,
    /// Environment: `sky` (smooth procedural), `white` (constant 1, the furnace), `none`, or a
    /// lat-long FILE.exr as pbrt-v3 reads it (z up: row 0 = zenith, φ = 2πu from +x to +y).
    #[arg(long, default_value = "sky")]
    env: brdftab_tools::args::PathArg,
    /// Extra light: none, point or area (a small spherical light).
    #[arg(long, default_value = "none")]
    light: String,
    /// Put the sphere on a diffuse grey ground plane.
    #[arg(long)]
    ground: bool,
    /// Sampling: mis (light + BRDF sampling), brdf (no point light), light, or fixed (light +
    /// cosine sampling: material-independent directions). Default: mis, but fixed with --compare,
    /// so both sources see the same directions and the difference shows materials, not noise.
    #[arg(long)]
    sampling: Option<String>,
    /// Exposure in stops: the linear values × 2^EV, in the PNG's encoding and the EXR alike.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    exposure: f32,
    /// Render a second SOURCE with the same seed; write OUT as the side-by-side pair
    /// (SOURCE left, OTHER right), OUT-diff.png as the false-colour difference, and print the
    /// relative RMSE of SOURCE against OTHER.
    #[arg(long)]
    compare: Option<brdftab_tools::args::PathArg>,
    /// Seed for the --compare render (default: the same seed). Comparing a SOURCE with itself
    /// under another seed measures the noise floor.
    #[arg(long, requires = "compare")]
    compare_seed: Option<u64>,
    #[command(flatten)]
    open: brdftab::request::OpenSettings,
    /// Number of threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

fn parse_size(s: &str) -> Result<(usize, usize)> {
    let bad = || Error::arg("--size", format!("`{s}` is not WxH (e.g. 256x256)"));
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let w = w.trim().parse().map_err(|_| bad())?;
    let h = h.trim().parse().map_err(|_| bad())?;
    Ok((w, h))
}

fn options(a: &RenderArgs) -> Result<RenderOptions> {
    let (width, height) = parse_size(&a.size)?;
    let mode = Mode::parse(&a.mode)?;
    // The lit sphere is one bounce whatever the flag says.
    if mode == Mode::Lit && a.max_depth.is_some() {
        return Err(Error::arg(
            "--max-depth",
            "is for --mode path (lit is one bounce)",
        ));
    }
    // A NaN or infinite exposure wrote an all-black PNG.
    if !a.exposure.is_finite() {
        return Err(Error::arg(
            "--exposure",
            format!("{} is not a number of stops", a.exposure),
        ));
    }
    let env = EnvChoice::parse(&a.env).map_err(|e| flag_named(e, "--env"))?;
    let light = LightChoice::parse(&a.light)?;
    let default_sampling = if a.compare.is_some() { "fixed" } else { "mis" };
    let sampling = Sampling::parse(a.sampling.as_deref().unwrap_or(default_sampling))?;
    Ok(RenderOptions {
        width,
        height,
        spp: a.spp,
        seed: a.seed,
        max_depth: a.max_depth.unwrap_or(8),
        mode,
        sampling,
        env,
        light,
        ground: a.ground,
        exposure: a.exposure,
        threads: a.threads,
    })
}

/// Renders with a progress bar on a terminal, silently otherwise; reports the time on stderr.
fn render_one(brdf: &dyn brdftab::Brdf, opts: &RenderOptions, label: &str) -> Result<Image> {
    let start = Instant::now();
    let bar = brdftab_tools::progress::Bar::new("{msg} [{bar:40}] {percent}% eta {eta}");
    bar.prefix(label);
    let img = preview::render(brdf, opts, &bar)?;
    eprintln!(
        "{label}: {}×{} at {} spp in {:.2} s",
        opts.width,
        opts.height,
        opts.spp,
        start.elapsed().as_secs_f64()
    );
    Ok(img)
}

/// `OUT.png` → `OUT-diff.png` (always PNG: it is a false-colour picture).
fn diff_path(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "render".into());
    out.with_file_name(format!("{stem}-diff.png"))
}

/// Runs `brdftab render`.
pub fn run(a: RenderArgs) -> Result<()> {
    // An output the render could not be written to is refused before the render.
    brdftab_tools::output::check(&a.output, "--output", &["png", "exr"])?;
    let opts = options(&a)?;
    let brdf = brdftab::request::open(&a.source, &a.open)?;
    let img = render_one(brdf.as_ref(), &opts, &a.source.to_string())?;
    let Some(other) = &a.compare else {
        return preview::write_auto(&img, &a.output, opts.exposure);
    };
    let brdf_b = brdftab::request::open(other, &a.open)?;
    let opts_b = RenderOptions {
        seed: a.compare_seed.unwrap_or(opts.seed),
        ..opts.clone()
    };
    let img_b = render_one(brdf_b.as_ref(), &opts_b, &other.to_string())?;
    let r = preview::compare(&img, &img_b)?;
    let pair = Image::hstack(&[&img, &img_b], 4, 0.0)?;
    preview::write_auto(&pair, &a.output, opts.exposure)?;
    let (diff, legend) = preview::difference_image(&img, &img_b)?;
    let dp = diff_path(&a.output);
    preview::write_png(&diff, &dp, 0.0)?;
    outln!(
        "relative RMSE: {:.6} ({:.4}%)",
        r.rel_rmse,
        100.0 * r.rel_rmse
    )?;
    outln!("RMSE: {:.6e}  max |a-b|: {:.6e}", r.rmse, r.max_abs)?;
    outln!(
        "mean {}: {:.6}  mean {}: {:.6}",
        a.source,
        r.mean_a,
        other,
        r.mean_b
    )?;
    outln!(
        "side by side: {} ({} left, {} right)",
        a.output.display(),
        a.source,
        other
    )?;
    outln!("difference: {} — {legend}", dp.display())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("256x128").unwrap(), (256, 128));
        assert!(parse_size("256").is_err());
        assert!(parse_size("axb").is_err());
    }

    #[test]
    fn diff_path_is_beside_the_output() {
        assert_eq!(
            diff_path(Path::new("out/a.exr")),
            PathBuf::from("out/a-diff.png")
        );
    }
}
