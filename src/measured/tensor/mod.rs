//! The RGL-EPFL tensor file container (`.bsdf` files of Dupuy & Jakob 2018).
//!
//! A tensor file is a small directory of named n-dimensional arrays:
//!
//! ```text
//! 12 bytes  magic "tensor_file\0"
//! u8[2]     version = {1, 0}
//! u32       field count
//! per field: u16 name length, name bytes, u16 ndim, u8 dtype, u64 absolute data offset,
//!            u64 shape[ndim]
//! ```
//!
//! all little-endian; dtype 1..=11 = u8, i8, u16, i16, u32, i32, u64, i64, f16, f32, f64.
//!
//! The reader loads the file into memory once and keeps, per field, only a byte range into it, so
//! no size read from the file ever drives an allocation: every count, shape product and offset is
//! checked (with overflow-checked arithmetic) against the file length before it is used. Any
//! inconsistency is an [`Error::Format`] naming the file, the field and the byte offset.
//!
//! [`TensorWriter`] writes the same container; tests use it to build small or deliberately broken
//! files.
//!
//! [`Error::Format`]: crate::error::Error::Format

mod field;
mod read;
#[cfg(test)]
mod tests;
mod write;

pub use field::{Dtype, Field};
pub use read::TensorFile;
pub use write::{ALIGN, TensorWriter};

/// The 12-byte magic at the start of every tensor file.
pub const MAGIC: &[u8; 12] = b"tensor_file\0";

/// Whether the regular file at `path` starts with the tensor files' [`MAGIC`] (false for
/// anything unreadable).
pub fn has_magic(path: impl AsRef<std::path::Path>) -> bool {
    use std::io::Read;
    let mut m = [0u8; 12];
    crate::files::is_regular(path.as_ref())
        && std::fs::File::open(path)
            .and_then(|mut f| f.read_exact(&mut m))
            .is_ok()
        && &m == MAGIC
}
