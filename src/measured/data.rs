//! Where the measured files the project ships live, and where else to look for them.
//!
//! The seven RGL-EPFL `.bsdf` files (CC0) that the tests, benches, examples and the demo use are
//! part of the project, in `data/rgl/` (provenance, SHA-256 and citation in `data/README.md`), so
//! a checkout standing alone finds them. Two other places stay as extra sources: a directory
//! named by `$BRDFTAB_RGL_DIR` (a user's own collection), and `../shared/data/measured/rgl` next to
//! the working directory or to the crate (the layout of the development machine).
//!
//! The search order of [`rgl_dirs`] is:
//!
//! 1. `$BRDFTAB_RGL_DIR`, when set and non-empty (an explicit choice wins);
//! 2. `data/rgl` in the crate's own directory (where this crate was compiled from);
//! 3. `data/rgl` under the working directory;
//! 4. `../shared/data/measured/rgl` under the working directory, then under the crate directory.
//!
//! [`rgl_dir`] is the first of these that exists; [`rgl_file`] the first that holds the named
//! file, so a `$BRDFTAB_RGL_DIR` without the project's files does not hide the shipped copies.
//! Nothing here falls back silently: a file that is nowhere is an [`Error::NotFound`] that lists
//! every place searched.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// The environment variable naming an extra directory of RGL `.bsdf` files.
pub const RGL_DIR_ENV: &str = "BRDFTAB_RGL_DIR";

/// The crate's directory at compile time (holds `data/` in a checkout or a packaged crate).
const CRATE_DIR: &str = env!("CARGO_MANIFEST_DIR");

/// Every directory that may hold RGL `.bsdf` files, in search order (existing or not).
pub fn rgl_dirs() -> Vec<PathBuf> {
    let mut v = Vec::with_capacity(5);
    if let Some(p) = std::env::var_os(RGL_DIR_ENV).filter(|p| !p.is_empty()) {
        v.push(PathBuf::from(p));
    }
    v.extend(data_candidates("rgl"));
    v
}

/// The first directory of [`rgl_dirs`] that exists; `None` when none does.
pub fn rgl_dir() -> Option<PathBuf> {
    rgl_dirs().into_iter().find(|p| p.is_dir())
}

/// The path of the RGL file `name` (e.g. `paper_white_rgb.bsdf`) in the first directory of
/// [`rgl_dirs`] that holds it.
///
/// # Errors
/// [`Error::NotFound`] naming every directory searched when none holds it.
pub fn rgl_file(name: &str) -> Result<PathBuf> {
    find(name, rgl_dirs())
}

/// The path of the MERL companion file `name` (the manifest `merl_expected_files.tsv`, the
/// database's readme) in `data/merl` (crate directory, then working directory) or
/// `../shared/data/measured/merl`.
///
/// # Errors
/// [`Error::NotFound`] naming every directory searched when none holds it.
pub fn merl_file(name: &str) -> Result<PathBuf> {
    find(name, data_candidates("merl"))
}

/// `data/<kind>` under the crate and the working directory, then the shared layout.
fn data_candidates(kind: &str) -> Vec<PathBuf> {
    let shipped = Path::new("data").join(kind);
    let shared = Path::new("../shared/data/measured").join(kind);
    vec![
        Path::new(CRATE_DIR).join(&shipped),
        shipped,
        shared.clone(),
        Path::new(CRATE_DIR).join(shared),
    ]
}

fn find(name: &str, dirs: Vec<PathBuf>) -> Result<PathBuf> {
    if let Some(p) = dirs.iter().map(|d| d.join(name)).find(|p| p.is_file()) {
        return Ok(p);
    }
    let searched: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
    Err(Error::NotFound(format!(
        "measured data file {name}: not in any of {}",
        searched.join(", ")
    )))
}

/// The `.bsdf` files of `dir`, sorted.
pub fn rgl_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let mut v: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "bsdf"))
        .collect();
    v.sort();
    if v.is_empty() {
        return Err(Error::NotFound(format!(
            "{}: no .bsdf files",
            dir.display()
        )));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_files_are_found() {
        for f in [
            "cc_ibiza_sunset_rgb.bsdf",
            "cc_iris_purple_gem_rgb.bsdf",
            "cg_sunflower_rgb.bsdf",
            "colodur_napoli_4f_rgb.bsdf",
            "paper_white_rgb.bsdf",
            "satin_rosaline_rgb.bsdf",
            "vch_golden_yellow_rgb.bsdf",
            "reference_eval_powitacq_rgb.tsv",
        ] {
            let p = rgl_file(f).unwrap();
            assert!(p.is_file(), "{}", p.display());
        }
        assert!(merl_file("merl_expected_files.tsv").unwrap().is_file());
        // The project's own copy is among the candidates right after the environment's.
        let own = Path::new(CRATE_DIR).join("data/rgl");
        assert!(own.join("paper_white_rgb.bsdf").is_file());
        assert!(rgl_dirs().contains(&own));
    }

    #[test]
    fn a_missing_file_names_the_places_searched() {
        let e = rgl_file("no_such_material.bsdf").unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, Error::NotFound(_)), "{msg}");
        assert!(
            msg.contains("no_such_material.bsdf")
                && msg.contains(&Path::new("data").join("rgl").display().to_string()),
            "{msg}"
        );
    }
}
