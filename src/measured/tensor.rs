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

use std::path::Path;

use crate::error::{Error, Result};

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

/// Element type of a tensor field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dtype {
    /// Unsigned 8-bit integer (code 1).
    U8,
    /// Signed 8-bit integer (code 2).
    I8,
    /// Unsigned 16-bit integer (code 3).
    U16,
    /// Signed 16-bit integer (code 4).
    I16,
    /// Unsigned 32-bit integer (code 5).
    U32,
    /// Signed 32-bit integer (code 6).
    I32,
    /// Unsigned 64-bit integer (code 7).
    U64,
    /// Signed 64-bit integer (code 8).
    I64,
    /// IEEE half precision (code 9).
    F16,
    /// IEEE single precision (code 10).
    F32,
    /// IEEE double precision (code 11).
    F64,
}

impl Dtype {
    /// The dtype of a file code, `None` for unknown codes (0 is "invalid" in the format).
    pub fn from_code(code: u8) -> Option<Dtype> {
        use Dtype::*;
        Some(match code {
            1 => U8,
            2 => I8,
            3 => U16,
            4 => I16,
            5 => U32,
            6 => I32,
            7 => U64,
            8 => I64,
            9 => F16,
            10 => F32,
            11 => F64,
            _ => return None,
        })
    }

    /// The file code of this dtype.
    pub fn code(self) -> u8 {
        self as u8 + 1
    }

    /// Bytes per element.
    pub fn size(self) -> usize {
        use Dtype::*;
        match self {
            U8 | I8 => 1,
            U16 | I16 | F16 => 2,
            U32 | I32 | F32 => 4,
            U64 | I64 | F64 => 8,
        }
    }

    /// Whether this is a floating-point type.
    pub fn is_float(self) -> bool {
        matches!(self, Dtype::F16 | Dtype::F32 | Dtype::F64)
    }

    /// Lower-case name (`f32`, `u8`, ...).
    pub fn name(self) -> &'static str {
        use Dtype::*;
        match self {
            U8 => "u8",
            I8 => "i8",
            U16 => "u16",
            I16 => "i16",
            U32 => "u32",
            I32 => "i32",
            U64 => "u64",
            I64 => "i64",
            F16 => "f16",
            F32 => "f32",
            F64 => "f64",
        }
    }
}

/// One named array of a tensor file: its type, shape and where its bytes are.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    /// The field's name (`theta_i`, `rgb`, ...).
    pub name: String,
    /// Element type.
    pub dtype: Dtype,
    /// Shape, outermost first (the last dimension is contiguous).
    pub shape: Vec<usize>,
    /// Absolute byte offset of the data in the file.
    pub offset: u64,
    /// Byte length of the data (checked: offset + len ≤ file size).
    len: usize,
}

impl Field {
    /// Number of elements (the product of the shape).
    pub fn count(&self) -> usize {
        self.len / self.dtype.size()
    }

    /// Shape as `f32[8,128]`-style text.
    pub fn describe(&self) -> String {
        let dims: Vec<String> = self.shape.iter().map(|d| d.to_string()).collect();
        format!("{}[{}]", self.dtype.name(), dims.join(","))
    }
}

/// A parsed tensor file: the fields and the bytes they point into.
#[derive(Debug, Clone)]
pub struct TensorFile {
    file: String,
    bytes: Vec<u8>,
    fields: Vec<Field>,
}

/// A bounds-checked little-endian cursor over the header.
struct Cursor<'a> {
    file: &'a str,
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize, what: &str, field: Option<&str>) -> Result<&'a [u8]> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.bytes.len());
        match end {
            Some(end) => {
                let s = &self.bytes[self.pos..end];
                self.pos = end;
                Ok(s)
            }
            None => Err(Error::format(
                self.file,
                field,
                Some(self.pos as u64),
                format!(
                    "truncated: {what} needs {n} bytes, file has {} left",
                    self.bytes.len().saturating_sub(self.pos)
                ),
            )),
        }
    }
    fn u8(&mut self, what: &str, field: Option<&str>) -> Result<u8> {
        Ok(self.take(1, what, field)?[0])
    }
    fn u16(&mut self, what: &str, field: Option<&str>) -> Result<u16> {
        let b = self.take(2, what, field)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }
    fn u32(&mut self, what: &str, field: Option<&str>) -> Result<u32> {
        let b = self.take(4, what, field)?;
        Ok(u32::from_le_bytes(b.try_into().unwrap_or([0; 4])))
    }
    fn u64(&mut self, what: &str, field: Option<&str>) -> Result<u64> {
        let b = self.take(8, what, field)?;
        Ok(u64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
    }
}

