//! Measured BRDF data: MERL and RGL-EPFL readers.
