//! Exports of stored tables: the dense table as NumPy `.npy`, 2D slices as OpenEXR.
//!
//! Both stream from the chunks: `.npy` writes chunk after chunk (the table is never whole in
//! memory), EXR slices decode only the chunks the slice touches.

use std::io::Write;
use std::path::Path;

use super::StoredTable;
pub use super::npy::npy_header;
use crate::error::{Error, Result};
use crate::spectrum::Channels;

/// Maps the index of a node (one per angular axis of the stored shape) to the flat offset of its
/// channel 0, or `None` when the node is not stored (packed layouts). `None` as a whole means the
/// plain row-major layout of the stored shape.
pub type NodeOffset<'a> = Option<&'a (dyn Fn(&[usize]) -> Option<usize> + Sync)>;

/// Writes the table as `.npy`: shape = stored grid dims + channels, dtype `<f4`, C order. Dense
/// tables stream chunk by chunk; packed tables (fewer values than the shape) are expanded with
/// `offset`, unstored nodes written as NaN.
///
/// The file is written through a temporary file renamed into place: a chunk that fails (its
/// checksum, its decoding) leaves no partial `.npy` behind.
pub fn npy(table: &StoredTable, out: impl AsRef<Path>, offset: NodeOffset<'_>) -> Result<()> {
    let path = &crate::files::resolve_links(out.as_ref())?;
    crate::files::refuse_input(path, &[table.file()])?;
    let tmp = crate::files::temp_path(path)?;
    let r = npy_to(table, &tmp, path, offset)
        .and_then(|()| crate::files::rename_over(&tmp, path).map_err(|e| Error::io(path, e)));
    if r.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    r
}

fn npy_to(table: &StoredTable, tmp: &Path, path: &Path, offset: NodeOffset<'_>) -> Result<()> {
    let h = table.header();
    let f = std::fs::File::create(tmp).map_err(|e| Error::io(path, e))?;
    let mut w = std::io::BufWriter::with_capacity(1 << 20, f);
    let io = |e| Error::io(path, e);
    w.write_all(&npy_header(&h.shape)).map_err(io)?;
    let mut buf = Vec::new();
    if offset.is_none() || Some(h.values) == h.dense_values() {
        if Some(h.values) != h.dense_values() {
            return Err(Error::Unsupported(format!(
                "table `{}` is packed ({} of {:?} values) and no layout was given",
                h.name, h.values, h.shape
            )));
        }
        for i in 0..table.chunk_count() {
            let c = table.decode_chunk(i)?;
            buf.clear();
            for v in c.iter() {
                buf.extend_from_slice(&v.to_le_bytes());
            }
            w.write_all(&buf).map_err(io)?;
        }
        return w.flush().map_err(io);
    }
    let offset = offset.expect("checked");
    let axes: Vec<usize> = h.shape[..h.shape.len() - 1]
        .iter()
        .map(|&d| d as usize)
        .collect();
    let nc = *h.shape.last().expect("non-empty") as usize;
    let nodes: usize = axes.iter().product();
    let mut idx = vec![0usize; axes.len()];
    for _ in 0..nodes {
        match offset(&idx) {
            Some(o) => {
                let (ci, off) = table.locate(o as u64)?;
                let c = table.chunk(ci)?;
                for v in &c[off..off + nc] {
                    buf.extend_from_slice(&v.to_le_bytes());
                }
            }
            None => (0..nc).for_each(|_| buf.extend_from_slice(&f32::NAN.to_le_bytes())),
        }
        if buf.len() > 1 << 20 {
            w.write_all(&buf).map_err(io)?;
            buf.clear();
        }
        for a in (0..axes.len()).rev() {
            idx[a] += 1;
            if idx[a] < axes[a] {
                break;
            }
            idx[a] = 0;
        }
    }
    w.write_all(&buf).map_err(io)?;
    w.flush().map_err(io)
}

/// Which 2D slice of a table to export: the axes along x and y (indices into the stored shape,
/// channels excluded) and a fixed index for every other axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Slice {
    /// The axis along image x.
    pub x: usize,
    /// The axis along image y.
    pub y: usize,
    /// One index per angular axis (those of `x` and `y` are ignored).
    pub fixed: Vec<u64>,
}

impl Slice {
    /// Parses `X,Y[:i0,i1,...]`, e.g. `3,2:45,0,0,0` (x along axis 3, y along axis 2, the other
    /// axes at the given indices; missing indices are 0).
    pub fn parse(s: &str, axes: usize) -> Result<Slice> {
        let err = |m: String| Error::arg("slice", m);
        let (xy, fixed) = s.split_once(':').unwrap_or((s, ""));
        let num = |t: &str| {
            t.trim()
                .parse::<u64>()
                .map_err(|_| err(format!("`{t}` is not an index")))
        };
        let xy: Vec<u64> = xy.split(',').map(num).collect::<Result<_>>()?;
        let [x, y] = xy[..] else {
            return Err(err("expected two axes `X,Y`".into()));
        };
        let mut fixed: Vec<u64> = if fixed.trim().is_empty() {
            vec![]
        } else {
            fixed.split(',').map(num).collect::<Result<_>>()?
        };
        if fixed.len() > axes {
            return Err(err(format!(
                "{} fixed indices for {axes} axes",
                fixed.len()
            )));
        }
        fixed.resize(axes, 0);
        let (x, y) = (x as usize, y as usize);
        if x >= axes || y >= axes || x == y {
            return Err(err(format!(
                "axes {x},{y} must be two different axes below {axes}"
            )));
        }
        Ok(Slice { x, y, fixed })
    }
}

