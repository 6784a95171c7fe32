//! Reading what the format's records point at, checked: a block's bytes against its range and
//! checksum, JSON records, and a table's header against its chunk index.

use super::{
    Block, ChunkEntry, INDEX_ENTRY_LEN, MAX_CHUNK_VALUES, MAX_VALUES, MAX_VALUES_PER_BYTE,
    SUPERBLOCK_LEN, TableHeader, xxh3,
};
use crate::error::{Error, Result, Section};

/// Returns the bytes of `block`, checking it lies inside `data` (after the superblock) and its
/// checksum matches.
pub fn block<'a>(
    file: &str,
    data: &'a [u8],
    block: &Block,
    what: &Section,
    max: u64,
) -> Result<&'a [u8]> {
    check_range(file, data.len() as u64, block, what, max)?;
    let b = &data[block.offset as usize..(block.offset + block.len) as usize];
    check_sum(file, b, block, what)?;
    Ok(b)
}

/// Checks that `block` lies inside a file of `file_len` bytes, after the superblock, and is at
/// most `max` bytes long.
pub fn check_range(
    file: &str,
    file_len: u64,
    block: &Block,
    what: &Section,
    max: u64,
) -> Result<()> {
    let end = block.offset.checked_add(block.len);
    match end {
        Some(end) if block.offset >= SUPERBLOCK_LEN as u64 && end <= file_len => {}
        _ => {
            return Err(Error::format(
                file,
                Some(&what.to_string()),
                Some(block.offset),
                format!(
                    "range {}+{} lies outside the file ({} bytes)",
                    block.offset, block.len, file_len
                ),
            ));
        }
    }
    if block.len > max {
        return Err(Error::format(
            file,
            Some(&what.to_string()),
            Some(block.offset),
            format!("{} bytes is more than the {max} allowed", block.len),
        ));
    }
    Ok(())
}

/// Checks the bytes `b` read for `block` against its checksum.
pub fn check_sum(file: &str, b: &[u8], block: &Block, what: &Section) -> Result<()> {
    let computed = xxh3(b);
    if computed != block.xxh3 {
        return Err(Error::Checksum {
            file: file.into(),
            what: what.clone(),
            stored: block.xxh3,
            computed,
        });
    }
    Ok(())
}

/// Parses JSON from a file block, naming the file and block on error.
pub fn json<T: serde::de::DeserializeOwned>(file: &str, what: &str, b: &[u8]) -> Result<T> {
    serde_json::from_slice(b).map_err(|e| Error::Json {
        context: format!("{file}: {what}"),
        source: e,
    })
}

/// Checks a table header and its chunk index against each other and the file; returns the index.
pub fn check_table(
    file: &str,
    data_len: u64,
    h: &TableHeader,
    index: &[u8],
    n: u64,
) -> Result<Vec<ChunkEntry>> {
    let what = |f: &str| format!("table `{}` {f}", h.name);
    let err = |f: &str, msg: String| Error::format(file, Some(&what(f)), None, msg);
    let dense = h.dense_values().unwrap_or(u64::MAX);
    // Packed layouts store at least half of the dense shape; chunks are slabs of axis 0.
    if h.shape.is_empty()
        || h.values > MAX_VALUES
        || h.values > dense
        || dense / 2 > h.values
        || h.shape[0] != n
    {
        return Err(err(
            "shape",
            format!(
                "{:?} / {} values: empty, inconsistent or more than {MAX_VALUES}",
                h.shape, h.values
            ),
        ));
    }
    if index.len() as u64 != n.saturating_mul(INDEX_ENTRY_LEN as u64) || n > h.values.max(1) {
        return Err(err(
            "index",
            format!(
                "{n} chunks in an index of {} bytes for {} values",
                index.len(),
                h.values
            ),
        ));
    }
    let mut out = Vec::with_capacity(n as usize);
    let mut sum = 0u64;
    for (i, b) in index.chunks_exact(INDEX_ENTRY_LEN).enumerate() {
        let e = ChunkEntry::read(b);
        let ok_range = e
            .offset
            .checked_add(e.len)
            .is_some_and(|end| e.offset >= SUPERBLOCK_LEN as u64 && end <= data_len);
        if !ok_range {
            return Err(err(
                &format!("chunk {i}"),
                format!(
                    "range {}+{} lies outside the file ({data_len} bytes)",
                    e.offset, e.len
                ),
            ));
        }
        if e.values > MAX_CHUNK_VALUES || e.values > e.len.saturating_mul(MAX_VALUES_PER_BYTE) {
            return Err(err(
                &format!("chunk {i}"),
                format!("claims {} values in {} bytes", e.values, e.len),
            ));
        }
        sum += e.values;
        out.push(e);
    }
    if sum != h.values {
        return Err(err(
            "index",
            format!("chunks hold {sum} values, the header says {}", h.values),
        ));
    }
    Ok(out)
}
