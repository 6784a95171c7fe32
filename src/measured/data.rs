//! Where the measured files that ship with brdftab are found.
//!
//! The project ships the seven RGL-EPFL measurements its tests, benches and demo use in
//! `data/rgl/` (see `data/README.md` for provenance). This module is the one place that looks
//! for them, so a clone standing alone and a checkout beside the shared data behave alike.

use std::path::{Path, PathBuf};

/// The directory of RGL `.bsdf` files: `$BRDFTAB_RGL_DIR` when set, else `data/rgl` of the crate
/// (or of the working directory), else `../shared/data/measured/rgl` beside either; `None` when
/// none exists.
pub fn rgl_dir() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("BRDFTAB_RGL_DIR") {
        return Some(PathBuf::from(p));
    }
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    [
        crate_dir.join("data/rgl"),
        PathBuf::from("data/rgl"),
        crate_dir.join("../shared/data/measured/rgl"),
        PathBuf::from("../shared/data/measured/rgl"),
    ]
    .into_iter()
    .find(|p| p.is_dir())
}