/// Extracts a slice: returns (width, height, values as `[y][x][channel]`). Unstored nodes of
/// packed layouts are NaN.
pub fn slice(
    table: &StoredTable,
    s: &Slice,
    offset: NodeOffset<'_>,
) -> Result<(usize, usize, Vec<f32>)> {
    let h = table.header();
    let (axes, nc) = (
        &h.shape[..h.shape.len() - 1],
        *h.shape.last().unwrap_or(&1) as usize,
    );
    if s.x >= axes.len() || s.y >= axes.len() || s.fixed.len() != axes.len() {
        return Err(Error::arg(
            "slice",
            format!("the table has {} angular axes", axes.len()),
        ));
    }
    for (a, (&i, &d)) in s.fixed.iter().zip(axes).enumerate() {
        if a != s.x && a != s.y && i >= d {
            return Err(Error::arg(
                "slice",
                format!("index {i} of axis {a} is not below its length {d}"),
            ));
        }
    }
    let (w, ht) = (axes[s.x] as usize, axes[s.y] as usize);
    let mut out = vec![f32::NAN; w * ht * nc];
    let mut idx: Vec<usize> = s.fixed.iter().map(|&i| i as usize).collect();
    // A dense table: chunk i is the C-order slab i of axis 0, an array over the other axes and
    // the channels (the same view `Table::view` gives of a whole table).
    let slab: Vec<usize> = axes[1..].iter().map(|&d| d as usize).chain([nc]).collect();
    let mut node = vec![0usize; slab.len()];
    for yy in 0..ht {
        for xx in 0..w {
            idx[s.x] = xx;
            idx[s.y] = yy;
            let o = (yy * w + xx) * nc;
            let Some(f) = offset else {
                let c = table.chunk(idx[0])?;
                let v = ndarray::ArrayViewD::from_shape(ndarray::IxDyn(&slab), &c[..]).map_err(
                    |e| Error::Unsupported(format!("chunk {} as an array: {e}", idx[0])),
                )?;
                node[..idx.len() - 1].copy_from_slice(&idx[1..]);
                for (ch, x) in out[o..o + nc].iter_mut().enumerate() {
                    node[slab.len() - 1] = ch;
                    *x = v[ndarray::IxDyn(&node)];
                }
                continue;
            };
            let Some(flat) = f(&idx) else { continue };
            let (ci, off) = table.locate(flat as u64)?;
            let c = table.chunk(ci)?;
            out[o..o + nc].copy_from_slice(&c[off..off + nc]);
        }
    }
    Ok((w, ht, out))
}

/// Channel names for EXR: `R`, `G`, `B` or `<nm>nm`.
fn channel_names(c: &Channels, n: usize) -> Vec<String> {
    match c {
        Channels::Rgb if n == 3 => vec!["R".into(), "G".into(), "B".into()],
        Channels::Wavelengths(w) if w.len() == n => w.iter().map(|x| format!("{x}nm")).collect(),
        _ => (0..n).map(|i| format!("c{i}")).collect(),
    }
}

/// Writes a 2D slice as OpenEXR, channels as EXR channels, f32 or f16 (`half`), ZIP-compressed,
/// replacing `out` atomically (a temporary file renamed into place, as the other outputs).
/// With `half`, a finite value beyond f16's range (±65504) is an error, not an infinite pixel;
/// a value nearer 0 than half of f16's smallest subnormal (2⁻²⁴ ≈ 6e-8) is written as 0, as
/// f16 must, and counted: the returned number (0 without `half`) says how many nonzero values
/// became 0, so a caller can tell a dark tail that vanished from one that was 0.
pub fn exr(
    table: &StoredTable,
    s: &Slice,
    offset: NodeOffset<'_>,
    out: impl AsRef<Path>,
    half: bool,
) -> Result<usize> {
    use exr::prelude::*;
    let (w, ht, v) = slice(table, s, offset)?;
    let nc = *table.header().shape.last().unwrap_or(&1) as usize;
    if w == 0 || ht == 0 {
        return Err(crate::Error::arg("slice", "empty slice"));
    }
    if half {
        // f16 holds ±65504 at most: a larger value (a grazing or sharp lobe's f_r) became inf.
        if let Some(i) = v
            .iter()
            .position(|&x| x.is_finite() && f16::from_f32(x).is_infinite())
        {
            let (px, c) = (i / nc, i % nc);
            return Err(crate::Error::arg(
                "half",
                format!(
                    "value {} at x = {}, y = {} (channel {c}) is beyond the half float range \
                     (±65504): write the slice as f32",
                    v[i],
                    px % w,
                    px / w
                ),
            ));
        }
    }
    let flushed = if half {
        (v.iter())
            .filter(|&&x| x != 0.0 && f16::from_f32(x) == f16::ZERO)
            .count()
    } else {
        0
    };
    let names = channel_names(&table.header().channels, nc);
    let list: Vec<AnyChannel<FlatSamples>> = (0..nc)
        .map(|c| {
            let plane = v.iter().skip(c).step_by(nc).copied();
            let samples = if half {
                FlatSamples::F16(plane.map(f16::from_f32).collect())
            } else {
                FlatSamples::F32(plane.collect())
            };
            AnyChannel::new(names[c].as_str(), samples)
        })
        .collect();
    let layer = Layer::new(
        (w, ht),
        LayerAttributes::named(table.header().name.as_str()),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list.into()),
    );
    let path = out.as_ref();
    crate::files::refuse_input(path, &[table.file()])?;
    // Encoded in memory (a slice is small) and written as every other output is, through a
    // temporary file renamed into place: `to_file` truncated the old file first, so a kill or
    // a full disk mid-write left a truncated EXR.
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| crate::Error::io(path, std::io::Error::other(e.to_string())))?;
    crate::files::write_atomic(path, bytes.get_ref())?;
    Ok(flushed)
}
