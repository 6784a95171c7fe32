//! The superblock: the file's first 64 bytes, written last and checked first, that locate and
//! checksum the table of contents.

use super::{Block, MAGIC, SUPERBLOCK_LEN, VERSION, xxh3};
use crate::error::{Error, Result, Section};

/// The decoded superblock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Superblock {
    /// Format version.
    pub version: u32,
    /// The TOC block.
    pub toc: Block,
    /// The file length the writer produced.
    pub file_len: u64,
}

impl Superblock {
    /// Serializes into [`SUPERBLOCK_LEN`] bytes.
    pub fn to_bytes(&self) -> [u8; SUPERBLOCK_LEN] {
        let mut b = [0u8; SUPERBLOCK_LEN];
        b[0..8].copy_from_slice(&MAGIC);
        b[8..12].copy_from_slice(&self.version.to_le_bytes());
        b[16..24].copy_from_slice(&self.toc.offset.to_le_bytes());
        b[24..32].copy_from_slice(&self.toc.len.to_le_bytes());
        b[32..40].copy_from_slice(&self.toc.xxh3.to_le_bytes());
        b[40..48].copy_from_slice(&self.file_len.to_le_bytes());
        let h = xxh3(&b[0..56]);
        b[56..64].copy_from_slice(&h.to_le_bytes());
        b
    }

    /// Parses and checks the superblock of a file of `data.len()` bytes.
    pub fn parse(file: &str, data: &[u8]) -> Result<Superblock> {
        Self::parse_head(file, data, data.len() as u64)
    }

    /// Parses and checks the superblock from `head`, the first bytes (at least the
    /// superblock's, or the whole file if shorter) of a file of `file_len` bytes.
    pub fn parse_head(file: &str, head: &[u8], file_len: u64) -> Result<Superblock> {
        let data = head;
        if data.len() < 8 || data[0..8] != MAGIC {
            let what = if data.len() < 8 && MAGIC.starts_with(data) {
                "truncated before the end of the magic"
            } else {
                "not a brdftab file (wrong magic)"
            };
            return Err(Error::format(file, Some("magic"), Some(0), what));
        }
        if data.len() < SUPERBLOCK_LEN {
            return Err(Error::format(
                file,
                Some("superblock"),
                Some(data.len() as u64),
                format!(
                    "truncated: {} bytes, the superblock alone is {SUPERBLOCK_LEN}",
                    data.len()
                ),
            ));
        }
        let u64_at = |o: usize| u64::from_le_bytes(data[o..o + 8].try_into().expect("8 bytes"));
        let version = u32::from_le_bytes(data[8..12].try_into().expect("4 bytes"));
        let stored = u64_at(56);
        let computed = xxh3(&data[0..56]);
        if stored != computed {
            return Err(Error::Checksum {
                file: file.into(),
                what: Section::Superblock,
                stored,
                computed,
            });
        }
        if version > VERSION {
            return Err(Error::format(
                file,
                Some("version"),
                Some(8),
                format!(
                    "format version {version} is newer than this build reads ({VERSION}); upgrade brdftab"
                ),
            ));
        }
        if version == 0 {
            return Err(Error::format(
                file,
                Some("version"),
                Some(8),
                "format version 0",
            ));
        }
        let sb = Superblock {
            version,
            toc: Block {
                offset: u64_at(16),
                len: u64_at(24),
                xxh3: u64_at(32),
            },
            file_len: u64_at(40),
        };
        if sb.file_len != file_len {
            return Err(Error::format(
                file,
                Some("file length"),
                Some(40),
                format!(
                    "the file is {file_len} bytes but was written as {} (truncated or appended \
                     to)",
                    sb.file_len
                ),
            ));
        }
        Ok(sb)
    }
}
