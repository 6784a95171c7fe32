//! NumPy `.npy` files: the header the exports write ([`npy_header`]) and the reader that takes
//! arrays back in ([`NpyReader`]).
//!
//! Why a module: an `.npy` file is the one array format a table's values leave in (`brdftab
//! export --npy`, Python's `Table.values` saved with `numpy.save`) and come back in (`brdftab
//! import`), so its byte layout is written down once, here. The reader takes what `numpy.save`
//! writes for the arrays a table holds: format versions 1.0, 2.0 and 3.0, little-endian
//! float32 (`<f4`) or float64 (`<f8`, numpy's default, converted to float32), C order, any
//! order of the header's keys. Everything else is refused with the file, the field and the
//! byte offset: Fortran order, big-endian and other dtypes, negative or overflowing shapes,
//! truncated files. The file's size is checked against the shape before anything is allocated,
//! so no header can ask for more memory than the file holds.

use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result};

mod dict;
#[cfg(test)]
mod tests;

use dict::Dict;

/// The first six bytes of every `.npy` file.
pub const MAGIC: &[u8; 6] = b"\x93NUMPY";

/// The longest header the reader accepts (numpy's own reader refuses more than 10 000 bytes
/// unless told otherwise; its writer pads to 64).
pub const MAX_HEADER_BYTES: usize = 1 << 16;

/// The most dimensions the reader accepts (numpy's limit is 64; a table's array has 5).
pub const MAX_DIMS: usize = 32;

/// The `.npy` v1.0 header for a little-endian f32 C-order array of `shape`.
pub fn npy_header(shape: &[u64]) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let shape = if dims.len() == 1 {
        format!("({},)", dims[0])
    } else {
        format!("({})", dims.join(", "))
    };
    let mut dict = format!("{{'descr': '<f4', 'fortran_order': False, 'shape': {shape}, }}");
    // magic(6) + version(2) + len(2) + dict + '\n' must be a multiple of 64.
    let unpadded = 10 + dict.len() + 1;
    dict.push_str(&" ".repeat(unpadded.next_multiple_of(64) - unpadded));
    dict.push('\n');
    let mut out = Vec::with_capacity(10 + dict.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(b"\x01\x00");
    out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out
}

/// The element types the reader takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dtype {
    /// Little-endian float32, `<f4`.
    F32,
    /// Little-endian float64, `<f8` (read as float32).
    F64,
}

impl Dtype {
    /// Bytes per element.
    pub fn size(self) -> usize {
        match self {
            Dtype::F32 => 4,
            Dtype::F64 => 8,
        }
    }

    /// The dtype as numpy's header names it: `<f4` or `<f8`.
    pub fn descr(self) -> &'static str {
        match self {
            Dtype::F32 => "<f4",
            Dtype::F64 => "<f8",
        }
    }
}

/// What an `.npy` header says.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NpyHeader {
    /// The format version (1, 0), (2, 0) or (3, 0).
    pub version: (u8, u8),
    /// The element type.
    pub dtype: Dtype,
    /// The array's shape (C order).
    pub shape: Vec<usize>,
    /// Where the data start, in bytes from the start of the file.
    pub data_offset: u64,
}

impl NpyHeader {
    /// Number of elements (the shape's product; checked against the file when read).
    pub fn elements(&self) -> usize {
        self.shape.iter().product()
    }
}

/// An `.npy` array whose header is read and checked against the file's size; [`read_f32`]
/// then reads the data.
///
/// [`read_f32`]: NpyReader::read_f32
#[derive(Debug)]
pub struct NpyReader<R> {
    file: String,
    reader: R,
    header: NpyHeader,
}

impl NpyReader<std::io::BufReader<std::fs::File>> {
    /// Opens the `.npy` file at `path` and reads its header.
    ///
    /// # Errors
    /// [`Error::NotFound`] when the file is missing, [`Error::Io`] when it cannot be read,
    /// [`Error::Format`] (file, field, byte offset)
    /// for what [`NpyReader::new`] refuses.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        crate::files::require_regular(path)?;
        let f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        let len = f.metadata().map_err(|e| Error::io(path, e))?.len();
        NpyReader::new(
            path.display().to_string(),
            std::io::BufReader::with_capacity(1 << 16, f),
            len,
        )
    }
}

