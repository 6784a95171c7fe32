//! Measured BRDF data: MERL and RGL-EPFL readers.
//!
//! - [`tensor`]: the RGL tensor-file container (bounds-checked reader of every dtype, and a
//!   writer used by tests to build small or deliberately broken files);
//! - [`rgl`]: RGL-EPFL `.bsdf` measurements evaluated natively by the published algorithm
//!   ([`RglBrdf`], RGB or spectral, isotropic or anisotropic), with importance sampling by the
//!   measurement's own warps;
//! - [`rgl_normal`]: an isotropic RGL file made continuous at normal incidence, which is
//!   what a bake samples (the reader's limit there depends on the approach direction);
//! - [`rgl_write`]: any `Brdf` written as an RGL `.bsdf` file (the adaptive parameterization
//!   rebuilt from the source: NDF by power iteration, warps, values), with its error report;
//! - [`merl`]: MERL `.binary` files, read (the reference reader's nearest lookup, a validity
//!   mask for unmeasured cells), written (bit-exact, or any `Brdf` resampled on the MERL grid)
//!   and turned into a table on [`Grid::merl`](crate::table::Grid::merl) ([`MerlBrdf`]);
//! - [`data`]: where the measured files the project ships (`data/rgl`, `data/merl`) and any
//!   extra copies are found;
//! - [`merl_manifest`]: the SHA-256 of the 100 published MERL files, to name a file a user
//!   brings.
//!
//! Both readers load a file completely at open (MERL: 35 MB in ≈ 0.1 s; RGL: 0.66–1.06 MB for
//! the shipped files, up to 32 MiB for one `convert` writes with its default layout) and never
//! allocate in `eval`. Slice images of any source live in
//! `brdftab_tools::preview::slice`.

pub mod data;
pub mod info;
pub mod merl;
pub mod merl_manifest;
pub mod merl_resample;
pub mod rgl;
pub mod rgl_normal;
pub mod rgl_write;
pub mod tensor;

pub use merl::MerlBrdf;
pub use rgl::RglBrdf;
