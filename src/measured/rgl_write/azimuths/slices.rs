//! The file of a grid read back: its slices encoded once each and cached, assembled in the
//! file's order.

use std::collections::HashMap;

use rayon::prelude::*;

use crate::brdf::Brdf;
use crate::error::Result;
use crate::measured::RglBrdf;
use crate::measured::rgl_write::elevations::Slice;
use crate::measured::rgl_write::ndf::Ndf;
use crate::measured::rgl_write::{Layout, Progress, values, warps};
use crate::measured::tensor::TensorFile;
use crate::progress::Silent;

/// The file of `base` with azimuths `phi` and elevations `theta`, read back by brdftab's RGL
/// reader; slices not in `cache` are encoded (in parallel) and kept there. Asks `progress` to
/// stop before each slice.
pub(super) fn reader(
    brdf: &dyn Brdf,
    ndf: &Ndf,
    base: &Layout,
    phi: &[f64],
    theta: &[f64],
    cache: &mut HashMap<(u64, u64), Slice>,
    progress: &dyn Progress,
) -> Result<RglBrdf> {
    let plane = base.n * base.n;
    let missing: Vec<(f64, f64)> = phi
        .iter()
        .flat_map(|&p| theta.iter().map(move |&t| (p, t)))
        .filter(|(p, t)| !cache.contains_key(&(p.to_bits(), t.to_bits())))
        .collect();
    let fresh = crate::par::install(|| {
        missing
            .par_iter()
            .map(|&(p, t)| {
                crate::progress::check(progress)?;
                let layout = Layout {
                    theta_i: vec![t as f32],
                    phi_i: vec![p as f32],
                    ..base.clone()
                };
                let w = warps::vndf(ndf, &layout)?;
                let v = values::sample(brdf, ndf, &w, &layout, None, &Silent)?;
                let valid = super::container::unpack_bits(&v.valid, plane);
                Ok((
                    (p.to_bits(), t.to_bits()),
                    Slice {
                        vndf: w.data,
                        values: v.data,
                        valid,
                    },
                ))
            })
            .collect::<Result<Vec<_>>>()
    })?;
    cache.extend(fresh);
    let Encoded { vndf, values } = encoded(phi, theta, cache);
    let layout = Layout {
        theta_i: theta.iter().map(|&t| t as f32).collect(),
        phi_i: phi.iter().map(|&p| p as f32).collect(),
        ..base.clone()
    };
    let fields = super::fields_of(String::new(), &layout, ndf, vndf, values, brdf.channels());
    let tf = TensorFile::from_bytes("(placing azimuths)", fields.to_bytes())?;
    RglBrdf::from_tensor_unhashed(&tf)
}

/// The VNDF slices and values of a grid, in the file's order (φi-major).
pub struct Encoded {
    /// φi × θi × rows × columns.
    pub vndf: Vec<f32>,
    /// The values and their valid bits.
    pub values: super::Values,
}

/// The grid `phi` × `theta` of slices in `cache` (every one of them there).
pub(super) fn encoded(phi: &[f64], theta: &[f64], cache: &HashMap<(u64, u64), Slice>) -> Encoded {
    let slices: Vec<&Slice> = (phi.iter())
        .flat_map(|&p| {
            theta
                .iter()
                .map(move |&t| &cache[&(p.to_bits(), t.to_bits())])
        })
        .collect();
    let valid: Vec<bool> = slices
        .iter()
        .flat_map(|s| s.valid.iter().copied())
        .collect();
    Encoded {
        vndf: slices.iter().flat_map(|s| s.vndf.iter().copied()).collect(),
        values: super::Values {
            data: slices
                .iter()
                .flat_map(|s| s.values.iter().copied())
                .collect(),
            valid: super::container::pack_bits(&valid),
        },
    }
}
