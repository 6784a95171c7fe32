//! Tests of the trait's provided methods: batches (with the draws' delta flags, at
//! wavelengths) equal one-pair calls, and a draw at no wavelengths still draws.

use super::*;
use crate::batch::{BLOCK, PARALLEL, SampleOut};
use crate::models::lambert::Lambert;
use crate::spectrum::Value;

fn dirs(n: usize) -> Vec<DVec3> {
    (0..n)
        .map(|k| {
            let t = k as f64 * 0.618;
            DVec3::new(t.sin() * 0.7, t.cos() * 0.5, 0.2 + (k % 7) as f64 * 0.1)
        })
        .collect()
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

/// The wavelength batches give the one-pair calls: `sample_flagged_at` the draws, flags and
/// weights of `sample_wavelengths`, `eval_wavelengths` those of `eval_wavelength` (across
/// the parallel path's blocks).
#[test]
fn wavelength_batches_equal_one_pair_calls() {
    let sum = crate::spec::ModelSpec::parse(
        r#"{"model": "sum", "terms": [{"model": "ggx", "alpha": 0.3, "fresnel":
            {"conductor": "Cu"}}, {"model": "mirror", "fresnel": {"conductor": "Au"}}]}"#,
    )
    .unwrap()
    .build(&Channels::Rgb)
    .unwrap();
    let n = PARALLEL + BLOCK / 2 + 3;
    let (wo, wi) = (dirs(n), dirs(n + 5)[5..].to_vec());
    let u: Vec<DVec2> = (0..n)
        .map(|k| DVec2::new((k % 97) as f64 / 97.0, (k % 89) as f64 / 89.0))
        .collect();
    let nm = [430.0, 520.0, 610.0, 700.0];
    let (mut si, mut sp, mut sw) = (vec![DVec3::NAN; n], vec![-1.0; n], vec![-1.0; 4 * n]);
    let mut d = vec![true; n];
    let out = SampleOut {
        wi: &mut si,
        pdf: &mut sp,
        weight: &mut sw,
    };
    sample_flagged_at(sum.as_ref(), &wo, &u, &nm, out, &mut d);
    let mut f = vec![-1.0f32; 4 * n];
    eval_wavelengths(sum.as_ref(), &wi, &wo, &nm, &mut f);
    let mut deltas = 0;
    for k in 0..n {
        let mut w = [0.0f32; 4];
        match sum.sample_wavelengths(wo[k], u[k], &nm, &mut w) {
            Some(s) => {
                assert_eq!((si[k], sp[k], d[k]), (s.wi, s.pdf, s.delta), "pair {k}");
                assert_eq!(&sw[4 * k..4 * k + 4], &w);
                deltas += s.delta as usize;
            }
            None => assert_eq!((si[k], sp[k], d[k]), (DVec3::ZERO, 0.0, false)),
        }
        for (j, &x) in nm.iter().enumerate() {
            assert_eq!(f[4 * k + j], sum.eval_wavelength(wi[k], wo[k], x) as f32);
        }
    }
    assert!(deltas > 0);
}

/// With no wavelengths, `sample_flagged_at` still draws: the directions, pdfs and flags of
/// `sample_flagged` (one pair, and across the parallel path's blocks). It drew nothing, and
/// left wi and pdf as they were, when the empty weights gave no block to zip with.
#[test]
fn sampling_at_no_wavelengths_still_draws() {
    let sum = crate::spec::ModelSpec::parse(
        r#"{"model": "sum", "terms": [{"model": "ggx", "alpha": 0.3},
            {"model": "mirror", "fresnel": {"conductor": "Au"}}]}"#,
    )
    .unwrap()
    .build(&Channels::Rgb)
    .unwrap();
    for n in [1, PARALLEL + BLOCK / 2 + 3] {
        let wo = dirs(n);
        let u: Vec<DVec2> = (0..n)
            .map(|k| DVec2::new((k % 97) as f64 / 97.0, (k % 89) as f64 / 89.0))
            .collect();
        let (mut ai, mut ap, mut ad) = (vec![DVec3::NAN; n], vec![-1.0; n], vec![true; n]);
        let out = SampleOut {
            wi: &mut ai,
            pdf: &mut ap,
            weight: &mut [],
        };
        sample_flagged_at(sum.as_ref(), &wo, &u, &[], out, &mut ad);
        let (mut bi, mut bp, mut bd) = (vec![DVec3::NAN; n], vec![-1.0; n], vec![true; n]);
        let out = SampleOut {
            wi: &mut bi,
            pdf: &mut bp,
            weight: &mut vec![0.0; 3 * n],
        };
        sample_flagged(sum.as_ref(), &wo, &u, out, &mut bd);
        assert_eq!((ai, ap, ad), (bi, bp, bd), "{n} pairs");
    }
}
