//! Many pairs at once: the batch forms of `pdf` and `sample` that every host calls.
//!
//! Why a module: the C ABI and the Python package both take arrays of directions from their
//! caller and used to loop over them each in its own way (the C ABI sequentially, Python on
//! rayon after copying the arrays). One implementation here — blocks of [`BLOCK`] pairs, on
//! the library's fork-safe pool ([`crate::par`]) from [`PARALLEL`] pairs on, the NaN rule of
//! every host applied once — makes a host's rate the library's rate. The trait's batch methods
//! ([`Brdf::eval_batch`], [`Brdf::pdf_batch`], [`Brdf::sample_batch`]) run on these blocks; this
//! module knows nothing of the trait, so that it and [`crate::brdf`] import each other in no
//! circle.
//!
//! [`Brdf::eval_batch`]: crate::brdf::Brdf::eval_batch
//! [`Brdf::pdf_batch`]: crate::brdf::Brdf::pdf_batch
//! [`Brdf::sample_batch`]: crate::brdf::Brdf::sample_batch

use glam::{DVec2, DVec3};
use rayon::prelude::*;

/// Pairs per block handed to one rayon task.
pub const BLOCK: usize = 4096;

/// Batches at least this large run on the library's pool; smaller ones on the calling thread.
pub const PARALLEL: usize = 4 * BLOCK;

/// Runs `f(start, block)` over consecutive blocks of at most [`BLOCK`] pairs of `out`
/// (`width` values per pair), in parallel from [`PARALLEL`] pairs on.
pub fn blocks<T: Send>(out: &mut [T], width: usize, f: impl Fn(usize, &mut [T]) + Sync + Send) {
    let width = width.max(1);
    let n = out.len() / width;
    let go = |(b, o): (usize, &mut [T])| f(b * BLOCK, o);
    if n >= PARALLEL {
        crate::par::install(|| out.par_chunks_mut(BLOCK * width).enumerate().for_each(go));
    } else {
        out.chunks_mut(BLOCK * width).enumerate().for_each(go);
    }
}

/// The outputs of [`Brdf::sample_batch`](crate::brdf::Brdf::sample_batch): one row per pair.
pub struct SampleOut<'a> {
    /// Drawn incident directions (0 where there is no sample).
    pub wi: &'a mut [DVec3],
    /// Their densities (solid angle; 0 where there is no sample).
    pub pdf: &'a mut [f64],
    /// `c` weights per pair, f_r cos θi / pdf (0 where there is no sample).
    pub weight: &'a mut [f32],
}

/// Whether a pair may have a sample: a non-finite `wo` has none (the NaN rule of every host),
/// and neither has a `u` outside [0, 1)² (NaN included), whatever the source — samplers map
/// only that square (beyond it Blinn-Phong drew directions of length 1.009 and Ward's density
/// was 20 % off).
#[inline]
pub fn drawable(wo: DVec3, u: DVec2) -> bool {
    wo.is_finite() && crate::geometry::in_unit_square(u)
}

/// The outputs of a pair without a sample: zeros.
#[inline]
pub fn no_sample(wi: &mut DVec3, pdf: &mut f64, weight: &mut [f32]) {
    *wi = DVec3::ZERO;
    *pdf = 0.0;
    weight.fill(0.0);
}

