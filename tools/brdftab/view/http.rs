//! The little HTTP/1.1 the viewer speaks: one request per connection, read with hard bounds.
//!
//! The parsing is `httparse` (hyper's parser); what is ours is the bounds around it. A request
//! head over [`MAX_HEAD`] bytes is refused (431) before it is parsed, a body over [`MAX_BODY`] is
//! refused (413) before it is read, chunked bodies are refused (the page never sends one), and
//! [`Deadline`] gives the whole request — head and body — [`READ_TIMEOUT`] in all, so a client
//! that trickles a byte at a time is cut off as surely as one that stalls; the response gets
//! [`WRITE_TIMEOUT`] in all the same way, so a client that reads a byte at a time cannot hold a
//! worker either.
//! Every response closes its connection, so no state outlives a request.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::time::{Duration, Instant};

/// The largest request head (request line + headers) read: URLs with an inline spec fit easily.
pub const MAX_HEAD: usize = 16 * 1024;
/// The largest request body read.
pub const MAX_BODY: usize = 64 * 1024;
/// How long a client may take to send its whole request (head and body).
pub const READ_TIMEOUT: Duration = Duration::from_secs(5);
/// How long writing a whole response may take.
pub const WRITE_TIMEOUT: Duration = Duration::from_secs(10);
/// The most headers a request may carry.
const MAX_HEADERS: usize = 48;

/// A parsed request.
#[derive(Debug, Clone)]
pub struct Request {
    /// `GET`, `HEAD`, ...
    pub method: String,
    /// The request target as sent (`/api/polar?m=0&theta_i=30`).
    pub target: String,
    /// The `Host` header, if exactly one was sent.
    pub host: Option<String>,
    /// The body (at most [`MAX_BODY`] bytes).
    pub body: Vec<u8>,
}

/// A response: status, content type, body.
#[derive(Debug, Clone)]
pub struct Response {
    /// The status code.
    pub status: u16,
    /// The `Content-Type`.
    pub content_type: &'static str,
    /// The body.
    pub body: Vec<u8>,
}

impl Response {
    /// A JSON body with status 200.
    pub fn json(body: String) -> Response {
        Response {
            status: 200,
            content_type: "application/json; charset=utf-8",
            body: body.into_bytes(),
        }
    }

    /// An error: `{"error": message}` with `status`.
    pub fn error(status: u16, message: &str) -> Response {
        let body = serde_json::json!({ "error": message }).to_string();
        Response {
            status,
            ..Response::json(body)
        }
    }
}

/// A connection read or written against one deadline for the whole request (or response): each
/// read or write may wait only for what is left of it, so the per-call socket timeout cannot be
/// renewed a byte at a time.
pub struct Deadline<'a> {
    stream: &'a TcpStream,
    until: Instant,
}

impl<'a> Deadline<'a> {
    /// Reads from or writes to `stream` for at most `total` from now.
    pub fn new(stream: &'a TcpStream, total: Duration) -> Deadline<'a> {
        Deadline {
            stream,
            until: Instant::now() + total,
        }
    }
}

impl Read for Deadline<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let left = self.until.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(std::io::ErrorKind::TimedOut.into());
        }
        self.stream.set_read_timeout(Some(left))?;
        let mut s = self.stream;
        s.read(buf)
    }
}

impl Write for Deadline<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let left = self.until.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(std::io::ErrorKind::TimedOut.into());
        }
        self.stream.set_write_timeout(Some(left))?;
        let mut s = self.stream;
        s.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        let mut s = self.stream;
        s.flush()
    }
}

/// Reads one request from `stream`, or the response refusing it.
pub fn read_request(stream: &mut impl Read) -> Result<Request, Response> {
    let mut buf = vec![0u8; MAX_HEAD];
    let mut len = 0;
    loop {
        if len == buf.len() {
            return Err(Response::error(431, "request head too large"));
        }
        let n = stream
            .read(&mut buf[len..])
            .map_err(|_| Response::error(408, "request not received in time"))?;
        if n == 0 {
            return Err(Response::error(400, "connection closed mid-request"));
        }
        len += n;
        let mut headers = [httparse::EMPTY_HEADER; MAX_HEADERS];
        let mut req = httparse::Request::new(&mut headers);
        match req.parse(&buf[..len]) {
            Ok(httparse::Status::Partial) => continue,
            Ok(httparse::Status::Complete(head)) => {
                let (request, body_len) = head_of(&req)?;
                return read_body(stream, request, &buf[head..len], body_len);
            }
            Err(httparse::Error::TooManyHeaders) => {
                return Err(Response::error(431, "too many headers"));
            }
            Err(e) => return Err(Response::error(400, &format!("bad request: {e}"))),
        }
    }
}

/// The request of a parsed head, and its body length.
fn head_of(req: &httparse::Request) -> Result<(Request, usize), Response> {
    let mut host = None;
    let mut hosts = 0;
    let (mut body_len, mut lengths) = (0usize, 0);
    for h in req.headers.iter() {
        let value = std::str::from_utf8(h.value)
            .map_err(|_| Response::error(400, "a header is not UTF-8"))?
            .trim();
        if h.name.eq_ignore_ascii_case("host") {
            hosts += 1;
            host = Some(value.to_owned());
        } else if h.name.eq_ignore_ascii_case("content-length") {
            let len = value
                .parse()
                .map_err(|_| Response::error(400, "bad Content-Length"))?;
            // Two that differ frame the body two ways (RFC 9112 §6.3: an error).
            if lengths > 0 && len != body_len {
                return Err(Response::error(400, "conflicting Content-Length headers"));
            }
            (body_len, lengths) = (len, lengths + 1);
        } else if h.name.eq_ignore_ascii_case("transfer-encoding") {
            return Err(Response::error(501, "chunked bodies are not accepted"));
        }
    }
    if body_len > MAX_BODY {
        return Err(Response::error(413, "request body too large"));
    }
    let request = Request {
        method: req.method.unwrap_or("").to_owned(),
        target: req.path.unwrap_or("").to_owned(),
        // Two Host headers are as good as none: the check refuses both.
        host: if hosts == 1 { host } else { None },
        body: Vec::new(),
    };
    Ok((request, body_len))
}

