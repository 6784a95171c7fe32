//! zstd frames: one call's compression or decompression, with a context kept per thread for
//! small calls and zstd's worker threads for large chunks.

use crate::error::{Error, Result};

/// Chunks above this many raw bytes are compressed with zstd's worker threads.
const MT_THRESHOLD: usize = 8 << 20;

/// zstd calls on up to this many bytes, at levels up to [`REUSE_MAX_LEVEL`], use a context kept
/// per thread: creating and sizing a context costs about a tenth of compressing a 50 kB chunk,
/// and the encoder makes three calls per chunk. Larger or slower calls take a fresh context, so
/// that no thread keeps a large one.
const REUSE_MAX: usize = 1 << 20;
/// See [`REUSE_MAX`].
const REUSE_MAX_LEVEL: i32 = 9;

thread_local! {
    static CCTX: std::cell::RefCell<Option<zstd::bulk::Compressor<'static>>> =
        const { std::cell::RefCell::new(None) };
    static DCTX: std::cell::RefCell<Option<zstd::bulk::Decompressor<'static>>> =
        const { std::cell::RefCell::new(None) };
}

/// One zstd frame of `bytes` at `level` (single-threaded; see [`REUSE_MAX`]).
pub(crate) fn zstd_compress(bytes: &[u8], level: i32) -> std::io::Result<Vec<u8>> {
    if bytes.len() > REUSE_MAX || level > REUSE_MAX_LEVEL {
        return zstd::bulk::compress(bytes, level);
    }
    CCTX.with(|c| {
        let mut c = c.borrow_mut();
        let z = match &mut *c {
            Some(z) => z,
            None => c.insert(zstd::bulk::Compressor::new(level)?),
        };
        z.set_compression_level(level)?;
        z.compress(bytes)
    })
}

/// Decompresses one zstd frame of at most `capacity` bytes (see [`REUSE_MAX`]).
pub(super) fn zstd_decompress(frame: &[u8], capacity: usize) -> std::io::Result<Vec<u8>> {
    DCTX.with(|d| {
        let mut d = d.borrow_mut();
        let z = match &mut *d {
            Some(z) => z,
            None => d.insert(zstd::bulk::Decompressor::new()?),
        };
        z.decompress(frame, capacity)
    })
}

pub(super) fn compress(bytes: &[u8], level: i32) -> Result<Vec<u8>> {
    let enc_err = |e: std::io::Error| Error::Encode {
        msg: format!("zstd: {e}"),
    };
    if bytes.len() < MT_THRESHOLD {
        return zstd_compress(bytes, level).map_err(enc_err);
    }
    let mut out = Vec::with_capacity(bytes.len() / 4);
    let mut enc = zstd::stream::Encoder::new(&mut out, level).map_err(enc_err)?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get()) as u32;
    enc.multithread(threads).map_err(enc_err)?;
    enc.include_contentsize(true).map_err(enc_err)?;
    enc.set_pledged_src_size(Some(bytes.len() as u64))
        .map_err(enc_err)?;
    std::io::Write::write_all(&mut enc, bytes).map_err(enc_err)?;
    enc.finish().map_err(enc_err)?;
    Ok(out)
}
