//! `slice`: a slice image of any SOURCE.

use brdftab::{Brdf, Error, Result};
use brdftab_tools::preview::slice;
use brdftab_tools::{errln, text::shortest};
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
    source: std::ffi::OsString,
    /// Output image: `.exr` (linear f32) or `.png` (log scale, viridis, colorbar).
    #[arg(short, long)]
    output: brdftab_tools::args::PathArg,
    /// Which slice.
    #[arg(long, value_enum, default_value = "halfdiff")]
    kind: SliceKind,
    /// Incident polar angle in degrees (polar slice; default 45).
    #[arg(long)]
    theta_in: Option<f64>,
    /// Incident azimuth in degrees (polar slice; default 0).
    #[arg(long)]
    phi_in: Option<f64>,
    /// Difference azimuth φd in degrees (halfdiff slice; default 90).
    #[arg(long)]
    phi_d: Option<f64>,
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

/// Refuses the angles of the other kind of slice, which this one would ignore.
fn refuse_other_kind(a: &SliceArgs) -> Result<()> {
    let (other, kind): (&[(&str, Option<f64>)], &str) = match a.kind {
        SliceKind::Halfdiff => (
            &[("--theta-in", a.theta_in), ("--phi-in", a.phi_in)],
            "polar",
        ),
        SliceKind::Polar => (&[("--phi-d", a.phi_d)], "halfdiff"),
    };
    match other.iter().find(|(_, x)| x.is_some()) {
        Some((flag, _)) => Err(Error::arg(
            *flag,
            format!("is for --kind {kind} slices only"),
        )),
        None => Ok(()),
    }
}

/// Renders a slice image.
pub fn slice(a: SliceArgs) -> Result<()> {
    if a.size == 0 || a.size > 8192 {
        return Err(Error::arg("--size", "must be 1..=8192"));
    }
    brdftab_tools::output::check(&a.output, "--output", &["exr", "png"])?;
    refuse_other_kind(&a)?;
    let (theta_in, phi_in) = (a.theta_in.unwrap_or(45.0), a.phi_in.unwrap_or(0.0));
    let phi_d = a.phi_d.unwrap_or(90.0);
    // An angle that is not a number drew an all-black image.
    for (flag, x) in [("--phi-in", phi_in), ("--phi-d", phi_d)] {
        if !x.is_finite() {
            return Err(Error::arg(flag, format!("{x} is not an angle")));
        }
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
    let img = match a.kind {
        SliceKind::Halfdiff => slice::halfdiff(&*brdf, a.size, phi_d.to_radians()),
        SliceKind::Polar => {
            let wi = slice::incident(theta_in.to_radians(), phi_in.to_radians()).map_err(|_| {
                Error::arg(
                    "--theta-in",
                    format!(
                        "{}° is outside [0°, 90°): the light must be above the horizon",
                        shortest(theta_in)
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
            shortest(phi_d)
        ),
        SliceKind::Halfdiff => format!(
            "f_r, x = θh 0..90°, y = θd 0..90° (top to bottom), φd = {}°, φh = 0° (anisotropic: \
             the half vector in the x–z plane)",
            shortest(phi_d)
        ),
        SliceKind::Polar => format!(
            "f_r·cos θo over the outgoing hemisphere (radius ∝ θo, +x right, +y up), θi = {}°, φi = {}°",
            shortest(theta_in),
            shortest(phi_in)
        ),
    };
    let legend = slice::write(&img, channel, &a.output)?;
    errln!("{}: {what}; {legend}", a.output)?;
    Ok(())
}
