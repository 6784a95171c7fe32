//! `albedo` and `check`: directional albedo and the plausibility report of a SOURCE.

use brdftab::analysis::{albedo, plausibility};
use brdftab::{Error, Result};
use brdftab_tools::text::{print_out, shortest};
use clap::Args;

/// Arguments of `brdftab albedo`.
#[derive(Args)]
pub struct AlbedoArgs {
    /// Any SOURCE: a model spec (inline JSON starting with `{`, or a .json file), a table
    /// (`FILE.btdb`, `DB#NAME`), a MERL `.binary` or an RGL `.bsdf`.
    source: std::ffi::OsString,
    /// Incidence angles θ′ in degrees, comma separated.
    #[arg(
        long,
        default_value = "0,15,30,45,60,75,85,89",
        value_name = "DEG[,DEG..]",
        allow_hyphen_values = true
    )]
    theta: String,
    /// Azimuth φ′ of the light in degrees from the local x axis, along which an anisotropic
    /// model's α_x runs (the albedo of an anisotropic source depends on it).
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "DEG",
        allow_hyphen_values = true
    )]
    phi: f64,
    #[command(flatten)]
    open: brdftab::request::OpenSettings,
}

/// Arguments of `brdftab check`.
#[derive(Args)]
pub struct CheckArgs {
    /// Any SOURCE: a model spec (inline JSON starting with `{`, or a .json file), a table
    /// (`FILE.btdb`, `DB#NAME`), a MERL `.binary` or an RGL `.bsdf`.
    source: std::ffi::OsString,
    /// Print the report as one JSON object.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    open: brdftab::request::OpenSettings,
}

/// Prints `theta a_1 a_2 ...` per requested angle.
pub fn albedo(a: AlbedoArgs) -> Result<()> {
    let thetas = parse_degrees(&a.theta)?;
    let brdf = brdftab::request::open(&a.source, &a.open)?;
    let radians: Vec<f64> = thetas.iter().map(|t| t.to_radians()).collect();
    // The library's rule, [0, π/2) in radians; `parse_degrees` has said it in degrees already,
    // unless a degree just below 90 rounded to π/2.
    let curve =
        albedo::albedo_curve_at(&*brdf, &radians, a.phi.to_radians()).map_err(|e| match e {
            Error::InvalidArgument { name, msg } if name == "phi" => Error::arg("--phi", msg),
            Error::InvalidArgument { msg, .. } => Error::arg("--theta", msg),
            e => e,
        })?;
    brdf.health()?;
    let mut text = String::new();
    for (t, row) in thetas.iter().zip(curve) {
        let vals: Vec<String> = row.iter().map(|&x| sig7(x)).collect();
        text += &format!("{} {}\n", shortest(*t), vals.join(" "));
    }
    print_out(&text)
}

/// Prints the plausibility report (text or JSON).
pub fn check(a: CheckArgs) -> Result<()> {
    let brdf = brdftab::request::open(&a.source, &a.open)?;
    let report = plausibility::check(&*brdf, &plausibility::Options::default())?;
    brdf.health()?;
    if a.json {
        let json = serde_json::to_string(&report)
            .map_err(|e| Error::Unsupported(format!("cannot serialize the report: {e}")))?;
        print_out(&format!("{json}\n"))
    } else {
        print_out(&report.to_string())
    }
}

/// Parses `0,30,60` as degrees in [0, 90): the albedo is defined for light above the horizon
/// ([`albedo::incidence`]).
fn parse_degrees(s: &str) -> Result<Vec<f64>> {
    s.split(',')
        .map(|x| {
            let t: f64 = x
                .trim()
                .parse()
                .map_err(|_| Error::arg("--theta", format!("`{x}` is not a number")))?;
            if !(0.0..90.0).contains(&t) {
                return Err(Error::arg(
                    "--theta",
                    format!(
                        "{}° is outside [0°, 90°): the albedo is defined for light above the horizon",
                        shortest(t)
                    ),
                ));
            }
            Ok(t)
        })
        .collect()
}

/// `x` rounded to 7 significant digits, printed in its shortest form.
pub fn sig7(x: f64) -> String {
    let rounded: f64 = format!("{x:.6e}").parse().unwrap_or(x);
    if rounded != 0.0 && rounded.abs() < 1e-4 {
        format!("{rounded:e}")
    } else {
        format!("{rounded}")
    }
}
