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

/// The header's dict, parsed from its Python literal: `{'descr': '<f4', 'fortran_order':
/// False, 'shape': (2, 3), }` with the keys in any order and the usual spaces, commas and
/// padding.
struct Dict {
    dtype: Dtype,
    shape: Vec<usize>,
    /// Where the shape's tuple starts in the file.
    shape_offset: u64,
}

/// A value of the header's dict.
enum Value {
    Str(String),
    Bool(bool),
    Tuple(Vec<u64>),
}

/// A cursor over the header's bytes; `base` is their offset in the file.
struct Parser<'a> {
    text: &'a [u8],
    at: usize,
    base: u64,
    file: &'a str,
}

impl Dict {
    fn parse(text: &[u8], file: &str, base: u64) -> Result<Dict> {
        let mut p = Parser {
            text,
            at: 0,
            base,
            file,
        };
        p.skip_space();
        p.expect(b'{', "a dict `{...}`")?;
        let (mut descr, mut fortran, mut shape) = (None, None, None);
        loop {
            p.skip_space();
            if p.eat(b'}') {
                break;
            }
            let key_at = p.offset();
            let key = match p.value()? {
                Value::Str(k) => k,
                _ => return Err(p.error(None, key_at, "a key that is not a string")),
            };
            let slot = match key.as_str() {
                "descr" => &mut descr,
                "fortran_order" => &mut fortran,
                "shape" => &mut shape,
                k => {
                    return Err(p.error(
                        None,
                        key_at,
                        &format!(
                            "unknown key `{}` (a .npy header holds descr, fortran_order and \
                             shape)",
                            crate::error::excerpt(k)
                        ),
                    ));
                }
            };
            if slot.is_some() {
                return Err(p.error(Some(&key), key_at, "given twice"));
            }
            p.skip_space();
            p.expect(b':', "`:` after a key")?;
            p.skip_space();
            let at = p.offset();
            let value = p.value()?;
            *slot = Some((value, at));
            p.skip_space();
            if !p.eat(b',') {
                p.skip_space();
                p.expect(b'}', "`,` or `}` after a value")?;
                break;
            }
        }
        p.skip_space();
        if p.at < text.len() {
            return Err(p.error(None, p.offset(), "text after the header's dict"));
        }
        let missing = |k: &str| p.error(Some(k), base, "missing from the header");
        let (descr, at) = descr.ok_or_else(|| missing("descr"))?;
        let dtype = match descr {
            Value::Str(d) => dtype(&d).map_err(|m| p.error(Some("descr"), at, &m))?,
            _ => {
                return Err(p.error(
                    Some("descr"),
                    at,
                    "a structured dtype (only plain float32 and float64 arrays are read)",
                ));
            }
        };
        match fortran.ok_or_else(|| missing("fortran_order"))? {
            (Value::Bool(false), _) => {}
            (Value::Bool(true), at) => {
                return Err(p.error(
                    Some("fortran_order"),
                    at,
                    "a Fortran-order array: save a C-order one (numpy.ascontiguousarray)",
                ));
            }
            (_, at) => return Err(p.error(Some("fortran_order"), at, "not True or False")),
        }
        let (shape, shape_offset) = match shape.ok_or_else(|| missing("shape"))? {
            (Value::Tuple(dims), at) => (dims, at),
            (_, at) => return Err(p.error(Some("shape"), at, "not a tuple of integers")),
        };
        if shape.len() > MAX_DIMS {
            return Err(p.error(
                Some("shape"),
                shape_offset,
                &format!("{} dimensions (at most {MAX_DIMS})", shape.len()),
            ));
        }
        let shape = shape
            .into_iter()
            .map(usize::try_from)
            .collect::<std::result::Result<Vec<_>, _>>()
            .map_err(|_| p.error(Some("shape"), shape_offset, "a dimension beyond usize"))?;
        Ok(Dict {
            dtype,
            shape,
            shape_offset,
        })
    }
}

/// The dtype of a `descr` string, or why it is refused.
fn dtype(descr: &str) -> std::result::Result<Dtype, String> {
    match descr {
        "<f4" => Ok(Dtype::F32),
        "<f8" => Ok(Dtype::F64),
        ">f4" | ">f8" => Err(format!(
            "big-endian `{descr}`: save the array little-endian (array.astype('<f4'))"
        )),
        d => Err(format!(
            "dtype `{}` is not read: expected float32 `<f4` or float64 `<f8` (array.astype('<f4'))",
            crate::error::excerpt(d)
        )),
    }
}