/// The smallest possible field header: name length, ndim, dtype, offset (no name, no dims).
const MIN_FIELD_HEADER: usize = 2 + 2 + 1 + 8;

impl TensorFile {
    /// Reads and parses a tensor file.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        crate::files::require_regular(path)?;
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        Self::from_bytes(path.display().to_string(), bytes)
    }

    /// Parses a tensor file held in memory; `file` names it in errors.
    pub fn from_bytes(file: impl Into<String>, bytes: Vec<u8>) -> Result<Self> {
        let file = file.into();
        let mut c = Cursor {
            file: &file,
            bytes: &bytes,
            pos: 0,
        };
        let magic = c.take(12, "the magic", None)?;
        if magic != MAGIC {
            // A brdftab table given a `.bsdf` name is the likely mistake: say so.
            let table = bytes.get(..8) == Some(&crate::store::format::MAGIC[..]);
            return Err(Error::format(
                &file,
                None,
                Some(0),
                if table {
                    "not a tensor file but a brdftab table (its signature): give it a .btdb name"
                } else {
                    "not a tensor file (magic `tensor_file\\0` missing)"
                },
            ));
        }
        let v0 = c.u8("the version", None)?;
        let v1 = c.u8("the version", None)?;
        if (v0, v1) != (1, 0) {
            return Err(Error::format(
                &file,
                None,
                Some(12),
                format!("unsupported tensor file version {v0}.{v1} (expected 1.0)"),
            ));
        }
        let n_fields = c.u32("the field count", None)? as usize;
        let left = bytes.len() - c.pos;
        if n_fields > left / MIN_FIELD_HEADER {
            return Err(Error::format(
                &file,
                None,
                Some(14),
                format!(
                    "field count {n_fields} cannot fit in the {left} bytes left (truncated or corrupt)"
                ),
            ));
        }
        let mut fields: Vec<Field> = Vec::with_capacity(n_fields);
        for i in 0..n_fields {
            let header_at = c.pos as u64;
            let label = format!("#{i}");
            let name_len = c.u16("a field name length", Some(&label))? as usize;
            let name_bytes = c.take(name_len, "a field name", Some(&label))?;
            let name = String::from_utf8(name_bytes.to_vec()).map_err(|_| {
                Error::format(
                    &file,
                    Some(&label),
                    Some(header_at + 2),
                    "field name is not UTF-8",
                )
            })?;
            let f = Some(name.as_str());
            let ndim = c.u16("ndim", f)? as usize;
            let dtype_at = c.pos as u64;
            let code = c.u8("dtype", f)?;
            let dtype = Dtype::from_code(code).ok_or_else(|| {
                Error::format(
                    &file,
                    f,
                    Some(dtype_at),
                    format!("unknown dtype code {code} (expected 1..=11)"),
                )
            })?;
            let offset_at = c.pos as u64;
            let offset = c.u64("data offset", f)?;
            if ndim > (bytes.len() - c.pos) / 8 {
                return Err(Error::format(
                    &file,
                    f,
                    Some(c.pos as u64),
                    format!("truncated: {ndim} dimensions do not fit in the file"),
                ));
            }
            let mut shape = Vec::with_capacity(ndim);
            let mut len = dtype.size();
            for _ in 0..ndim {
                let dim_at = c.pos as u64;
                let d = c.u64("shape", f)?;
                let d_us = usize::try_from(d).ok();
                len = match d_us.and_then(|d| len.checked_mul(d)) {
                    Some(l) => l,
                    None => {
                        return Err(Error::format(
                            &file,
                            f,
                            Some(dim_at),
                            format!("shape overflows: dimension {d} makes the size exceed 2^64"),
                        ));
                    }
                };
                shape.push(d as usize);
            }
            let end = usize::try_from(offset)
                .ok()
                .and_then(|o| o.checked_add(len));
            match end {
                Some(end) if end <= bytes.len() => {}
                _ => {
                    return Err(Error::format(
                        &file,
                        f,
                        Some(offset_at),
                        format!(
                            "data ({} of {len} bytes at offset {offset}) lies past the end of the file ({} bytes)",
                            describe_shape(dtype, &shape),
                            bytes.len()
                        ),
                    ));
                }
            }
            if fields.iter().any(|g| g.name == name) {
                return Err(Error::format(
                    &file,
                    f,
                    Some(header_at),
                    "duplicate field name",
                ));
            }
            fields.push(Field {
                name,
                dtype,
                shape,
                offset,
                len,
            });
        }
        Ok(TensorFile {
            file,
            bytes,
            fields,
        })
    }

    /// The file name used in errors.
    pub fn file_name(&self) -> &str {
        &self.file
    }

    /// Total size of the file in bytes.
    pub fn size(&self) -> u64 {
        self.bytes.len() as u64
    }

    /// The whole file's bytes (e.g. for checksums).
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// All fields in file order.
    pub fn fields(&self) -> &[Field] {
        &self.fields
    }

    /// The field called `name`, if present.
    pub fn get(&self, name: &str) -> Option<&Field> {
        self.fields.iter().find(|f| f.name == name)
    }

    /// The field called `name`, or a format error saying it is missing.
    pub fn field(&self, name: &str) -> Result<&Field> {
        self.get(name)
            .ok_or_else(|| Error::format(&self.file, Some(name), None, "required field is missing"))
    }

    /// The raw bytes of a field.
    pub fn raw(&self, field: &Field) -> &[u8] {
        let o = field.offset as usize;
        &self.bytes[o..o + field.len]
    }

    /// The field's values converted to f64 (any dtype). Floating-point fields must be finite:
    /// a NaN or infinity is an error naming the element's byte offset.
    pub fn to_f64(&self, field: &Field) -> Result<Vec<f64>> {
        let raw = self.raw(field);
        let s = field.dtype.size();
        let mut out = Vec::with_capacity(field.count());
        for (k, b) in raw.chunks_exact(s).enumerate() {
            let v = decode(field.dtype, b);
            if !v.is_finite() {
                return Err(Error::format(
                    &self.file,
                    Some(&field.name),
                    Some(field.offset + (k * s) as u64),
                    format!("element {k} is {v} (NaN and infinities are not allowed)"),
                ));
            }
            out.push(v);
        }
        Ok(out)
    }

    /// The field's values as f32 (see [`TensorFile::to_f64`]; f64 values outside the f32 range
    /// are errors too).
    pub fn to_f32(&self, field: &Field) -> Result<Vec<f32>> {
        let v = self.to_f64(field)?;
        let mut out = Vec::with_capacity(v.len());
        for (k, x) in v.into_iter().enumerate() {
            let y = x as f32;
            if !y.is_finite() {
                return Err(Error::format(
                    &self.file,
                    Some(&field.name),
                    Some(field.offset + (k * field.dtype.size()) as u64),
                    format!("element {k} = {x} does not fit in f32"),
                ));
            }
            out.push(y);
        }
        Ok(out)
    }

    /// A format error about `field` (for checks made by readers of particular layouts).
    pub fn error(&self, field: &Field, msg: impl Into<String>) -> Error {
        Error::format(&self.file, Some(&field.name), Some(field.offset), msg)
    }

    /// Checks that `field` has `ndim` dimensions; returns the shape.
    pub fn expect_ndim<'f>(&self, field: &'f Field, ndim: usize) -> Result<&'f [usize]> {
        if field.shape.len() != ndim {
            return Err(self.error(
                field,
                format!(
                    "expected {ndim} dimensions, found {} ({})",
                    field.shape.len(),
                    field.describe()
                ),
            ));
        }
        Ok(&field.shape)
    }
}

