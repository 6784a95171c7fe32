//! The fields of a `.bsdf` file and their layout in the tensor container, in the order and with
//! the dtypes of the published files: `version: u32[2] = {1, 0}`, `description: u8[len]`,
//! `phi_i: f32[φi]`, `theta_i: f32[θi]`, `sigma` and `ndf: f32[rows, cols]`,
//! `vndf: f32[φi, θi, n, n]`, `luminance: f32[φi, θi, N, N]`, `rgb: f32[φi, θi, 3, N, N]` (or
//! `spectra: f32[φi, θi, λ, N, N]` followed by `wavelengths: f32[λ]`), `jacobian: u8[1] = 1`,
//! `valid: u8[bytes]`.

use crate::measured::tensor::{Dtype, TensorWriter};

/// Every field of a `.bsdf` file, as [`encode`](super::encode) computed them.
#[derive(Debug, Clone, PartialEq)]
pub struct Fields {
    /// The `description` text.
    pub description: String,
    /// Incident azimuths (radians).
    pub phi_i: Vec<f32>,
    /// Incident elevations (radians).
    pub theta_i: Vec<f32>,
    /// Shape of `ndf` and `sigma`: [rows (φ), columns (θ)].
    pub ndf_shape: [usize; 2],
    /// Projected area σ(ω) on the (θ, φ) unit square.
    pub sigma: Vec<f32>,
    /// The microfacet distribution D on the (θ, φ) unit square (∫ D cos θ dω = 1).
    pub ndf: Vec<f32>,
    /// Shape of one VNDF slice: [rows (φ), columns (θ)].
    pub vndf_shape: [usize; 2],
    /// The visible-normal densities, φi × θi × rows × columns.
    pub vndf: Vec<f32>,
    /// The luminance of the stored values, φi × θi × N × N.
    pub luminance: Vec<f32>,
    /// Reflectance table resolution N.
    pub n: usize,
    /// The stored values (f_r·cos θo · 4σ/D), φi × θi × channels × N × N.
    pub values: Vec<f32>,
    /// One bit per sample (1: ωo above the horizon), packed most significant bit first.
    pub valid: Vec<u8>,
    /// `None` for RGB (`rgb` field), else the wavelengths in nm (`spectra` + `wavelengths`).
    pub wavelengths: Option<Vec<f32>>,
}

impl Fields {
    /// Number of channels stored.
    pub fn channels(&self) -> usize {
        self.wavelengths.as_ref().map_or(3, |w| w.len())
    }

    /// The container's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let (np, nt) = (self.phi_i.len() as u64, self.theta_i.len() as u64);
        let n = self.n as u64;
        let [vr, vc] = self.vndf_shape.map(|d| d as u64);
        let [nr, nc] = self.ndf_shape.map(|d| d as u64);
        let version: Vec<u8> = [1u32, 0].iter().flat_map(|v| v.to_le_bytes()).collect();
        let desc = self.description.as_bytes();
        let mut w = TensorWriter::new()
            .raw("version", Dtype::U32, &[2], version)
            .u8("description", &[desc.len() as u64], desc)
            .f32("phi_i", &[np], &self.phi_i)
            .f32("theta_i", &[nt], &self.theta_i)
            .f32("sigma", &[nr, nc], &self.sigma)
            .f32("ndf", &[nr, nc], &self.ndf)
            .f32("vndf", &[np, nt, vr, vc], &self.vndf)
            .f32("luminance", &[np, nt, n, n], &self.luminance);
        let nch = self.channels() as u64;
        w = match &self.wavelengths {
            None => w.f32("rgb", &[np, nt, nch, n, n], &self.values),
            Some(wl) => {
                w.f32("spectra", &[np, nt, nch, n, n], &self.values)
                    .f32("wavelengths", &[nch], wl)
            }
        };
        w.u8("jacobian", &[1], &[1])
            .u8("valid", &[self.valid.len() as u64], &self.valid)
            .to_bytes()
    }
}

/// Packs bits most significant first (numpy's `packbits` order), padding the last byte with 0.
pub fn pack_bits(bits: &[bool]) -> Vec<u8> {
    bits.chunks(8)
        .map(|c| {
            c.iter()
                .enumerate()
                .fold(0u8, |b, (i, &on)| if on { b | (0x80 >> i) } else { b })
        })
        .collect()
}

/// The first `len` bits of [`pack_bits`]' bytes.
pub fn unpack_bits(bytes: &[u8], len: usize) -> Vec<bool> {
    (0..len)
        .map(|i| bytes.get(i / 8).is_some_and(|b| b & (0x80 >> (i % 8)) != 0))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_pack_most_significant_first() {
        let b = [true, false, false, false, false, false, true, true, true];
        assert_eq!(pack_bits(&b), [0b1000_0011, 0b1000_0000]);
        assert_eq!(unpack_bits(&pack_bits(&b), b.len()), b);
    }
}
