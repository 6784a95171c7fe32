//! `brdftab view`: a BRDF explorer in the browser, served from the tool itself.
//!
//! The server lives here, on the application's side, so the core crate never links an HTTP
//! stack. It is deliberately small and synchronous: a `std` listener, a few worker threads that
//! each accept and answer one request per connection, `httparse` for the request head. The page
//! (plain JS drawing SVG, no framework, no build step) is embedded in the binary.
//!
//! - [`http`]: reading a request within bounds, writing a response;
//! - [`security`]: the `Host` check (DNS rebinding), plain paths, inline specs only;
//! - [`routes`]: the fixed table of routes; [`api`]: one handler per view;
//! - [`registry`]: the materials named at start, by index; [`eval`]: the numbers of each view.
//!
//! Security model: it binds 127.0.0.1 unless told otherwise; it answers only for the materials
//! opened at start and for inline analytic specs; a request can never make it open a file.

pub mod api;
pub mod eval;
pub mod http;
pub mod registry;
pub mod routes;
pub mod security;

use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;

use brdftab::{Error, Result};

pub use registry::Registry;

/// A bound viewer, ready to [`run`](Server::run).
pub struct Server {
    listener: TcpListener,
    addr: SocketAddr,
    registry: Arc<Registry>,
    hosts: Arc<Vec<String>>,
}

impl Server {
    /// Opens every SOURCE and binds `addr` (port 0 picks a free port).
    pub fn bind<S: AsRef<std::ffi::OsStr>>(sources: &[S], addr: SocketAddr) -> Result<Server> {
        let registry = Arc::new(Registry::open(sources)?);
        let listener = TcpListener::bind(addr).map_err(|e| Error::io(format!("bind {addr}"), e))?;
        let addr = listener
            .local_addr()
            .map_err(|e| Error::io("local address", e))?;
        Ok(Server {
            listener,
            addr,
            hosts: Arc::new(security::allowed_hosts(addr)),
            registry,
        })
    }

    /// The address it is bound to.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The page's URL.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// The materials it serves.
    pub fn registry(&self) -> &Registry {
        &self.registry
    }

    /// Serves forever on `workers` threads (at least 2).
    pub fn run(self, workers: usize) -> Result<()> {
        let mut threads = Vec::new();
        for _ in 0..workers.max(2) {
            let listener = self
                .listener
                .try_clone()
                .map_err(|e| Error::io("listener", e))?;
            let (reg, hosts) = (self.registry.clone(), self.hosts.clone());
            threads.push(std::thread::spawn(move || {
                for stream in listener.incoming().flatten() {
                    serve(&reg, &hosts, stream);
                }
            }));
        }
        for t in threads {
            let _ = t.join();
        }
        Ok(())
    }
}

/// Answers one connection: one request, one response, closed. A handler that panics answers
/// 500 and the worker lives on.
fn serve(reg: &Registry, hosts: &[String], stream: TcpStream) {
    let read = http::read_request(&mut http::Deadline::new(&stream, http::READ_TIMEOUT));
    let (response, head_only) = match read {
        Ok(req) => {
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                routes::handle(reg, hosts, &req)
            }))
            .unwrap_or_else(|_| http::Response::error(500, "internal error"));
            (r, req.method == "HEAD")
        }
        Err(r) => (r, false),
    };
    let mut out = http::Deadline::new(&stream, http::WRITE_TIMEOUT);
    let _ = http::write_response(&mut out, &response, head_only);
    let _ = stream.shutdown(std::net::Shutdown::Write);
}
