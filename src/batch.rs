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

/// One block of [`sample_flagged`]'s outputs, numbered: (block, (((wi, pdf), weights), flags)).
type FlaggedBlock<'a> = (
    usize,
    (
        ((&'a mut [DVec3], &'a mut [f64]), &'a mut [f32]),
        &'a mut [bool],
    ),
);

/// [`Brdf::sample_batch`](crate::brdf::Brdf::sample_batch) and each draw's delta flag:
/// `delta[k]` is true where pair `k` drew a delta lobe (a mirror, or a sum's mirror term: its
/// pdf is then the probability of choosing that lobe, not a density, and
/// [`Brdf::pdf`](crate::brdf::Brdf::pdf) does not contain it). What a host's renderer needs to
/// tell such draws from smooth ones (pbrt's `BSDFSample::flags`, Mitsuba's `sampled_type`).
/// Sources without a delta lobe take `sample_batch` (a table's batch path) and flag nothing.
///
/// # Panics
///
/// If the lengths do not match `wo.len()` pairs.
pub fn sample_flagged<B: crate::brdf::Brdf + ?Sized>(
    brdf: &B,
    wo: &[DVec3],
    u: &[DVec2],
    out: SampleOut<'_>,
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
    let SampleOut { wi, pdf, weight } = out;
    assert!(
        u.len() == n && wi.len() == n && pdf.len() == n && weight.len() == n * c,
        "sample_flagged: {n} wo, {} u, {} wi, {} pdf and {} weights do not match ({c} channels)",
        u.len(),
        wi.len(),
        pdf.len(),
        weight.len()
    );
    let go = |(b, (((wi, p), w), d)): FlaggedBlock<'_>| {
        for k in 0..wi.len() {
            let (wo, u) = (wo[b * BLOCK + k], u[b * BLOCK + k]);
            let w = &mut w[k * c..(k + 1) * c];
            let drawn = match drawable(wo, u) {
                true => brdf.sample(wo, u, w),
                false => None,
            };
            match drawn {
                Some(s) => (wi[k], p[k], d[k]) = (s.wi, s.pdf, s.delta),
                None => {
                    no_sample(&mut wi[k], &mut p[k], w);
                    d[k] = false;
                }
            }
        }
    };
    if n >= PARALLEL {
        crate::par::install(|| {
            wi.par_chunks_mut(BLOCK)
                .zip(pdf.par_chunks_mut(BLOCK))
                .zip(weight.par_chunks_mut(BLOCK * c))
                .zip(delta.par_chunks_mut(BLOCK))
                .enumerate()
                .for_each(go)
        });
    } else {
        wi.chunks_mut(BLOCK)
            .zip(pdf.chunks_mut(BLOCK))
            .zip(weight.chunks_mut(BLOCK * c))
            .zip(delta.chunks_mut(BLOCK))
            .enumerate()
            .for_each(go);
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

    /// `sample_flagged` gives the one-pair draws and their delta flags (a sum with a mirror
    /// term, across the parallel path's blocks); a source without a delta lobe flags nothing.
    #[test]
    fn flagged_batches_carry_the_draws_delta_flags() {
        let spec = crate::spec::ModelSpec::parse(
            r#"{"model": "sum", "terms": [{"model": "lambert", "kd": 0.2},
                {"model": "mirror", "fresnel": {"conductor": "Au"}}]}"#,
        )
        .unwrap();
        let lambert: Box<dyn Brdf + Send + Sync> =
            Box::new(Lambert::new(Value::Grey(0.5), &Channels::Rgb).unwrap());
        let sum = spec.build(&Channels::Rgb).unwrap();
        let n = PARALLEL + BLOCK / 2 + 3;
        let wo = dirs(n);
        let u: Vec<DVec2> = (0..n)
            .map(|k| DVec2::new((k % 97) as f64 / 97.0, (k % 89) as f64 / 89.0))
            .collect();
        for (b, has_delta) in [(&sum, true), (&lambert, false)] {
            let (mut si, mut sp, mut sw) = (vec![DVec3::NAN; n], vec![-1.0; n], vec![-1.0; 3 * n]);
            let mut d = vec![true; n];
            let out = SampleOut {
                wi: &mut si,
                pdf: &mut sp,
                weight: &mut sw,
            };
            sample_flagged(b.as_ref(), &wo, &u, out, &mut d);
            let mut deltas = 0;
            for k in 0..n {
                let mut w = [0.0f32; 3];
                match b.sample(wo[k], u[k], &mut w) {
                    Some(s) => {
                        assert_eq!((si[k], sp[k], d[k]), (s.wi, s.pdf, s.delta), "pair {k}");
                        assert_eq!(&sw[3 * k..3 * k + 3], &w);
                        deltas += s.delta as usize;
                    }
                    None => assert_eq!((si[k], sp[k], d[k]), (DVec3::ZERO, 0.0, false)),
                }
            }
            assert_eq!(deltas > 0, has_delta, "{deltas} delta draws");
        }
    }
}
