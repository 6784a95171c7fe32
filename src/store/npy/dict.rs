//! The header's dict of an `.npy` file: its Python literal parsed, with every refusal naming the
//! field and the byte offset (see the parent module's docs for what is taken).

use super::{Dtype, MAX_DIMS};
use crate::error::{Error, Result};

/// The header's dict, parsed from its Python literal: `{'descr': '<f4', 'fortran_order':
/// False, 'shape': (2, 3), }` with the keys in any order and the usual spaces, commas and
/// padding.
pub(super) struct Dict {
    pub(super) dtype: Dtype,
    pub(super) shape: Vec<usize>,
    /// Where the shape's tuple starts in the file.
    pub(super) shape_offset: u64,
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
    pub(super) fn parse(text: &[u8], file: &str, base: u64) -> Result<Dict> {
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
