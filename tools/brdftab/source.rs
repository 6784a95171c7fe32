//! SOURCE arguments: thin over [`brdftab::source`], the library's one place that knows the
//! kinds (opening goes through [`brdftab::request::open`]). This module only adds the
//! directory search behind `--rgl`.

pub use brdftab::source::{SourceKind as Kind, classify as kind};

/// The directory of RGL `.bsdf` files used by `demo` and `accuracy`: `--rgl DIR`, else the
/// library's search ([`brdftab::measured::data::rgl_dir`]: `$BRDFTAB_RGL_DIR`, the shipped
/// `data/rgl`, `../shared/data/measured/rgl`); `None` when none exists.
pub fn rgl_dir(arg: Option<&std::path::Path>) -> Option<std::path::PathBuf> {
    match arg {
        Some(p) => Some(p.to_path_buf()),
        None => brdftab::measured::data::rgl_dir(),
    }
}
