//! `view`: the BRDF explorer in the browser (the server is `brdftab_tools::view`).

use std::io::Write;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};

use brdftab::{Error, Result};
use brdftab_tools::view::Server;
use clap::Args;

/// Connections served at once. A worker waits on its client for up to `http::READ_TIMEOUT`, and
/// a browser keeps idle preconnected sockets open, so there are more workers than cores (a
/// view's evaluation is parallel within its request anyway).
const WORKERS: usize = 16;

/// Arguments of `brdftab view`.
#[derive(Args)]
pub struct ViewArgs {
    /// Materials: model specs, table files, databases (every table), DB#NAME, MERL or RGL files.
    #[arg(required = true)]
    sources: Vec<brdftab_tools::args::PathArg>,
    /// The port (0: any free port; the URL printed says which).
    #[arg(long, default_value_t = 8127)]
    port: u16,
    /// The address to bind (not 0.0.0.0: requests must name it as their Host). Anything but
    /// loopback exposes the materials to the network.
    #[arg(long, default_value_t = IpAddr::V4(Ipv4Addr::LOCALHOST))]
    bind: IpAddr,
}

/// Opens the materials, binds, prints the URL on stdout and serves until killed.
pub fn run(a: ViewArgs) -> Result<()> {
    if a.bind.is_unspecified() {
        // The Host check answers only to the bound address: name the one clients will use.
        return Err(Error::arg(
            "--bind",
            format!(
                "{} is not an address clients can name; give this machine's address",
                a.bind
            ),
        ));
    }
    if !a.bind.is_loopback() {
        eprintln!(
            "warning: --bind {} serves the materials beyond this machine",
            a.bind
        );
    }
    let server = Server::bind(&a.sources, SocketAddr::new(a.bind, a.port))?;
    let n = server.registry().materials.len();
    let mut out = std::io::stdout().lock();
    let plural = if n == 1 { "" } else { "s" };
    writeln!(
        out,
        "brdftab view: {n} material{plural} at {}",
        server.url()
    )
    .and_then(|()| out.flush())
    .map_err(|e| Error::io("stdout", e))?;
    drop(out);
    eprintln!("(Ctrl-C stops the server)");
    server.run(WORKERS)
}