impl Parser<'_> {
    fn offset(&self) -> u64 {
        self.base + self.at as u64
    }

    fn error(&self, field: Option<&str>, offset: u64, msg: &str) -> Error {
        Error::format(
            self.file,
            Some(field.unwrap_or("header")),
            Some(offset),
            msg,
        )
    }

    fn peek(&self) -> Option<u8> {
        self.text.get(self.at).copied()
    }

    fn skip_space(&mut self) {
        while matches!(self.peek(), Some(b' ' | b'\t' | b'\n' | b'\r')) {
            self.at += 1;
        }
    }

    fn eat(&mut self, b: u8) -> bool {
        let hit = self.peek() == Some(b);
        self.at += hit as usize;
        hit
    }

    fn expect(&mut self, b: u8, what: &str) -> Result<()> {
        if self.eat(b) {
            return Ok(());
        }
        let found = match self.peek() {
            Some(c) if c.is_ascii_graphic() => format!("`{}`", c as char),
            Some(c) => format!("byte {c:#04x}"),
            None => "the end of the header".to_owned(),
        };
        Err(self.error(
            None,
            self.offset(),
            &format!("expected {what}, found {found}"),
        ))
    }

    /// A string, `True`, `False` or a tuple of non-negative integers.
    fn value(&mut self) -> Result<Value> {
        let at = self.offset();
        match self.peek() {
            Some(q @ (b'\'' | b'"')) => {
                self.at += 1;
                let start = self.at;
                while let Some(c) = self.peek() {
                    if c == q {
                        let s = String::from_utf8_lossy(&self.text[start..self.at]).into_owned();
                        self.at += 1;
                        return Ok(Value::Str(s));
                    }
                    if c == b'\\' {
                        return Err(self.error(None, self.offset(), "an escape in a string"));
                    }
                    self.at += 1;
                }
                Err(self.error(None, at, "a string without its closing quote"))
            }
            Some(b'(') => {
                self.at += 1;
                let mut dims = Vec::new();
                loop {
                    self.skip_space();
                    if self.eat(b')') {
                        return Ok(Value::Tuple(dims));
                    }
                    if dims.len() > MAX_DIMS {
                        return Err(self.error(
                            Some("shape"),
                            at,
                            &format!("more than {MAX_DIMS} dimensions"),
                        ));
                    }
                    dims.push(self.dimension()?);
                    self.skip_space();
                    if !self.eat(b',') {
                        self.skip_space();
                        self.expect(b')', "`,` or `)` in a tuple")?;
                        return Ok(Value::Tuple(dims));
                    }
                }
            }
            _ => {
                for (word, b) in [("True", true), ("False", false)] {
                    if self.text[self.at..].starts_with(word.as_bytes()) {
                        self.at += word.len();
                        return Ok(Value::Bool(b));
                    }
                }
                Err(self.error(
                    None,
                    at,
                    "expected a string, True, False or a tuple of integers",
                ))
            }
        }
    }

    /// A non-negative integer of a shape.
    fn dimension(&mut self) -> Result<u64> {
        let at = self.offset();
        if self.peek() == Some(b'-') {
            return Err(self.error(Some("shape"), at, "a negative dimension"));
        }
        let start = self.at;
        while matches!(self.peek(), Some(b'0'..=b'9')) {
            self.at += 1;
        }
        let digits = std::str::from_utf8(&self.text[start..self.at]).unwrap_or("");
        if digits.is_empty() {
            return Err(self.error(Some("shape"), at, "a dimension that is not an integer"));
        }
        digits.parse::<u64>().map_err(|_| {
            self.error(
                Some("shape"),
                at,
                &format!("the dimension {} overflows", crate::error::excerpt(digits)),
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An `.npy` file of `version` with header dict `dict` (padded as numpy pads) and `data`.
    fn npy(version: u8, dict: &str, data: &[u8]) -> Vec<u8> {
        let len_bytes = if version == 1 { 2 } else { 4 };
        let mut text = dict.to_owned();
        let unpadded = 8 + len_bytes + text.len() + 1;
        text.push_str(&" ".repeat(unpadded.next_multiple_of(64) - unpadded));
        text.push('\n');
        let mut out = MAGIC.to_vec();
        out.extend_from_slice(&[version, 0]);
        match len_bytes {
            2 => out.extend_from_slice(&(text.len() as u16).to_le_bytes()),
            _ => out.extend_from_slice(&(text.len() as u32).to_le_bytes()),
        }
        out.extend_from_slice(text.as_bytes());
        out.extend_from_slice(data);
        out
    }

    fn f32_bytes(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    fn read(bytes: &[u8]) -> Result<(NpyHeader, Vec<f32>)> {
        let r = NpyReader::new("t.npy", bytes, bytes.len() as u64)?;
        let h = r.header().clone();
        Ok((h, r.read_f32()?))
    }

    /// The error of reading `bytes`: its message, which names the file, and its field and
    /// offset.
    fn refused(bytes: &[u8]) -> (String, Option<String>, Option<u64>) {
        match read(bytes) {
            Err(e @ Error::Format { .. }) => {
                let msg = e.to_string();
                assert!(msg.starts_with("t.npy: "), "{msg}");
                let Error::Format { field, offset, .. } = e else {
                    unreachable!()
                };
                (msg, field, offset)
            }
            r => panic!("{r:?}"),
        }
    }

    const VALUES: [f32; 6] = [0.5, -1.0, 3.25e-7, 1e30, 0.0, f32::NAN];

    #[test]
    fn the_exports_header_reads_back() {
        let mut b = npy_header(&[2, 3]);
        b.extend(f32_bytes(&VALUES));
        let (h, v) = read(&b).unwrap();
        assert_eq!(
            (h.version, h.dtype, &h.shape[..]),
            ((1, 0), Dtype::F32, &[2, 3][..])
        );
        assert_eq!(h.data_offset, 128);
        assert_eq!(b.len(), 128 + 24);
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&v), bits(&VALUES));
    }

    #[test]
    fn versions_key_orders_and_tuple_forms_read_alike() {
        let data = f32_bytes(&VALUES);
        for (version, dict) in [
            (
                1,
                "{'descr': '<f4', 'fortran_order': False, 'shape': (6,), }",
            ),
            (2, "{'shape': (6,), 'descr': '<f4', 'fortran_order': False}"),
            (
                3,
                "{\"fortran_order\": False, \"shape\": (6), \"descr\": \"<f4\"}",
            ),
            (
                1,
                "{ 'fortran_order':False,'shape':( 6 , ),'descr':'<f4' , }",
            ),
        ] {
            let (h, v) = read(&npy(version, dict, &data)).unwrap_or_else(|e| panic!("{dict}: {e}"));
            assert_eq!((h.version.0, &h.shape[..]), (version, &[6][..]), "{dict}");
            assert_eq!(v[..5], VALUES[..5], "{dict}");
        }
        for (dict, shape) in [
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (1, 2, 3)}",
                vec![1, 2, 3],
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (1, 2, 3,)}",
                vec![1, 2, 3],
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (3, 0, 2)}",
                vec![3, 0, 2],
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': ()}",
                vec![],
            ),
        ] {
            let n: usize = shape.iter().product();
            let (h, v) = read(&npy(1, dict, &data[..4 * n])).unwrap();
            assert_eq!((h.shape, v.len()), (shape, n), "{dict}");
        }
    }

    #[test]
    fn float64_is_converted_and_values_beyond_float32_are_refused() {
        let x = [0.1f64, -2.5, 1e-40, f64::INFINITY, 3.0e38];
        let data: Vec<u8> = x.iter().flat_map(|x| x.to_le_bytes()).collect();
        let dict = "{'descr': '<f8', 'fortran_order': False, 'shape': (5,), }";
        let (h, v) = read(&npy(1, dict, &data)).unwrap();
        assert_eq!(h.dtype, Dtype::F64);
        assert_eq!(h.data_offset, 128);
        assert_eq!(v, x.map(|x| x as f32));
        let mut big = data.clone();
        big[16..24].copy_from_slice(&1e300f64.to_le_bytes());
        let (msg, field, offset) = refused(&npy(1, dict, &big));
        assert_eq!(
            (field.as_deref(), offset),
            (Some("data"), Some(128 + 16)),
            "{msg}"
        );
        assert!(
            msg.contains("element 2") && msg.contains("float32"),
            "{msg}"
        );
    }

    #[test]
    fn other_layouts_and_dtypes_are_refused_by_name() {
        let data = f32_bytes(&VALUES);
        for (dict, field, words) in [
            (
                "{'descr': '<f4', 'fortran_order': True, 'shape': (2, 3), }",
                "fortran_order",
                "Fortran",
            ),
            (
                "{'descr': '>f4', 'fortran_order': False, 'shape': (2, 3), }",
                "descr",
                "big-endian `>f4`",
            ),
            (
                "{'descr': '<i4', 'fortran_order': False, 'shape': (2, 3), }",
                "descr",
                "dtype `<i4`",
            ),
            (
                "{'descr': '<f2', 'fortran_order': False, 'shape': (2, 3), }",
                "descr",
                "dtype `<f2`",
            ),
            (
                "{'descr': [('a', '<f4')], 'fortran_order': False, 'shape': (6,), }",
                "header",
                "expected a string",
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (-2, 3), }",
                "shape",
                "negative",
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (99999999999999999999999, 3), }",
                "shape",
                "overflows",
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': 6, }",
                "header",
                "expected a string",
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, }",
                "shape",
                "missing",
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (6,), 'extra': 1}",
                "header",
                "unknown key `extra`",
            ),
            (
                "{'descr': '<f4', 'descr': '<f4', 'fortran_order': False, 'shape': (6,)}",
                "descr",
                "twice",
            ),
            (
                "{'descr': '<f4', 'fortran_order': False, 'shape': (6,)} x",
                "header",
                "after the header",
            ),
            (
                "{'descr': '<f4' 'fortran_order': False, 'shape': (6,)}",
                "header",
                "expected `,` or `}`",
            ),
        ] {
            let (msg, f, offset) = refused(&npy(1, dict, &data));
            assert_eq!(f.as_deref(), Some(field), "{dict}: {msg}");
            assert!(msg.contains(words), "{dict}: {msg}");
            assert!(offset.is_some_and(|o| o >= 10), "{dict}: {msg}");
        }
    }

    /// A shape whose product overflows, or one far larger than the file, is refused from the
    /// header and the file's size alone: nothing is allocated for it.
    #[test]
    fn a_shape_the_file_cannot_hold_is_refused_before_allocating() {
        let data = f32_bytes(&VALUES);
        let dict =
            "{'descr': '<f4', 'fortran_order': False, 'shape': (4294967296, 4294967296, 16), }";
        let (msg, field, _) = refused(&npy(1, dict, &data));
        assert_eq!(field.as_deref(), Some("shape"), "{msg}");
        assert!(msg.contains("overflows"), "{msg}");
        let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (100000, 100000, 100), }";
        let b = npy(1, dict, &data);
        let (msg, field, offset) = refused(&b);
        assert_eq!(
            (field.as_deref(), offset),
            (Some("data"), Some(b.len() as u64)),
            "{msg}"
        );
        assert!(
            msg.contains("needs 4000000000000 bytes") && msg.contains("holds 24"),
            "{msg}"
        );
    }

    #[test]
    fn truncated_files_bad_magic_and_unknown_versions_are_refused() {
        let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }";
        let whole = npy(1, dict, &f32_bytes(&VALUES));
        assert_eq!(whole.len(), 128 + 24);
        for (cut, field) in [
            (0, "magic"),
            (5, "magic"),
            (7, "version"),
            (9, "header length"),
            (40, "header"),
            (127, "header"),
            (128, "data"),
            (whole.len() - 1, "data"),
        ] {
            let (msg, f, offset) = refused(&whole[..cut]);
            assert_eq!(f.as_deref(), Some(field), "cut at {cut}: {msg}");
            assert!(offset.is_some(), "cut at {cut}: {msg}");
        }
        let mut longer = whole.clone();
        longer.extend_from_slice(&[0, 0, 0, 0]);
        let (msg, field, offset) = refused(&longer);
        assert_eq!(
            (field.as_deref(), offset),
            (Some("data"), Some(whole.len() as u64))
        );
        assert!(msg.contains("4 bytes after"), "{msg}");
        let mut magic = whole.clone();
        magic[1] = b'n';
        let (msg, field, offset) = refused(&magic);
        assert_eq!(
            (field.as_deref(), offset),
            (Some("magic"), Some(0)),
            "{msg}"
        );
        let mut v = whole.clone();
        v[6] = 4;
        let (msg, field, offset) = refused(&v);
        assert_eq!(
            (field.as_deref(), offset),
            (Some("version"), Some(6)),
            "{msg}"
        );
        assert!(msg.contains("4.0"), "{msg}");
        // A header length beyond the bound, and one beyond the file.
        let mut long = npy(2, dict, &f32_bytes(&VALUES));
        long[8..12].copy_from_slice(&(1u32 << 30).to_le_bytes());
        let (msg, field, _) = refused(&long);
        assert_eq!(field.as_deref(), Some("header length"), "{msg}");
        long[8..12].copy_from_slice(&4000u32.to_le_bytes());
        let (msg, field, _) = refused(&long);
        assert_eq!(field.as_deref(), Some("header"), "{msg}");
        assert!(msg.contains("truncated"), "{msg}");
        let mut utf = npy(
            3,
            "{'descr': '<f4', 'fortran_order': False, 'shape': (6,), }",
            &f32_bytes(&VALUES),
        );
        utf[20] = 0xff;
        let (msg, field, _) = refused(&utf);
        assert_eq!(field.as_deref(), Some("header"), "{msg}");
    }

    /// Random mutants of valid files — bytes flipped, overwritten, cut and inserted, in the
    /// header and the data — are read or refused with a format error, never a panic; what is
    /// read holds exactly the elements its shape says.
    #[test]
    fn mutants_are_read_or_refused_never_a_panic() {
        let dicts = [
            (
                1,
                "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }",
            ),
            (
                2,
                "{'shape': (3, 2), 'fortran_order': False, 'descr': '<f8'}",
            ),
            (3, "{'descr': '<f4', 'fortran_order': False, 'shape': (6,)}"),
        ];
        let mut rng = crate::rng::Pcg32::new(7);
        let (mut read_ok, mut refused) = (0, 0);
        for k in 0..30_000 {
            let (version, dict) = dicts[k % dicts.len()];
            let data = if dict.contains("<f8") {
                VALUES
                    .iter()
                    .flat_map(|&x| (x as f64).to_le_bytes())
                    .collect()
            } else {
                f32_bytes(&VALUES)
            };
            let mut b = npy(version, dict, &data);
            for _ in 0..1 + rng.below(3) {
                let at = rng.below(b.len() as u32) as usize;
                match rng.below(4) {
                    0 => b[at] ^= 1 << rng.below(8),
                    1 => b[at] = b"0123456789(),' -:{}TF"[rng.below(21) as usize],
                    2 => b.truncate(at),
                    _ => b.insert(at, rng.below(256) as u8),
                }
                if b.is_empty() {
                    break;
                }
            }
            match read(&b) {
                Ok((h, v)) => {
                    assert_eq!(v.len(), h.elements());
                    read_ok += 1;
                }
                Err(Error::Format { .. }) => refused += 1,
                Err(e) => panic!("mutant {k}: {e}"),
            }
        }
        assert!(
            read_ok > 1000 && refused > 10_000,
            "{read_ok} read, {refused} refused"
        );
    }

    #[test]
    fn a_file_reads_by_its_path() {
        let d = crate::testkit::TempDir::new("npy-read");
        let p = d.join("a.npy");
        let mut b = npy_header(&[3, 2]);
        b.extend(f32_bytes(&VALUES));
        std::fs::write(&p, &b).unwrap();
        let (shape, v) = read_f32(&p).unwrap();
        assert_eq!((shape, v[..5].to_vec()), (vec![3, 2], VALUES[..5].to_vec()));
        std::fs::write(&p, &b[..b.len() - 2]).unwrap();
        let e = read_f32(&p).unwrap_err().to_string();
        assert!(e.contains("a.npy") && e.contains("truncated"), "{e}");
        assert!(matches!(
            read_f32(d.join("none.npy")),
            Err(Error::NotFound(_))
        ));
        assert!(read_f32(d.path()).is_err());
    }
}
