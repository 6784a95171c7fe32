//! What a request asks for, as hosts spell it: the grid ([`GridChoice`]), the symmetry
//! ([`SymmetryChoice`]) and where the table goes ([`BakeTarget`]), each parsed from the strings
//! the CLI, Python and C hosts pass. Plain values: nothing here opens a source or bakes.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::table::Symmetry;
use crate::table::presets::Preset;

/// The grid a bake samples on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GridChoice {
    /// The source's natural grid: a MERL file's own cells for MERL sources, for RGL files the
    /// smallest adaptive grid ([`GridChoice::Adaptive`]) that meets [`MEASURED_TARGET_ERROR`](super::MEASURED_TARGET_ERROR)
    /// (the medium preset when the file is not isotropic and bilateral within
    /// [`MEASURED_BILATERAL_TOLERANCE`](super::MEASURED_BILATERAL_TOLERANCE)), the medium preset otherwise — but for a model whose
    /// medium table misses its albedo by more than [`PRESET_ALBEDO_TOLERANCE`](super::PRESET_ALBEDO_TOLERANCE), the adaptive
    /// grid of [`MODEL_FALLBACK_TARGET_ERROR`](super::MODEL_FALLBACK_TARGET_ERROR), calibrated (isotropic, bilateral models), or
    /// the medium table calibrated, whichever the check takes. With an error target
    /// ([`BakeRequest::target_error`](super::BakeRequest::target_error)) any source gets the adaptive grid that meets it.
    #[default]
    Default,
    /// A size preset.
    Preset(Preset),
    /// Full axis sizes θ1 × φ1 × θ2 × φ2 (halfdiff: sqrt θh, uniform θd; inout: uniform).
    Sizes([usize; 4]),
    /// The MERL grid (90 θh × 90 θd × 180 φd cell centres). A MERL source keeps its cells.
    Merl,
    /// An adaptive `halfdiff` grid ([`crate::table::adaptive`]): θh, θd and φd warped by the
    /// source's own variation, with these node counts (θh, θd, stored φd), or without them
    /// the counts an error target picks ([`crate::table::target`]) or else
    /// [`adaptive::DEFAULT_NODES`](crate::table::adaptive::DEFAULT_NODES).
    Adaptive(Option<[usize; 3]>),
}

impl std::str::FromStr for GridChoice {
    type Err = crate::Error;

    /// Parses `small`/`medium`/`large`, `merl`, sizes `θ1xφ1xθ2xφ2`, `adaptive` or
    /// `adaptive:NHxNDxNP` (θh, θd and stored φd nodes).
    fn from_str(s: &str) -> std::result::Result<Self, crate::Error> {
        let t = s.trim().to_ascii_lowercase();
        if let Some(rest) = t.strip_prefix("adaptive") {
            let Some(n) = rest.strip_prefix(':') else {
                return if rest.is_empty() {
                    Ok(GridChoice::Adaptive(None))
                } else {
                    Err(Error::arg(
                        "grid",
                        format!("`{s}`: expected adaptive[:NHxNDxNP]"),
                    ))
                };
            };
            let v = sizes(n)?;
            let n: [usize; 3] = v.try_into().map_err(|_| {
                Error::arg(
                    "grid",
                    format!("`{s}`: expected adaptive:NHxNDxNP (three sizes)"),
                )
            })?;
            return Ok(GridChoice::Adaptive(Some(n)));
        }
        match t.as_str() {
            "merl" => Ok(GridChoice::Merl),
            "default" => Ok(GridChoice::Default),
            "small" | "medium" | "large" => Ok(GridChoice::Preset(t.parse::<Preset>()?)),
            _ => {
                let v = sizes(&t)?;
                let sizes: [usize; 4] = v.try_into().map_err(|_| {
                    Error::arg(
                        "grid",
                        format!("`{s}`: expected four sizes θ1xφ1xθ2xφ2, merl, or a preset"),
                    )
                })?;
                Ok(GridChoice::Sizes(sizes))
            }
        }
    }
}

/// `AxBxC…` as sizes.
fn sizes(t: &str) -> Result<Vec<usize>> {
    t.split(['x', '×'])
        .map(|x| {
            x.trim()
                .parse::<usize>()
                .map_err(|_| Error::arg("grid", format!("`{x}` is not a size")))
        })
        .collect()
}

/// The symmetry a bake reduces by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SymmetryChoice {
    /// Detect the symmetries the source meets within the symmetry tolerance.
    #[default]
    Auto,
    /// Exactly these (verified against the source unless forced).
    Exactly(Symmetry),
    /// What the source declares ([`Symmetry::from_flags`]), not verified: for measured data,
    /// which declares the symmetries of the material but meets them only up to noise.
    Declared,
}

