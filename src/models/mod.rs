//! Analytic BRDF models, one family per file, all behind the [`Brdf`](crate::Brdf) trait.
//!
//! Each model is written with the names of its paper or of the lecture so a reader can check it
//! against the equation. Models are built from a [`ModelSpec`](crate::spec::ModelSpec) (whose declaration,
//! [`MODELS`](crate::spec::MODELS), lists them all); parameters are
//! resolved per channel at construction so `eval` never allocates.

pub mod beckmann;
pub mod blinn_phong;
pub mod cook_torrance;
pub mod ggx;
pub mod lambert;
pub mod mirror;
pub mod oren_nayar;
pub mod phong;
pub mod sum;
pub mod visible;
pub mod ward;

#[cfg(test)]
pub(crate) mod test_util;

/// Writes `src` to `out[..src.len()]`, or zeros when `on` is false, with three plain stores for
/// RGB (a slice copy of 12 bytes otherwise becomes a `memcpy` call).
#[inline]
pub(crate) fn put_channels(out: &mut [f32], src: &[f32], on: bool) {
    let out = &mut out[..src.len()];
    if let ([o0, o1, o2], [k0, k1, k2]) = (&mut *out, src) {
        let m = if on { 1.0 } else { 0.0 };
        (*o0, *o1, *o2) = (k0 * m, k1 * m, k2 * m);
    } else if on {
        out.copy_from_slice(src);
    } else {
        out.fill(0.0);
    }
}

#[cfg(test)]
mod range_tests {
    use crate::error::Error;
    use crate::fresnel::FresnelSpec;
    use crate::spectrum::{Channels, NUMBER_RANGE, Value};

    fn ok<T>(r: crate::error::Result<T>) -> crate::error::Result<()> {
        r.map(|_| ())
    }

    /// Each model constructor's plain-number parameter, built with `x`: the field's name and
    /// whether the model was built.
    fn build_each(x: f64) -> Vec<(&'static str, crate::error::Result<()>)> {
        let ch = &Channels::Rgb;
        let ks = || Value::Grey(0.5);
        let lambert = || -> Box<dyn crate::Brdf + Send + Sync> {
            Box::new(super::lambert::Lambert::new(ks(), ch).unwrap())
        };
        vec![
            (
                "m",
                ok(super::cook_torrance::CookTorrance::new(
                    x,
                    ks(),
                    &FresnelSpec::None,
                    ch,
                )),
            ),
            ("n", ok(super::blinn_phong::BlinnPhong::new(ks(), x, ch))),
            (
                "n",
                ok(super::phong::Phong::new(
                    super::phong::PhongVariant::Reciprocal,
                    ks(),
                    x,
                    ch,
                )),
            ),
            (
                "alpha_x",
                ok(super::ggx::Ggx::new(x, 0.3, ks(), FresnelSpec::None, ch)),
            ),
            (
                "alpha_y",
                ok(super::ggx::Ggx::new(0.3, x, ks(), FresnelSpec::None, ch)),
            ),
            ("alpha_x", ok(super::ward::Ward::new(ks(), x, 0.3, ch))),
            ("alpha_y", ok(super::ward::Ward::new(ks(), 0.3, x, ch))),
            ("sigma", ok(super::oren_nayar::OrenNayar::new(ks(), x, ch))),
            (
                "weights[1]",
                ok(super::sum::Sum::new(
                    vec![lambert(), lambert()],
                    Some(vec![1.0, x]),
                    ch,
                )),
            ),
        ]
    }

    /// The constructors hold their plain numbers to the spec's [`NUMBER_RANGE`], as specs are:
    /// 1e300 as a roughness gave NaN (`spec`'s range test, through specs), and a Rust caller
    /// who builds a model directly meets the same rule, with the field named.
    #[test]
    fn constructors_refuse_numbers_beyond_the_spec_range() {
        for x in [*NUMBER_RANGE.start(), 1.0, *NUMBER_RANGE.end()] {
            for (field, r) in build_each(x) {
                assert!(r.is_ok(), "{field} = {x:e}: {r:?}");
            }
        }
        for x in [NUMBER_RANGE.start() / 4.0, NUMBER_RANGE.end() * 4.0] {
            for (field, r) in build_each(x) {
                match r {
                    Err(Error::Spec { field: f, .. }) => assert_eq!(f, field, "{x:e}"),
                    other => panic!("{field} = {x:e}: {other:?}"),
                }
            }
        }
    }
}