fn describe_shape(dtype: Dtype, shape: &[usize]) -> String {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    format!("{}[{}]", dtype.name(), dims.join(","))
}

/// Decodes one little-endian element (`b.len() == dtype.size()`).
fn decode(dtype: Dtype, b: &[u8]) -> f64 {
    let a2 = || [b[0], b[1]];
    let a4 = || [b[0], b[1], b[2], b[3]];
    let a8 = || [b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]];
    match dtype {
        Dtype::U8 => b[0] as f64,
        Dtype::I8 => b[0] as i8 as f64,
        Dtype::U16 => u16::from_le_bytes(a2()) as f64,
        Dtype::I16 => i16::from_le_bytes(a2()) as f64,
        Dtype::U32 => u32::from_le_bytes(a4()) as f64,
        Dtype::I32 => i32::from_le_bytes(a4()) as f64,
        Dtype::U64 => u64::from_le_bytes(a8()) as f64,
        Dtype::I64 => i64::from_le_bytes(a8()) as f64,
        Dtype::F16 => half::f16::from_bits(u16::from_le_bytes(a2())).to_f64(),
        Dtype::F32 => f32::from_le_bytes(a4()) as f64,
        Dtype::F64 => f64::from_le_bytes(a8()),
    }
}

/// The alignment of every field's data in a written file: 8 bytes, so that a reader which maps
/// the file and reads an `f32`/`f64` field in place reads aligned memory.
pub const ALIGN: u64 = 8;

