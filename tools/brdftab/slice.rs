//! `slice`: a slice image of any SOURCE.

use brdftab::{Brdf, Error, Result};
use brdftab_tools::outln;
use brdftab_tools::preview::slice;
use clap::{Args, ValueEnum};

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
    #[command(flatten)]
    open: brdftab::request::OpenSettings,
}

/// Renders a slice image.
pub fn slice(a: SliceArgs) -> Result<()> {
    if a.size == 0 || a.size > 8192 {
        return Err(Error::arg("--size", "must be 1..=8192"));
    }
    let brdf = brdftab::request::open(&a.source, &a.open)?;
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
    // An angle that is not a number drew an all-black image.
    for (flag, x) in [("--phi-in", a.phi_in), ("--phi-d", a.phi_d)] {
        if !x.is_finite() {
            return Err(Error::arg(flag, format!("{x} is not an angle")));
        }
    }
    let img = match a.kind {
        SliceKind::Halfdiff => slice::halfdiff(&*brdf, a.size, a.phi_d.to_radians()),
        SliceKind::Polar => {
            let wi =
                slice::incident(a.theta_in.to_radians(), a.phi_in.to_radians()).map_err(|_| {
                    Error::arg(
                        "--theta-in",
                        format!(
                            "{}° is outside [0°, 90°): the light must be above the horizon",
                            a.theta_in
                        ),
                    )
                })?;
            slice::polar(&*brdf, a.size, wi)
        }
    };
    // A source that failed while it was read (a corrupt table chunk) drew zeros.
    brdf.health()?;
    let what = match a.kind {
        // An isotropic BRDF is the same at every φh; an anisotropic one shows its φh = 0 slice.
        SliceKind::Halfdiff if brdf.flags().isotropic => format!(
            "f_r, x = θh 0..90°, y = θd 0..90° (top to bottom), φd = {}°",
            a.phi_d
        ),
        SliceKind::Halfdiff => format!(
            "f_r, x = θh 0..90°, y = θd 0..90° (top to bottom), φd = {}°, φh = 0° (anisotropic: \
             the half vector in the x–z plane)",
            a.phi_d
        ),
        SliceKind::Polar => format!(
            "f_r·cos θo over the outgoing hemisphere (radius ∝ θo, +x right, +y up), θi = {}°, φi = {}°",
            a.theta_in, a.phi_in
        ),
    };
    let legend = slice::write(&img, channel, &a.output)?;
    outln!("{}: {what}; {legend}", a.output)?;
    Ok(())
}
