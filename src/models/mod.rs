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

/// [`geometry::upper_pair`](crate::geometry::upper_pair) for the hot path: normalizes both
/// directions with one division (1 / (|wi| |wo|)) instead of six, and checks both are strictly
/// above the horizon and finite. Directions that are already unit to within 2⁻⁴⁰ in squared
/// length are returned unchanged. Symmetric: swapping the arguments swaps the results bit for bit.
#[inline]
pub(crate) fn unit_upper_pair(
    wi: glam::DVec3,
    wo: glam::DVec3,
) -> Option<(glam::DVec3, glam::DVec3)> {
    let (l2, v2) = (wi.length_squared(), wo.length_squared());
    if !(wi.z > 0.0 && wo.z > 0.0) {
        return None;
    }
    // Unit inputs (what renderers and samplers pass) are used as they are.
    if crate::geometry::is_unit_l2(l2) && crate::geometry::is_unit_l2(v2) {
        return Some((wi, wo));
    }
    let normal = f64::MIN_POSITIVE..f64::INFINITY;
    if !(normal.contains(&l2) && normal.contains(&v2)) {
        // Lengths whose squares under- or overflow (or NaN, infinite): scaled one by one.
        return crate::geometry::upper_pair(wi, wo);
    }
    // 1/(|wi| |wo|) ≤ 1/MIN_POSITIVE: finite.
    let (sl, sv) = (l2.sqrt(), v2.sqrt());
    let r = 1.0 / (sl * sv);
    Some((wi * (sv * r), wo * (sl * r)))
}

#[cfg(test)]
mod unit_pair_tests {
    use super::unit_upper_pair;
    use crate::geometry;
    use crate::rng::Pcg32;

    #[test]
    fn unit_and_scaled_inputs_give_the_same_pair() {
        let mut rng = Pcg32::new(12);
        for _ in 0..2000 {
            let a = geometry::cosine_hemisphere(rng.next_dvec2());
            let b = geometry::cosine_hemisphere(rng.next_dvec2());
            let Some((l, v)) = unit_upper_pair(a, b) else {
                continue;
            };
            assert_eq!((l, v), (a, b), "unit inputs are returned as they are");
            let (l2, v2) = unit_upper_pair(a * 3.0, b * 0.25).unwrap();
            assert!((l2 - a).length() < 1e-15 && (v2 - b).length() < 1e-15);
            // Symmetric bit for bit.
            assert_eq!(unit_upper_pair(b * 0.25, a * 3.0), Some((v2, l2)));
        }
        assert!(unit_upper_pair(glam::DVec3::new(0.0, 0.0, -1.0), glam::DVec3::Z).is_none());
        assert!(unit_upper_pair(glam::DVec3::new(f64::NAN, 0.0, 1.0), glam::DVec3::Z).is_none());
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