/// Builds a tensor file in memory: add fields, then [`TensorWriter::to_bytes`].
#[derive(Debug, Default, Clone)]
pub struct TensorWriter {
    fields: Vec<(String, Dtype, Vec<u64>, Vec<u8>)>,
}

impl TensorWriter {
    /// An empty file.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a field with raw little-endian element bytes (not checked against the shape, so
    /// tests can write inconsistent files).
    pub fn raw(mut self, name: &str, dtype: Dtype, shape: &[u64], data: Vec<u8>) -> Self {
        self.fields
            .push((name.to_owned(), dtype, shape.to_vec(), data));
        self
    }

    /// Adds an f32 field.
    pub fn f32(self, name: &str, shape: &[u64], data: &[f32]) -> Self {
        let bytes = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.raw(name, Dtype::F32, shape, bytes)
    }

    /// Adds a u8 field.
    pub fn u8(self, name: &str, shape: &[u64], data: &[u8]) -> Self {
        self.raw(name, Dtype::U8, shape, data.to_vec())
    }

    /// Serializes: header first, then the fields' data in order, each starting at a multiple
    /// of [`ALIGN`] bytes (zero padding between), as Mitsuba's `tensor_io.write` and the
    /// published files lay them out.
    pub fn to_bytes(&self) -> Vec<u8> {
        let align = |x: u64| x.div_ceil(ALIGN) * ALIGN;
        let mut header = Vec::new();
        header.extend_from_slice(MAGIC);
        header.extend_from_slice(&[1, 0]);
        header.extend_from_slice(&(self.fields.len() as u32).to_le_bytes());
        let header_len: usize = header.len()
            + self
                .fields
                .iter()
                .map(|(n, _, s, _)| 2 + n.len() + 2 + 1 + 8 + 8 * s.len())
                .sum::<usize>();
        let mut offset = align(header_len as u64);
        for (name, dtype, shape, data) in &self.fields {
            header.extend_from_slice(&(name.len() as u16).to_le_bytes());
            header.extend_from_slice(name.as_bytes());
            header.extend_from_slice(&(shape.len() as u16).to_le_bytes());
            header.push(dtype.code());
            header.extend_from_slice(&offset.to_le_bytes());
            for d in shape {
                header.extend_from_slice(&d.to_le_bytes());
            }
            offset = align(offset + data.len() as u64);
        }
        for (_, _, _, data) in &self.fields {
            header.resize(align(header.len() as u64) as usize, 0);
            header.extend_from_slice(data);
        }
        header
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<u8> {
        let h = [
            half::f16::from_f32(1.5).to_bits(),
            half::f16::from_f32(-2.0).to_bits(),
        ];
        TensorWriter::new()
            .u8("a", &[3], &[1, 2, 255])
            .raw("b", Dtype::I8, &[2], vec![0xff, 0x7f])
            .raw("c", Dtype::U16, &[1], 65535u16.to_le_bytes().to_vec())
            .raw("d", Dtype::I16, &[1], (-300i16).to_le_bytes().to_vec())
            .raw(
                "e",
                Dtype::U32,
                &[1],
                4_000_000_000u32.to_le_bytes().to_vec(),
            )
            .raw("f", Dtype::I32, &[1], (-7i32).to_le_bytes().to_vec())
            .raw("g", Dtype::U64, &[1], (1u64 << 40).to_le_bytes().to_vec())
            .raw(
                "h",
                Dtype::I64,
                &[1],
                (-(1i64 << 40)).to_le_bytes().to_vec(),
            )
            .raw(
                "i",
                Dtype::F16,
                &[2],
                h.iter().flat_map(|x| x.to_le_bytes()).collect(),
            )
            .f32("j", &[2, 1], &[0.25, -1.0])
            .raw("k", Dtype::F64, &[1], 1e300f64.to_le_bytes().to_vec())
            .to_bytes()
    }

    #[test]
    fn every_dtype_decodes() {
        let t = TensorFile::from_bytes("mem", sample()).unwrap();
        let v = |n: &str| t.to_f64(t.field(n).unwrap()).unwrap();
        assert_eq!(v("a"), [1.0, 2.0, 255.0]);
        assert_eq!(v("b"), [-1.0, 127.0]);
        assert_eq!(v("c"), [65535.0]);
        assert_eq!(v("d"), [-300.0]);
        assert_eq!(v("e"), [4e9]);
        assert_eq!(v("f"), [-7.0]);
        assert_eq!(v("g"), [(1u64 << 40) as f64]);
        assert_eq!(v("h"), [-((1u64 << 40) as f64)]);
        assert_eq!(v("i"), [1.5, -2.0]);
        assert_eq!(v("j"), [0.25, -1.0]);
        assert_eq!(v("k"), [1e300]);
        assert_eq!(t.field("j").unwrap().shape, [2, 1]);
        // 1e300 does not fit in f32.
        assert!(t.to_f32(t.field("k").unwrap()).is_err());
    }

    #[test]
    fn every_truncation_is_an_error() {
        let bytes = sample();
        for n in 0..bytes.len() {
            let r = TensorFile::from_bytes("mem", bytes[..n].to_vec());
            assert!(
                matches!(r, Err(Error::Format { .. })),
                "prefix {n} accepted"
            );
        }
    }

    #[test]
    fn unknown_dtype_names_field_and_offset() {
        let mut b = TensorWriter::new().f32("x", &[1], &[1.0]).to_bytes();
        // header: 12 magic + 2 version + 4 count + 2 len + 1 name + 2 ndim = 23 → dtype
        b[23] = 12;
        let e = TensorFile::from_bytes("t.bsdf", b).unwrap_err().to_string();
        assert!(
            e.contains("t.bsdf") && e.contains("`x`") && e.contains("at byte 23"),
            "{e}"
        );
        assert!(e.contains("unknown dtype"), "{e}");
    }

    #[test]
    fn shape_and_offset_past_the_end_are_errors() {
        // Shape claims more data than exists.
        let b = TensorWriter::new()
            .raw("x", Dtype::F32, &[1000], vec![0; 8])
            .to_bytes();
        let e = TensorFile::from_bytes("m", b).unwrap_err().to_string();
        assert!(e.contains("past the end"), "{e}");
        // Overflowing shape product.
        let b = TensorWriter::new()
            .raw("x", Dtype::F64, &[u64::MAX / 2, 4], vec![0; 8])
            .to_bytes();
        let e = TensorFile::from_bytes("m", b).unwrap_err().to_string();
        assert!(e.contains("overflows"), "{e}");
        // Offset far past the end.
        let mut b = TensorWriter::new().f32("x", &[1], &[1.0]).to_bytes();
        b[24..32].copy_from_slice(&u64::MAX.to_le_bytes());
        let e = TensorFile::from_bytes("m", b).unwrap_err().to_string();
        assert!(e.contains("past the end") && e.contains("`x`"), "{e}");
        // Absurd field count.
        let mut b = TensorWriter::new().f32("x", &[1], &[1.0]).to_bytes();
        b[14..18].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(TensorFile::from_bytes("m", b).is_err());
    }

    #[test]
    fn nan_is_an_error_with_the_element_offset() {
        let b = TensorWriter::new()
            .f32("x", &[3], &[1.0, f32::NAN, 2.0])
            .to_bytes();
        let t = TensorFile::from_bytes("m", b).unwrap();
        let f = t.field("x").unwrap();
        let e = t.to_f32(f).unwrap_err().to_string();
        assert!(e.contains(&format!("at byte {}", f.offset + 4)), "{e}");
    }

    #[test]
    fn bad_magic_and_version() {
        let mut b = TensorWriter::new().to_bytes();
        b[12] = 2;
        assert!(
            TensorFile::from_bytes("m", b.clone())
                .unwrap_err()
                .to_string()
                .contains("version")
        );
        b[0] = b'x';
        assert!(
            TensorFile::from_bytes("m", b)
                .unwrap_err()
                .to_string()
                .contains("magic")
        );
    }
}
