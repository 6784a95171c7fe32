//! `info`: what a table file or a measured file holds (the library's `store::info` and
//! `measured::info` say it; this prints).

use brdftab::Result;
use brdftab::store::info;
use clap::Args;

use crate::source;
use brdftab_tools::text::print_out;

/// Arguments of `brdftab info`.
#[derive(Args)]
pub struct InfoArgs {
    /// A brdftab file (`FILE.btdb`, or one table of it as `DB#NAME`), a raw table file, a MERL
    /// `.binary` or an RGL `.bsdf`.
    source: brdftab_tools::args::PathArg,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// `brdftab info`: measured, brdftab and raw files as text or JSON.
pub fn info(a: InfoArgs) -> Result<()> {
    use brdftab::measured::info as measured;
    use source::Kind::{Merl, Rgl};
    let (v, text): (_, fn(&serde_json::Value) -> String) = match source::kind(&a.source) {
        Merl | Rgl if !a.json => return print_out(&measured::describe(&a.source)?),
        Merl | Rgl => (measured::info(&a.source)?, |_| String::new()),
        _ => info::table_file_info(&a.source)?,
    };
    if a.json {
        let json = serde_json::to_string_pretty(&v).unwrap_or_default();
        print_out(&format!("{json}\n"))
    } else {
        print_out(&text(&v))
    }
}