impl<R: Read> NpyReader<R> {
    /// Reads the header of the `.npy` array `reader` holds, `len` bytes in all (`file` names
    /// it in errors), and checks that exactly the shape's data follow it.
    ///
    /// # Errors
    /// [`Error::Format`] naming the field and byte offset: no `.npy` magic, a version other
    /// than 1.0, 2.0 or 3.0, a header that is not a dict of `descr`, `fortran_order` and
    /// `shape` or longer than [`MAX_HEADER_BYTES`], a dtype other than `<f4` and `<f8`,
    /// Fortran order, a negative or overflowing shape, or data shorter or longer than the
    /// shape says.
    pub fn new(file: impl Into<String>, mut reader: R, len: u64) -> Result<Self> {
        let file = file.into();
        let mut prefix = [0u8; 12];
        let head = 10.min(len) as usize;
        read_exact(&mut reader, &mut prefix[..head], &file, 0)?;
        if head < 8 || &prefix[..6] != MAGIC {
            if head >= 6 && &prefix[..6] == MAGIC {
                return Err(truncated(&file, "version", head as u64, 8));
            }
            return Err(Error::format(
                &file,
                Some("magic"),
                Some(0),
                "not a .npy file (it does not start with \\x93NUMPY)",
            ));
        }
        let version = (prefix[6], prefix[7]);
        let len_bytes = match version {
            (1, 0) => 2,
            (2, 0) | (3, 0) => 4,
            (a, b) => {
                return Err(Error::format(
                    &file,
                    Some("version"),
                    Some(6),
                    format!("format version {a}.{b}: this reader knows 1.0, 2.0 and 3.0"),
                ));
            }
        };
        let start = 8 + len_bytes;
        if len < start as u64 {
            return Err(truncated(&file, "header length", len, start as u64));
        }
        read_exact(&mut reader, &mut prefix[head..start], &file, head as u64)?;
        let header_len = match len_bytes {
            2 => u16::from_le_bytes([prefix[8], prefix[9]]) as u64,
            _ => u32::from_le_bytes([prefix[8], prefix[9], prefix[10], prefix[11]]) as u64,
        };
        if header_len > MAX_HEADER_BYTES as u64 {
            return Err(Error::format(
                &file,
                Some("header length"),
                Some(8),
                format!("a header of {header_len} bytes (at most {MAX_HEADER_BYTES})"),
            ));
        }
        let data_offset = start as u64 + header_len;
        if len < data_offset {
            return Err(truncated(&file, "header", len, data_offset));
        }
        let mut text = vec![0u8; header_len as usize];
        read_exact(&mut reader, &mut text, &file, start as u64)?;
        if version.0 == 3 && std::str::from_utf8(&text).is_err() {
            return Err(Error::format(
                &file,
                Some("header"),
                Some(start as u64),
                "a version 3.0 header that is not UTF-8",
            ));
        }
        let dict = Dict::parse(&text, &file, start as u64)?;
        let header = NpyHeader {
            version,
            dtype: dict.dtype,
            shape: dict.shape,
            data_offset,
        };
        let bytes = header
            .shape
            .iter()
            .try_fold(header.dtype.size() as u64, |n, &d| n.checked_mul(d as u64))
            .filter(|&n| usize::try_from(n).is_ok())
            .ok_or_else(|| {
                Error::format(
                    &file,
                    Some("shape"),
                    Some(dict.shape_offset),
                    format!(
                        "an array of shape {:?} does not fit in memory (its size overflows)",
                        header.shape
                    ),
                )
            })?;
        let held = len - data_offset;
        if held < bytes {
            return Err(Error::format(
                &file,
                Some("data"),
                Some(len),
                format!(
                    "truncated: an array of shape {:?} ({}) needs {bytes} bytes of data, the \
                     file holds {held}",
                    header.shape,
                    header.dtype.descr()
                ),
            ));
        }
        if held > bytes {
            return Err(Error::format(
                &file,
                Some("data"),
                Some(data_offset + bytes),
                format!(
                    "{} bytes after the data of an array of shape {:?} ({})",
                    held - bytes,
                    header.shape,
                    header.dtype.descr()
                ),
            ));
        }
        Ok(NpyReader {
            file,
            reader,
            header,
        })
    }

    /// The header.
    pub fn header(&self) -> &NpyHeader {
        &self.header
    }

    /// The array's values in C order as float32 (float64 values rounded to the nearest).
    ///
    /// # Errors
    /// [`Error::Format`] for a float64 value beyond float32's range (its byte offset), or data
    /// that end early (the file shrank since it was opened); [`Error::Io`] for a failed read.
    pub fn read_f32(mut self) -> Result<Vec<f32>> {
        let h = &self.header;
        let n = h.elements();
        let size = h.dtype.size();
        let mut out = Vec::with_capacity(n);
        let mut buf = vec![0u8; (1 << 16) / size * size];
        let mut offset = h.data_offset;
        while out.len() < n {
            let k = (n - out.len()).min(buf.len() / size);
            let block = &mut buf[..k * size];
            read_exact(&mut self.reader, block, &self.file, offset)?;
            match h.dtype {
                Dtype::F32 => out.extend(
                    block
                        .chunks_exact(4)
                        .map(|b| f32::from_le_bytes(b.try_into().expect("chunks of 4 bytes"))),
                ),
                Dtype::F64 => {
                    for (i, b) in block.chunks_exact(8).enumerate() {
                        let x = f64::from_le_bytes(b.try_into().expect("chunks of 8 bytes"));
                        let y = x as f32;
                        if x.is_finite() && !y.is_finite() {
                            return Err(Error::format(
                                &self.file,
                                Some("data"),
                                Some(offset + (i * 8) as u64),
                                format!("{x:e} (element {}) is beyond float32's range", out.len()),
                            ));
                        }
                        out.push(y);
                    }
                }
            }
            offset += (k * size) as u64;
        }
        Ok(out)
    }
}

/// The shape and the float32 values of the `.npy` file at `path` ([`NpyReader`]).
///
/// # Errors
/// As [`NpyReader::open`] and [`NpyReader::read_f32`].
pub fn read_f32(path: impl AsRef<Path>) -> Result<(Vec<usize>, Vec<f32>)> {
    let r = NpyReader::open(path)?;
    let shape = r.header().shape.clone();
    Ok((shape, r.read_f32()?))
}

fn read_exact(r: &mut impl Read, buf: &mut [u8], file: &str, offset: u64) -> Result<()> {
    r.read_exact(buf).map_err(|e| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => Error::format(
            file,
            None,
            Some(offset),
            "the file ends early (it changed while it was read?)",
        ),
        _ => Error::io(file, e),
    })
}

fn truncated(file: &str, field: &str, len: u64, need: u64) -> Error {
    Error::format(
        file,
        Some(field),
        Some(len),
        format!("truncated: the file ends at byte {len}, its {field} needs {need} bytes"),
    )
}
