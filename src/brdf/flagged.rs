//! Batches of draws with each draw's delta flag, what a host's renderer needs to tell delta
//! draws from smooth ones ([`sample_flagged`], [`sample_flagged_at`]).

use glam::{DVec2, DVec3};

use super::{Brdf, BrdfSample};

/// One block of [`sample_flagged`]'s outputs, numbered: (block, (((wi, pdf), weights), flags)).
type FlaggedBlock<'a> = (
    usize,
    (
        ((&'a mut [DVec3], &'a mut [f64]), &'a mut [f32]),
        &'a mut [bool],
    ),
);

/// [`Brdf::sample_batch`] and each draw's delta flag:
/// `delta[k]` is true where pair `k` drew a delta lobe (a mirror, or a sum's mirror term: its
/// pdf is then the probability of choosing that lobe, not a density, and
/// [`Brdf::pdf`] does not contain it). What a host's renderer needs to
/// tell such draws from smooth ones (pbrt's `BSDFSample::flags`, Mitsuba's `sampled_type`).
/// Sources without a delta lobe take `sample_batch` (a table's batch path) and flag nothing.
///
/// # Panics
///
/// If the lengths do not match `wo.len()` pairs.
pub fn sample_flagged<B: Brdf + ?Sized>(
    brdf: &B,
    wo: &[DVec3],
    u: &[DVec2],
    out: crate::batch::SampleOut<'_>,
    delta: &mut [bool],
) {
    let n = wo.len();
    assert_eq!(
        delta.len(),
        n,
        "sample_flagged: {n} wo and {} flags",
        delta.len()
    );
    if !brdf.flags().lobes.delta {
        delta.fill(false);
        return brdf.sample_batch(wo, u, out);
    }
    let c = brdf.channels().len().max(1);
    flagged_blocks(c, wo, u, out, delta, |wo, u, w| brdf.sample(wo, u, w));
}

/// [`sample_flagged`] with the weights at the wavelengths `nm` ([`Brdf::sample_wavelengths`]):
/// `out.weight` holds `nm.len()` values per pair. The same draws and flags as
/// [`sample_flagged`]; what a spectral renderer with wavelengths of its own per path (pbrt-v4's
/// sampled wavelengths) calls.
///
/// # Panics
///
/// If the lengths do not match `wo.len()` pairs of `nm.len()` weights.
pub fn sample_flagged_at<B: Brdf + ?Sized>(
    brdf: &B,
    wo: &[DVec3],
    u: &[DVec2],
    nm: &[f64],
    out: crate::batch::SampleOut<'_>,
    delta: &mut [bool],
) {
    flagged_blocks(nm.len(), wo, u, out, delta, |wo, u, w| {
        brdf.sample_wavelengths(wo, u, nm, w)
    });
}

/// Draws pair by pair with `draw(wo, u, weights)` (`width` weights a pair) into `out` and each
/// draw's delta flag into `delta`, in blocks, on the library's pool from
/// [`crate::batch::PARALLEL`] pairs on: [`sample_flagged`]'s and [`sample_flagged_at`]'s loop.
fn flagged_blocks(
    width: usize,
    wo: &[DVec3],
    u: &[DVec2],
    out: crate::batch::SampleOut<'_>,
    delta: &mut [bool],
    draw: impl Fn(DVec3, DVec2, &mut [f32]) -> Option<BrdfSample> + Sync,
) {
    use crate::batch::{BLOCK, PARALLEL, SampleOut, drawable, no_sample};
    use rayon::prelude::*;
    let n = wo.len();
    let SampleOut { wi, pdf, weight } = out;
    assert!(
        u.len() == n
            && wi.len() == n
            && pdf.len() == n
            && weight.len() == n * width
            && delta.len() == n,
        "sample_flagged: {n} wo, {} u, {} wi, {} pdf, {} weights ({width} a pair) and {} flags \
         do not match",
        u.len(),
        wi.len(),
        pdf.len(),
        weight.len(),
        delta.len()
    );
    let go = |(b, (((wi, p), w), d)): FlaggedBlock<'_>| {
        for j in 0..wi.len() {
            let (wo, u) = (wo[b * BLOCK + j], u[b * BLOCK + j]);
            let w = &mut w[j * width..(j + 1) * width];
            let drawn = match drawable(wo, u) {
                true => draw(wo, u, w),
                false => None,
            };
            match drawn {
                Some(s) => (wi[j], p[j], d[j]) = (s.wi, s.pdf, s.delta),
                None => {
                    no_sample(&mut wi[j], &mut p[j], w);
                    d[j] = false;
                }
            }
        }
    };
    if width == 0 {
        // No weights (zero wavelengths): `chunks_mut` of the empty weights yields no block at
        // all, and zipped with it nothing would be drawn; each block of pairs gets no weights.
        fn none<'a>(_: ()) -> &'a mut [f32] {
            &mut []
        }
        if n >= PARALLEL {
            crate::par::install(|| {
                wi.par_chunks_mut(BLOCK)
                    .zip(pdf.par_chunks_mut(BLOCK))
                    .zip(rayon::iter::repeat_n((), n.div_ceil(BLOCK)).map(none))
                    .zip(delta.par_chunks_mut(BLOCK))
                    .enumerate()
                    .for_each(go)
            });
        } else {
            wi.chunks_mut(BLOCK)
                .zip(pdf.chunks_mut(BLOCK))
                .zip(std::iter::repeat(()).map(none))
                .zip(delta.chunks_mut(BLOCK))
                .enumerate()
                .for_each(go);
        }
    } else if n >= PARALLEL {
        crate::par::install(|| {
            wi.par_chunks_mut(BLOCK)
                .zip(pdf.par_chunks_mut(BLOCK))
                .zip(weight.par_chunks_mut(BLOCK * width))
                .zip(delta.par_chunks_mut(BLOCK))
                .enumerate()
                .for_each(go)
        });
    } else {
        wi.chunks_mut(BLOCK)
            .zip(pdf.chunks_mut(BLOCK))
            .zip(weight.chunks_mut(BLOCK * width))
            .zip(delta.chunks_mut(BLOCK))
            .enumerate()
            .for_each(go);
    }
}