/// The blocks of a batch of samples: `run(wo, u, out)` fills one block of at most [`BLOCK`]
/// pairs (`wo` and `u` are the block's inputs, `out` its rows; `c` weights per pair), in
/// parallel from [`PARALLEL`] pairs on. [`Brdf::sample_batch`]'s default draws pair by pair in
/// `run`; tables draw a block first and then evaluate its weights together (their
/// [`Brdf::eval_batch`]'s eight-lane path).
///
/// [`Brdf::sample_batch`]: crate::brdf::Brdf::sample_batch
/// [`Brdf::eval_batch`]: crate::brdf::Brdf::eval_batch
///
/// # Panics
///
/// If the lengths do not match `wo.len()` pairs of `c` weights.
pub fn sample_blocks(
    c: usize,
    wo: &[DVec3],
    u: &[DVec2],
    out: SampleOut<'_>,
    run: impl Fn(&[DVec3], &[DVec2], SampleOut<'_>) + Sync + Send,
) {
    let n = wo.len();
    let SampleOut { wi, pdf, weight } = out;
    assert!(
        u.len() == n && wi.len() == n && pdf.len() == n && weight.len() == n * c,
        "sample_batch: {n} wo, {} u, {} wi, {} pdf and {} weights do not match ({c} channels)",
        u.len(),
        wi.len(),
        pdf.len(),
        weight.len()
    );
    let go = |s: usize, wi: &mut [DVec3], pdf: &mut [f64], weight: &mut [f32]| {
        let m = wi.len();
        run(&wo[s..s + m], &u[s..s + m], SampleOut { wi, pdf, weight })
    };
    if n >= PARALLEL {
        crate::par::install(|| {
            wi.par_chunks_mut(BLOCK)
                .zip(pdf.par_chunks_mut(BLOCK))
                .zip(weight.par_chunks_mut(BLOCK * c))
                .enumerate()
                .for_each(|(b, ((wi, p), w))| go(b * BLOCK, wi, p, w))
        });
    } else {
        for (b, ((wi, p), w)) in wi
            .chunks_mut(BLOCK)
            .zip(pdf.chunks_mut(BLOCK))
            .zip(weight.chunks_mut(BLOCK * c))
            .enumerate()
        {
            go(b * BLOCK, wi, p, w);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Brdf;
    use crate::models::lambert::Lambert;
    use crate::spectrum::{Channels, Value};

    fn dirs(n: usize) -> Vec<DVec3> {
        (0..n)
            .map(|k| {
                let t = k as f64 * 0.618;
                DVec3::new(t.sin() * 0.7, t.cos() * 0.5, 0.2 + (k % 7) as f64 * 0.1)
            })
            .collect()
    }

    /// The parallel path (≥ PARALLEL pairs, blocks straddled) equals the one-pair methods.
    #[test]
    fn batches_equal_one_pair_calls() {
        let b = Lambert::new(Value::Grey(0.5), &Channels::Rgb).unwrap();
        let n = PARALLEL + 3 * BLOCK / 2 + 5;
        let (wi, wo) = (dirs(n), dirs(n + 9)[9..].to_vec());
        let mut p = vec![-1.0; n];
        b.pdf_batch(&wi, &wo, &mut p);
        for k in [0, BLOCK - 1, BLOCK, n - 1] {
            assert_eq!(p[k], b.pdf(wi[k], wo[k]));
        }
        let u: Vec<DVec2> = (0..n)
            .map(|k| DVec2::new((k % 97) as f64 / 97.0, (k % 89) as f64 / 89.0))
            .collect();
        let (mut si, mut sp, mut sw) = (vec![DVec3::NAN; n], vec![-1.0; n], vec![-1.0; 3 * n]);
        let mut nan_wo = wo.clone();
        nan_wo[BLOCK] = DVec3::new(f64::NAN, 0.0, 1.0);
        let out = SampleOut {
            wi: &mut si,
            pdf: &mut sp,
            weight: &mut sw,
        };
        b.sample_batch(&nan_wo, &u, out);
        let mut drawn = 0;
        for k in [0, 1, BLOCK - 1, BLOCK + 1, n - 2, n - 1] {
            let mut w = [0.0f32; 3];
            match b.sample(nan_wo[k], u[k], &mut w) {
                Some(s) => {
                    drawn += 1;
                    assert_eq!((si[k], sp[k]), (s.wi, s.pdf));
                    assert_eq!(&sw[3 * k..3 * k + 3], &w);
                }
                // u = (0, 0) is the disk's rim: no direction (pdf 0).
                None => assert_eq!((si[k], sp[k]), (DVec3::ZERO, 0.0)),
            }
        }
        assert!(drawn >= 4);
        assert_eq!((si[BLOCK], sp[BLOCK]), (DVec3::ZERO, 0.0));
        assert_eq!(&sw[3 * BLOCK..3 * BLOCK + 3], &[0.0; 3]);
    }
}
