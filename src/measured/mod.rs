//! Measured BRDF data: MERL and RGL-EPFL readers.
//!
//! - [`tensor`]: the RGL tensor-file container (bounds-checked reader, writer for tests);
//! - [`rgl`]: RGL-EPFL `.bsdf` measurements evaluated natively ([`RglBrdf`]);
//! - [`merl`]: MERL `.binary` files, read and write ([`MerlBrdf`]); [`merl_manifest`]: the
//!   SHA-256 of the 100 published files.

pub mod rgl;
pub mod tensor;

pub use rgl::RglBrdf;
pub mod merl;
pub mod merl_manifest;

pub use merl::MerlBrdf;
