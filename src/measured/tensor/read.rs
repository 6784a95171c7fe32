//! Reading a tensor file: the header parsed with every count, shape and offset checked against
//! the file's length, and a field's values converted to f64 or f32.

use std::path::Path;

use super::{Dtype, Field, MAGIC};
use crate::error::{Error, Result};

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
