//! `eval` and `models`.

use std::io::{BufRead, Write};

use brdftab::spec::MODELS;
use brdftab::{Error, Result};
use clap::Args;
use glam::DVec3;

use crate::source;

/// Arguments of `brdftab eval`.
#[derive(Args)]
pub struct EvalArgs {
    /// A model spec (inline JSON starting with `{`, or a .json file), or a table file.
    source: String,
    /// Evaluate at these wavelengths in nm (comma separated) instead of RGB.
    #[arg(long)]
    wavelengths: Option<String>,
    /// Interpolation for table sources: nearest or linear.
    #[arg(long, default_value = "linear")]
    interp: String,
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
    let channels = source::channels(a.wavelengths.as_deref())?;
    let interp = brdftab::table::Interp::parse(&a.interp)?;
    let brdf = source::open_with(&a.source, &channels, interp)?;
    let c = brdf.channels().len();
    let mut f = vec![0.0f32; c];
    let stdin = std::io::stdin().lock();
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    for (i, line) in stdin.lines().enumerate() {
        let line = line.map_err(|e| Error::io("stdin", e))?;
        let Some(v) = parse_numbers::<6>(&line, i + 1)? else {
            continue;
        };
        brdf.eval(
            DVec3::new(v[0], v[1], v[2]),
            DVec3::new(v[3], v[4], v[5]),
            &mut f,
        );
        let s: Vec<String> = f.iter().map(|x| format!("{x:e}")).collect();
        writeln!(out, "{}", s.join(" ")).map_err(|e| Error::io("stdout", e))?;
    }
    out.flush().map_err(|e| Error::io("stdout", e))
}

/// Parses a line of exactly `N` numbers; `None` for blank and `#` lines.
pub fn parse_numbers<const N: usize>(line: &str, lineno: usize) -> Result<Option<[f64; N]>> {
    let t = line.trim();
    if t.is_empty() || t.starts_with('#') {
        return Ok(None);
    }
    let mut v = [0.0; N];
    let mut k = 0;
    for tok in t.split_whitespace() {
        if k == N {
            return Err(parse_err(lineno, format!("expected {N} numbers, got more")));
        }
        v[k] = tok
            .parse()
            .map_err(|_| parse_err(lineno, format!("`{tok}` is not a number")))?;
        k += 1;
    }
    if k < N {
        return Err(parse_err(lineno, format!("expected {N} numbers, got {k}")));
    }
    Ok(Some(v))
}

fn parse_err(line: usize, msg: String) -> Error {
    Error::Parse {
        source_name: "stdin".into(),
        line,
        msg,
    }
}

/// Lists every model.
pub fn models(a: ModelsArgs) -> Result<()> {
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(MODELS).unwrap_or_default()
        );
    } else {
        for m in MODELS {
            println!(
                "{:<17} {}\n{:<17} params: {}\n{:<17} e.g. {}",
                m.name,
                m.description,
                "",
                m.params_line(),
                "",
                m.example
            );
        }
    }
    Ok(())
}
