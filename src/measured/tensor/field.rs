//! What a field of a tensor file is: its element type ([`Dtype`]) and its shape and place in
//! the file ([`Field`]).

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
    pub(super) len: usize,
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