impl std::str::FromStr for SymmetryChoice {
    type Err = crate::Error;

    /// Parses `auto`, `declared`, `none`, `all` or a list of `isotropic,reciprocal,bilateral`.
    fn from_str(s: &str) -> std::result::Result<Self, crate::Error> {
        match s.trim() {
            "auto" => Ok(SymmetryChoice::Auto),
            "declared" => Ok(SymmetryChoice::Declared),
            s => Ok(SymmetryChoice::Exactly(s.parse::<Symmetry>()?)),
        }
    }
}

/// Where a bake writes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BakeTarget {
    /// A single-table brdftab file, replaced atomically.
    File(PathBuf),
    /// Table `name` of database `path` (created if absent).
    Db {
        /// The database file.
        path: PathBuf,
        /// The table's name.
        name: String,
        /// Replace a table of that name (otherwise an existing name is an error).
        replace: bool,
    },
    /// A raw (uncompressed f32) table file.
    Raw(PathBuf),
    /// A MERL `.binary` file: the source resampled as MERL cell means, in RGB (the grid,
    /// symmetry and codec of the request do not apply; the format fixes them).
    Merl(PathBuf),
}

impl BakeTarget {
    /// A single-table file.
    pub fn file(path: impl Into<PathBuf>) -> BakeTarget {
        BakeTarget::File(path.into())
    }

    /// A new table of a database.
    pub fn db(path: impl Into<PathBuf>, name: impl Into<String>) -> BakeTarget {
        BakeTarget::Db {
            path: path.into(),
            name: name.into(),
            replace: false,
        }
    }

    /// Reads an output string the way `convert` does: `DB#NAME` is a database entry, a `.btdb`
    /// file a single-table file (or, with `name`, an entry of that database), anything else a
    /// raw table file. The output need not be UTF-8 (a file name is bytes): `DB#NAME` is split
    /// on its bytes ([`crate::store::name::parse_output_os`]).
    pub fn parse(
        output: impl AsRef<OsStr>,
        name: Option<&str>,
        replace: bool,
    ) -> Result<BakeTarget> {
        let (path, entry) = crate::store::name::parse_output_os("output", output.as_ref())?;
        let btdb = path.as_os_str().as_encoded_bytes();
        let btdb = btdb.len() >= 5 && btdb[btdb.len() - 5..].eq_ignore_ascii_case(b".btdb");
        Ok(match (entry.or(name), btdb) {
            (Some(n), _) => BakeTarget::Db {
                path: path.into(),
                name: n.into(),
                replace,
            },
            (None, true) => BakeTarget::File(path.into()),
            (None, false) => BakeTarget::Raw(path.into()),
        })
    }

    /// The file written.
    pub fn path(&self) -> &Path {
        match self {
            BakeTarget::File(p)
            | BakeTarget::Raw(p)
            | BakeTarget::Merl(p)
            | BakeTarget::Db { path: p, .. } => p,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_choice_parses() {
        assert_eq!("merl".parse::<GridChoice>().unwrap(), GridChoice::Merl);
        assert_eq!(
            "90x1x90x180".parse::<GridChoice>().unwrap(),
            GridChoice::Sizes([90, 1, 90, 180])
        );
        assert_eq!(
            "small".parse::<GridChoice>().unwrap(),
            GridChoice::Preset(Preset::Small)
        );
        assert!(matches!(
            "90x1x90".parse::<GridChoice>(),
            Err(Error::InvalidArgument { .. })
        ));
        assert_eq!(
            "adaptive".parse::<GridChoice>().unwrap(),
            GridChoice::Adaptive(None)
        );
        assert_eq!(
            "Adaptive:96x48x25".parse::<GridChoice>().unwrap(),
            GridChoice::Adaptive(Some([96, 48, 25]))
        );
        for bad in ["adaptive:96x48", "adaptivex", "adaptive:", "adaptive:axbxc"] {
            assert!(
                matches!(
                    bad.parse::<GridChoice>(),
                    Err(Error::InvalidArgument { .. })
                ),
                "{bad}"
            );
        }
    }

    #[test]
    fn targets_parse_like_convert() {
        assert_eq!(
            BakeTarget::parse("a.btdb#x", None, false).unwrap(),
            BakeTarget::db("a.btdb", "x")
        );
        assert_eq!(
            BakeTarget::parse("a.btdb", None, false).unwrap(),
            BakeTarget::file("a.btdb")
        );
        assert_eq!(
            BakeTarget::parse("a.tbl", None, false).unwrap(),
            BakeTarget::Raw("a.tbl".into())
        );
        assert!(matches!(
            BakeTarget::parse("a.btdb#", None, false),
            Err(Error::InvalidArgument { ref name, .. }) if name == "output"
        ));
    }
}