/// Reads the rest of a body of `body_len` bytes, `start` of which came with the head.
fn read_body(
    stream: &mut impl Read,
    mut request: Request,
    start: &[u8],
    body_len: usize,
) -> Result<Request, Response> {
    let mut body = start[..start.len().min(body_len)].to_vec();
    if body.len() < body_len {
        let mut rest = vec![0u8; body_len - body.len()];
        stream
            .read_exact(&mut rest)
            .map_err(|_| Response::error(408, "request body not received in time"))?;
        body.extend_from_slice(&rest);
    }
    request.body = body;
    Ok(request)
}

/// The reason phrase of the statuses the server sends.
fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        413 => "Content Too Large",
        421 => "Misdirected Request",
        431 => "Request Header Fields Too Large",
        501 => "Not Implemented",
        _ => "Internal Server Error",
    }
}

/// Writes `r` (with no body for `HEAD`) and the headers every response carries: no caching, no
/// sniffing, no framing, and a content security policy that allows nothing from elsewhere. A 405
/// says which methods are served (`Allow`, which RFC 9110 §15.5.6 requires of it).
pub fn write_response(
    stream: &mut impl Write,
    r: &Response,
    head_only: bool,
) -> std::io::Result<()> {
    let allow = if r.status == 405 {
        "Allow: GET, HEAD\r\n"
    } else {
        ""
    };
    let head = format!(
        "HTTP/1.1 {} {}\r\nContent-Type: {}\r\nContent-Length: {}\r\n{allow}Connection: close\r\n\
         Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\nX-Frame-Options: DENY\r\n\
         Referrer-Policy: no-referrer\r\nContent-Security-Policy: default-src 'self'; \
         img-src 'self' data: blob:; style-src 'self'; connect-src 'self'; frame-ancestors 'none'\r\n\r\n",
        r.status,
        reason(r.status),
        r.content_type,
        r.body.len()
    );
    stream.write_all(head.as_bytes())?;
    if !head_only {
        stream.write_all(&r.body)?;
    }
    stream.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(bytes: &[u8]) -> Result<Request, Response> {
        read_request(&mut std::io::Cursor::new(bytes.to_vec()))
    }

    #[test]
    fn a_request_with_a_body_is_read_whole() {
        let r = read(b"POST /x HTTP/1.1\r\nHost: a:1\r\nContent-Length: 3\r\n\r\nabc").unwrap();
        assert_eq!((r.method.as_str(), r.target.as_str()), ("POST", "/x"));
        assert_eq!(r.host.as_deref(), Some("a:1"));
        assert_eq!(r.body, b"abc");
    }

    #[test]
    fn oversized_heads_bodies_and_chunked_bodies_are_refused() {
        let long = format!("GET /{} HTTP/1.1\r\n\r\n", "a".repeat(MAX_HEAD));
        assert_eq!(read(long.as_bytes()).unwrap_err().status, 431);
        let big = format!(
            "POST / HTTP/1.1\r\nContent-Length: {}\r\n\r\n",
            MAX_BODY + 1
        );
        assert_eq!(read(big.as_bytes()).unwrap_err().status, 413);
        let chunked = b"POST / HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\n";
        assert_eq!(read(chunked).unwrap_err().status, 501);
        assert_eq!(read(b"GET / HTTP/1.1\r\n").unwrap_err().status, 400);
        let two = b"POST / HTTP/1.1\r\nContent-Length: 3\r\nContent-Length: 0\r\n\r\nabc";
        assert_eq!(read(two).unwrap_err().status, 400);
        let same = b"POST / HTTP/1.1\r\nContent-Length: 3\r\nContent-Length: 3\r\n\r\nabc";
        assert_eq!(read(same).unwrap().body, b"abc");
    }

    #[test]
    fn a_client_reading_a_trickle_cannot_hold_the_response_past_its_deadline() {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap();
        // The client reads 1 KiB every 10 ms, so every write makes a little progress and no
        // per-write timeout would ever fire.
        let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let stop = done.clone();
        let client = std::thread::spawn(move || {
            let mut c = TcpStream::connect(addr).unwrap();
            let mut buf = [0u8; 1024];
            while !stop.load(std::sync::atomic::Ordering::Relaxed)
                && matches!(c.read(&mut buf), Ok(n) if n > 0)
            {
                std::thread::sleep(Duration::from_millis(10));
            }
        });
        let (server, _) = listener.accept().unwrap();
        let body = vec![b'x'; 64 << 20];
        let t0 = Instant::now();
        let total = Duration::from_millis(300);
        let r = Deadline::new(&server, total).write_all(&body);
        let took = t0.elapsed();
        done.store(true, std::sync::atomic::Ordering::Relaxed);
        drop(server);
        client.join().unwrap();
        assert_eq!(r.unwrap_err().kind(), std::io::ErrorKind::TimedOut);
        // One write's wait is at most what is left of the deadline: the whole stays near it.
        assert!(took < total * 3, "{took:?}");
    }

    #[test]
    fn two_host_headers_count_as_none() {
        let r = read(b"GET / HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n").unwrap();
        assert_eq!(r.host, None);
    }
}
