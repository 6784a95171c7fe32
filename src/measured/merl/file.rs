//! A MERL `.binary` file read (its size, header and every sample checked) and written.

use std::path::Path;

use super::{FILE_SIZE, MerlBrdf, RES_PHI_D, RES_THETA_D, RES_THETA_H, SAMPLES, SCALE};
use crate::error::{Error, Result};
use crate::spectrum::Channels;

/// A brdftab table given a `.binary` name is the likely mistake behind a file that starts with
/// the table signature: said so, where its header read as MERL dimensions (1146372745 ×
/// 436866370 × 1) and its size as a truncation said nothing of what the file is.
fn table_error(file: &str, head: &[u8]) -> Option<Error> {
    (head.get(..8) == Some(&crate::store::format::MAGIC[..])).then(|| {
        Error::format(
            file,
            None,
            Some(0),
            "not a MERL file but a brdftab table (its signature): give it a .btdb name",
        )
    })
}

impl MerlBrdf {
    /// Reads a `.binary` file; checks its size and header before reading the samples.
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let file = path.display().to_string();
        crate::files::require_regular(path)?;
        let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
        if meta.len() != FILE_SIZE {
            // Read the header anyway (if present) for a more helpful message.
            let head = std::fs::File::open(path).ok().and_then(|mut f| {
                use std::io::Read;
                let mut h = [0u8; 12];
                f.read_exact(&mut h).ok().map(|_| h)
            });
            if let Some(e) = head.as_ref().and_then(|h| table_error(&file, h)) {
                return Err(e);
            }
            return Err(size_error(&file, meta.len(), head.map(|h| dims(&h))));
        }
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        Self::from_bytes(file, &bytes)
    }

    /// Parses a MERL file held in memory; `name` names it in errors.
    pub fn from_bytes(name: impl Into<String>, bytes: &[u8]) -> Result<Self> {
        let name = name.into();
        if bytes.len() < 12 {
            return Err(Error::format(
                &name,
                Some("header"),
                Some(0),
                format!("truncated: {} bytes, the header alone has 12", bytes.len()),
            ));
        }
        if let Some(e) = table_error(&name, bytes) {
            return Err(e);
        }
        let d = dims(&bytes[..12]);
        if d != [RES_THETA_H as i32, RES_THETA_D as i32, RES_PHI_D as i32] {
            let product = d.iter().map(|&x| x as i64).product::<i64>();
            return Err(Error::format(
                &name,
                Some("header"),
                Some(0),
                format!(
                    "dimensions {} × {} × {} (product {product}); MERL files are 90 × 90 × 180 = {SAMPLES}",
                    d[0], d[1], d[2]
                ),
            ));
        }
        if bytes.len() as u64 != FILE_SIZE {
            return Err(size_error(&name, bytes.len() as u64, None));
        }
        let data: Vec<f64> = bytes[12..]
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
            .collect();
        if let Some((k, why)) = bad_sample(&data) {
            return Err(Error::format(
                &name,
                Some(CHANNEL_NAMES[k / SAMPLES]),
                Some(12 + 8 * k as u64),
                format!("sample {} {why}", k % SAMPLES),
            ));
        }
        Ok(MerlBrdf {
            name,
            data,
            channels: Channels::Rgb,
            sampler: std::sync::OnceLock::new(),
        })
    }

    /// Builds from raw stored values (3 × [`SAMPLES`], channel-planar, unscaled).
    pub fn from_raw(name: impl Into<String>, data: Vec<f64>) -> Result<Self> {
        if data.len() != 3 * SAMPLES {
            return Err(Error::arg(
                "data",
                format!("{} values, expected 3 × {SAMPLES}", data.len()),
            ));
        }
        if let Some((k, why)) = bad_sample(&data) {
            return Err(Error::arg(
                "data",
                format!(
                    "channel {} sample {} {why}",
                    CHANNEL_NAMES[k / SAMPLES],
                    k % SAMPLES
                ),
            ));
        }
        Ok(MerlBrdf {
            name: name.into(),
            data,
            channels: Channels::Rgb,
            sampler: std::sync::OnceLock::new(),
        })
    }

    /// The file's bytes: header and the raw samples, little-endian.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(FILE_SIZE as usize);
        for d in [RES_THETA_H, RES_THETA_D, RES_PHI_D] {
            out.extend_from_slice(&(d as i32).to_le_bytes());
        }
        for v in &self.data {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out
    }

    /// Writes the file (through a temporary file renamed into place).
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        crate::files::write_atomic(path.as_ref(), &self.to_bytes())
    }
}

/// The error of a file of `len` bytes, not [`FILE_SIZE`]: at the byte where it ends (and the
/// channel and sample missing from there) or where its surplus begins; `header` the dimensions
/// it says, when read.
fn size_error(file: &str, len: u64, header: Option<[i32; 3]>) -> Error {
    let hint = header
        .map(|d| format!(" (header says {} × {} × {})", d[0], d[1], d[2]))
        .unwrap_or_default();
    let (offset, what) = if len < 12 {
        (len, "truncated in the header".to_owned())
    } else if len < FILE_SIZE {
        let k = ((len - 12) / 8) as usize;
        let ch = CHANNEL_NAMES[k / SAMPLES];
        (
            len,
            format!("truncated in channel {ch}, sample {}", k % SAMPLES),
        )
    } else {
        (
            FILE_SIZE,
            format!("{} bytes after the last sample", len - FILE_SIZE),
        )
    };
    Error::format(
        file,
        None,
        Some(offset),
        format!("a MERL file has {FILE_SIZE} bytes, this one has {len}{hint}: {what}"),
    )
}

/// The channels of the file, in order.
const CHANNEL_NAMES: [&str; 3] = ["R", "G", "B"];

/// The first stored value no lookup can use, and why: NaN, ±∞, or finite but beyond f32 once
/// scaled to f_r (the lookups' precision), where it would become ∞ — a corrupt file, which
/// would otherwise evaluate to ∞ in the cells it touches. Negative finite values are the
/// database's "unmeasured" marker and pass.
fn bad_sample(data: &[f64]) -> Option<(usize, String)> {
    data.iter().enumerate().find_map(|(k, &v)| {
        let scaled = v * SCALE[k / SAMPLES];
        if v.is_nan() {
            Some((k, "is NaN".to_owned()))
        } else if v.is_infinite() {
            Some((k, format!("is {}", if v > 0.0 { "+∞" } else { "−∞" })))
        } else if !(scaled as f32).is_finite() {
            Some((k, format!("is {v:e}, beyond f32 once scaled to f_r")))
        } else {
            None
        }
    })
}

fn dims(h: &[u8]) -> [i32; 3] {
    let r = |i: usize| i32::from_le_bytes([h[i], h[i + 1], h[i + 2], h[i + 3]]);
    [r(0), r(4), r(8)]
}
