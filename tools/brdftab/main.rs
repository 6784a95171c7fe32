//! `brdftab`: the command-line tool. Thin over the library: parse arguments, call the library,
//! print. Errors print as `error: ...` on stderr with exit code 1.

mod accuracy;
mod analysis;
mod bake;
mod bench;
mod convert;
mod db;
mod demo;
mod demo_extra;
mod export;
mod fit;
mod models;
mod render;
mod sample;
mod slice;
mod source;
mod table;

// `view/` beside it is the library's server module (`brdftab_tools::view`).
#[path = "view.rs"]
mod view;

use brdftab_tools::args::{as_typed, clap_exit, subcommand_path};
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use std::process::ExitCode;

/// Tabulated BRDFs: analytic models, dense compressed tables, measured data.
#[derive(Parser)]
#[command(name = "brdftab", version, long_about = None)]
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
    /// Bake SOURCE into a dense (symmetry-reduced) table file.
    Bake(bake::BakeArgs),
    /// Databases of named tables: add, list, rm, rename, verify.
    Db(db::DbArgs),
    /// Export a stored table as .npy, or a 2D slice of it as EXR.
    Export(export::ExportArgs),
    /// Write a .npy array of values (an export edited in numpy) as a table on another's grid.
    Import(export::ImportArgs),
    /// Describe a table file (grid, symmetry, channels, sizes) or a measured file (MERL, RGL).
    Info(table::InfoArgs),
    /// Time lookups of SOURCE on random pairs (single thread and batch on all cores).
    Bench(bench::BenchArgs),
    /// Render SOURCE on a sphere (path tracer or lit sphere); --compare renders two side by side.
    Render(render::RenderArgs),
    /// Render a slice image (MERL-style θh × θd, or polar f_r·cos θo) to EXR or PNG.
    Slice(slice::SliceArgs),
    /// Convert between formats (MERL .binary, RGL .bsdf, tables).
    Convert(convert::ConvertArgs),
    /// Directional albedo a(θ′) per channel (light at azimuth `--phi`, default 0): one line `theta a_1 a_2 ...` per angle.
    Albedo(analysis::AlbedoArgs),
    /// Physical plausibility: positivity, reciprocity, energy conservation.
    Check(analysis::CheckArgs),
    /// The tour: the lecture's models' plausibility, tables baked and measured against their
    /// sources, preview renders and a rate–distortion sweep.
    Demo(demo::DemoArgs),
    /// Accuracy suite: tables of every source per grid and codec vs the source; CSV, Markdown, plots.
    Accuracy(accuracy::AccuracyArgs),
    /// Fit a model's parameters to SOURCE by least squares; prints the fitted spec.
    Fit(fit::FitArgs),
    /// Draw incident directions from SOURCE's sampler: `wix wiy wiz pdf w_1 .. w_c` per line.
    Sample(sample::SampleArgs),
    /// Print pdf(wi | wo) for `wix wiy wiz wox woy woz` lines read from stdin.
    Pdf(sample::PdfArgs),
    /// Explore materials in the browser: serves a local web app and prints its URL.
    View(view::ViewArgs),
}

/// The command line's grammar: the derived one, with every value free to be a negative number
/// (`--theta-in -10` is a value for the library's range check to answer, not an unknown
/// flag `-1`), including the flags the library's settings structs derive.
fn command() -> clap::Command {
    fn negatives(c: clap::Command) -> clap::Command {
        let c = c.mut_args(|a| match a.get_action().takes_values() {
            true => a.allow_negative_numbers(true),
            false => a,
        });
        c.mut_subcommands(negatives)
    }
    negatives(Cli::command())
}

fn main() -> ExitCode {
    let mut matches = match command().try_get_matches() {
        Ok(m) => m,
        Err(e) => return clap_exit(e),
    };
    let path = subcommand_path(&matches);
    let cli = match Cli::from_arg_matches_mut(&mut matches) {
        Ok(cli) => cli,
        Err(e) => return clap_exit(e.format(&mut command())),
    };
    let result = match cli.command {
        Command::Eval(a) => models::eval(a),
        Command::Models(a) => models::models(a),
        Command::Bake(a) => bake::bake(a),
        Command::Info(a) => table::info(a),
        Command::Db(a) => db::run(a),
        Command::Export(a) => export::run(a),
        Command::Import(a) => export::import(a),
        Command::Bench(a) => bench::bench(a),
        Command::Render(a) => render::run(a),
        Command::Slice(a) => slice::slice(a),
        Command::Convert(a) => convert::convert(a),
        Command::Albedo(a) => analysis::albedo(a),
        Command::Check(a) => analysis::check(a),
        Command::Demo(a) => demo::demo(a),
        Command::Accuracy(a) => accuracy::accuracy(a),
        Command::Fit(a) => fit::fit(a),
        Command::Sample(a) => sample::sample(a),
        Command::Pdf(a) => sample::pdf(a),
        Command::View(a) => view::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader went away (`brdftab ... | head`): stop quietly.
        Err(brdftab::Error::Io { source, .. })
            if source.kind() == std::io::ErrorKind::BrokenPipe =>
        {
            ExitCode::SUCCESS
        }
        Err(e) => {
            let e = as_typed(e, &command(), &path);
            eprintln!("error: {e}{}", hint(&e, &path));
            ExitCode::from(1)
        }
    }
}

/// The flags that get past an error: the library's messages name none, the CLI adds them here.
fn hint(e: &brdftab::Error, path: &[String]) -> &'static str {
    match e {
        brdftab::Error::Duplicate { .. } if path != ["db", "rename"] => " (use --replace)",
        brdftab::Error::Symmetry { .. } => " (use --force to bake anyway, or --symmetry none)",
        _ => "",
    }
}
