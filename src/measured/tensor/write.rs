//! Writing a tensor file: the container the reader reads, built in memory (for the `.bsdf`
//! writer, and for tests' small or deliberately broken files).

use super::{Dtype, MAGIC};

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
