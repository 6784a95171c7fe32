//! `eval` and `models`.

use std::io::Write;

use brdftab::spec::MODELS;
use brdftab::{Error, Result};
use brdftab_tools::outln;
use clap::Args;

/// Arguments of `brdftab eval`.
#[derive(Args)]
pub struct EvalArgs {
    /// Any SOURCE: a model spec (inline JSON starting with `{`, or a .json file), a table
    /// (`FILE.btdb`, `DB#NAME`), a MERL `.binary` or an RGL `.bsdf`.
    source: std::ffi::OsString,
    #[command(flatten)]
    open: brdftab::request::OpenSettings,
}

/// Arguments of `brdftab models`.
#[derive(Args)]
pub struct ModelsArgs {
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// Reads `wix wiy wiz wox woy woz` lines from stdin, prints f_r per channel.
pub fn eval(a: EvalArgs) -> Result<()> {
    let brdf = brdftab::request::open(&a.source, &a.open)?;
    let c = brdf.channels().len();
    let mut f = vec![0.0f32; c];
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    brdftab_tools::text::for_each_pair(std::io::stdin().lock(), "stdin", |wi, wo| {
        brdf.eval(wi, wo, &mut f);
        // A lazily read table whose chunk failed its checksum gave 0: stop with its error.
        brdf.health()?;
        let s: Vec<String> = f.iter().map(|x| format!("{x:e}")).collect();
        writeln!(out, "{}", s.join(" ")).map_err(|e| Error::io("stdout", e))
    })?;
    out.flush().map_err(|e| Error::io("stdout", e))
}

/// Lists every model.
pub fn models(a: ModelsArgs) -> Result<()> {
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(MODELS).unwrap_or_default()
        )?;
    } else {
        for m in MODELS {
            outln!(
                "{:<17} {}\n{:<17} params: {}\n{:<17} e.g. {}",
                m.name,
                m.description,
                "",
                m.params_line(),
                "",
                m.example
            )?;
        }
    }
    Ok(())
}
