//! `brdftab`: the command-line tool. Thin over the library: parse arguments, call the library,
//! print. Errors print as `error: ...` on stderr with exit code 1.

mod fit;
mod measured;
mod models;
mod sample;
mod source;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Tabulated BRDFs: analytic models, dense compressed tables, measured data.
#[derive(Parser)]
#[command(name = "brdftab", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Evaluate f_r for direction pairs read from stdin (`wix wiy wiz wox woy woz` per line).
    Eval(models::EvalArgs),
    /// List every model with its parameters.
    Models(models::ModelsArgs),
    /// Fit a model's parameters to SOURCE by least squares; prints the fitted spec.
    Fit(fit::FitArgs),
    /// Draw incident directions from SOURCE's sampler: `wix wiy wiz pdf w_1 .. w_c` per line.
    Sample(sample::SampleArgs),
    /// Print pdf(wi | wo) for `wix wiy wiz wox woy woz` lines read from stdin.
    Pdf(sample::PdfArgs),
    /// Describe a measured file (MERL .binary, RGL .bsdf): description, dims, channels, sha256.
    Info(measured::InfoArgs),
    /// Render a slice image (MERL-style θh × θd, or polar f_r·cos θo) to EXR or PNG.
    Slice(measured::SliceArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Eval(a) => models::eval(a),
        Command::Models(a) => models::models(a),
        Command::Fit(a) => fit::fit(a),
        Command::Sample(a) => sample::sample(a),
        Command::Pdf(a) => sample::pdf(a),
        Command::Info(a) => measured::info(a),
        Command::Slice(a) => measured::slice(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
