//! Fresnel reflectance: exact dielectric and conductor formulas for unpolarized light.
//!
//! The lecture writes, for a wave arriving at angle θ′ and refracted to θ in a medium of complex
//! index n + kj,
//!
//! ```text
//! F∥ = |(cos θ − (n+kj) cos θ′) / (cos θ + (n+kj) cos θ′)|²
//! F⊥ = |(cos θ′ − (n+kj) cos θ) / (cos θ′ + (n+kj) cos θ)|²
//! k_r = (F∥ + F⊥) / 2
//! ```
//!
//! with Snell's law n = sin θ′ / sin θ giving the (complex) refraction angle. [`conductor`]
//! evaluates exactly this with complex arithmetic; [`dielectric`] is the k = 0 case with total
//! internal reflection handled. [`schlick`] exists as a separate, approximate option.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::spectrum::{Channels, Value};

#[derive(Debug, Clone, Copy)]
struct C {
    re: f64,
    im: f64,
}

impl C {
    #[inline]
    fn new(re: f64, im: f64) -> Self {
        C { re, im }
    }
    #[inline]
    fn mul(self, o: C) -> C {
        C::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    #[inline]
    fn add(self, o: C) -> C {
        C::new(self.re + o.re, self.im + o.im)
    }
    #[inline]
    fn sub(self, o: C) -> C {
        C::new(self.re - o.re, self.im - o.im)
    }
    #[inline]
    fn scale(self, s: f64) -> C {
        C::new(self.re * s, self.im * s)
    }
    #[inline]
    fn norm2(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    #[inline]
    fn div(self, o: C) -> C {
        let d = o.norm2();
        C::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
    /// Principal square root.
    #[inline]
    fn sqrt(self) -> C {
        let r = self.norm2().sqrt();
        let re = ((r + self.re) * 0.5).max(0.0).sqrt();
        let im = ((r - self.re) * 0.5).max(0.0).sqrt().copysign(self.im);
        C::new(re, im)
    }
}

/// The parallel and perpendicular reflectances (F∥, F⊥) at a conductor (or dielectric) surface
/// of complex relative index `n + k j`, for incidence cosine `cos_i` ∈ [0, 1] (θ′ of the lecture).
pub fn conductor_polarized(cos_i: f64, n: f64, k: f64) -> (f64, f64) {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let eta = C::new(n, k);
    let sin2_i = 1.0 - cos_i * cos_i;
    // Snell: sin θ = sin θ′ / η, cos θ = sqrt(1 − sin² θ′ / η²) (complex for conductors).
    let eta2 = eta.mul(eta);
    let cos_t = C::new(1.0, 0.0).sub(C::new(sin2_i, 0.0).div(eta2)).sqrt();
    let ci = C::new(cos_i, 0.0);
    // F∥ = |(cos θ − η cos θ′) / (cos θ + η cos θ′)|²
    let f_par = cos_t
        .sub(eta.scale(cos_i))
        .div(cos_t.add(eta.scale(cos_i)))
        .norm2();
    // F⊥ = |(cos θ′ − η cos θ) / (cos θ′ + η cos θ)|²
    let et = eta.mul(cos_t);
    let f_perp = ci.sub(et).div(ci.add(et)).norm2();
    (f_par, f_perp)
}

/// Unpolarized conductor reflectance k_r = (F∥ + F⊥)/2 for incidence cosine `cos_i` and complex
/// index `n + k j`. At normal incidence this is ((n−1)² + k²) / ((n+1)² + k²).
#[inline]
pub fn conductor(cos_i: f64, n: f64, k: f64) -> f64 {
    if cos_i.is_nan() || cos_i <= 0.0 {
        return 1.0;
    }
    // The same quantity as `conductor_polarized` in real arithmetic (exact, not an
    // approximation; e.g. Lagarde, "Memo on Fresnel equations", 2013): with
    // a² + b² = |η² − sin² θ′| and a = Re sqrt(η² − sin² θ′),
    // F⊥ = (a² + b² − 2a cos θ′ + cos² θ′) / (a² + b² + 2a cos θ′ + cos² θ′),
    // F∥ = F⊥ (cos² θ′ (a² + b²) − 2a cos θ′ sin² θ′ + sin⁴ θ′) / (… + …).
    // Two square roots and two divisions instead of complex division and square roots; this is
    // on the hot path of every microfacet model with a metal.
    let c = cos_i.min(1.0);
    let cos2 = c * c;
    let sin2 = 1.0 - cos2;
    let (n2, k2) = (n * n, k * k);
    // η² − sin² θ′ as (n² − k² − 1) + cos² θ′: for an index near 1 + 0j the form with sin² =
    // 1 − cos² cancelled to rounding noise (F ~ 1e-17 where it is 0).
    let t0 = (n2 - k2 - 1.0) + cos2;
    let a2b2 = (t0 * t0 + 4.0 * n2 * k2).sqrt();
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let t1 = a2b2 + cos2;
    let t2 = 2.0 * a * c;
    let t3 = cos2 * a2b2 + sin2 * sin2;
    let t4 = t2 * sin2;
    // ½ (F⊥ + F∥) = ½ F⊥ (1 + (t3 − t4)/(t3 + t4)) = F⊥ t3 / (t3 + t4): one division.
    ratio(t1 - t2, t3, (t1 + t2) * (t3 + t4))
}

/// The closed form's last step, (t1 − t2) t3 / den, kept finite and non-negative.
///
/// t1 − t2 = |η² − sin²| + cos² − 2a cos ≥ (√|η² − sin²| − cos)² ≥ 0 (a ≤ √|η² − sin²|), but
/// where the two nearly cancel (an index near 1 + 0j) rounding made it negative: F of −1e-17.
/// den is 0 only for the index-matched 1 + 0j where cos² θ′ underflows (every term 0, which was
/// 0/0 = NaN): that gives 1, as [`dielectric`] does at η = 1 there (its critical angle) and
/// [`conductor`] at cos θ′ ≤ 0.
#[inline(always)]
fn ratio(d12: f64, t3: f64, den: f64) -> f64 {
    if den > 0.0 {
        d12.max(0.0) * t3 / den
    } else {
        1.0
    }
}

/// [`conductor`] for `N` indices at once, lane by lane the same operations (so bit-identical
/// results), written over fixed-size arrays so that the square roots and divisions vectorize.
#[inline]
pub fn conductor_lanes<const N: usize>(cos_i: f64, n: [f64; N], k: [f64; N]) -> [f64; N] {
    conductor_lanes_c2(cos_i, cos_i * cos_i, n, k)
}

/// [`conductor_lanes`] with cos² θ′ supplied by the caller (`cos2_i`, consistent with `cos_i`
/// to rounding): a caller that has cos² before cos (a quotient before its square root) starts
/// the two square roots of the formula, which need only cos², without waiting for cos.
#[inline]
pub fn conductor_lanes_c2<const N: usize>(
    cos_i: f64,
    cos2_i: f64,
    n: [f64; N],
    k: [f64; N],
) -> [f64; N] {
    if cos_i.is_nan() || cos_i <= 0.0 {
        return [1.0; N];
    }
    let c = cos_i.min(1.0);
    let cos2 = cos2_i.min(1.0);
    let sin2 = 1.0 - cos2;
    let mut out = [0.0; N];
    let mut t0 = [0.0; N];
    let mut a2b2 = [0.0; N];
    let mut a = [0.0; N];
    for i in 0..N {
        let (n2, k2) = (n[i] * n[i], k[i] * k[i]);
        t0[i] = (n2 - k2 - 1.0) + cos2;
        a2b2[i] = t0[i] * t0[i] + 4.0 * n2 * k2;
    }
    for v in &mut a2b2 {
        *v = v.sqrt();
    }
    for i in 0..N {
        a[i] = (0.5 * (a2b2[i] + t0[i])).max(0.0);
    }
    for v in &mut a {
        *v = v.sqrt();
    }
    for i in 0..N {
        let t1 = a2b2[i] + cos2;
        let t2 = 2.0 * a[i] * c;
        let t3 = cos2 * a2b2[i] + sin2 * sin2;
        let t4 = t2 * sin2;
        out[i] = ratio(t1 - t2, t3, (t1 + t2) * (t3 + t4));
    }
    out
}

/// [`conductor_lanes`] at the cosine x / √gg of a direction w and an unnormalized normal g,
/// given as x = w·g and gg = |g|², without the division and root that normalizing costs.
///
/// Every term of the formula is a power of gg times its normalized value (T0 = gg t0,
/// A2B2 = gg a2b2, A x = gg a c, T1 = gg t1, T2 = gg t2, T3 = gg² t3, T4 = gg² t4), so the
/// ratio F = (T1 − T2) T3 / ((T1 + T2)(T3 + T4)) is the same: a caller whose normal is still
/// unnormalized starts the formula's square roots without waiting for 1/gg. 1 for x ≤ 0.
#[inline]
pub fn conductor_lanes_scaled<const N: usize>(
    x: f64,
    gg: f64,
    n: [f64; N],
    k: [f64; N],
) -> [f64; N] {
    if !(x > 0.0 && gg > 0.0 && gg < f64::INFINITY) {
        return [1.0; N];
    }
    // gg cos² ≤ gg and gg sin² ≥ 0, as the normalized formula clamps cos ≤ 1.
    let x2 = (x * x).min(gg);
    let s = gg - x2;
    let mut out = [0.0; N];
    let mut t0 = [0.0; N];
    let mut a2b2 = [0.0; N];
    let mut a = [0.0; N];
    for i in 0..N {
        let (n2, k2) = (n[i] * n[i], k[i] * k[i]);
        t0[i] = gg * (n2 - k2 - 1.0) + x2;
        let nkg = 2.0 * n[i] * k[i] * gg;
        a2b2[i] = t0[i] * t0[i] + nkg * nkg;
    }
    for v in &mut a2b2 {
        *v = v.sqrt();
    }
    for i in 0..N {
        a[i] = (0.5 * (a2b2[i] + t0[i])).max(0.0);
    }
    for v in &mut a {
        *v = v.sqrt();
    }
    for i in 0..N {
        let t1 = a2b2[i] + x2;
        let t2 = 2.0 * a[i] * x;
        let t3 = x2 * a2b2[i] + s * s;
        let t4 = t2 * s;
        out[i] = ratio(t1 - t2, t3, (t1 + t2) * (t3 + t4));
    }
    out
}

/// Unpolarized dielectric reflectance for incidence cosine `cos_i` and relative index
/// `eta` = n_transmitted / n_incident. A negative `cos_i` means the light arrives from inside
/// (the other side of the normal); then the relative index is 1/eta. Total internal reflection
/// gives 1.
pub fn dielectric(cos_i: f64, eta: f64) -> f64 {
    let (cos_i, eta) = if cos_i < 0.0 {
        (-cos_i, 1.0 / eta)
    } else {
        (cos_i, eta)
    };
    let cos_i = cos_i.min(1.0);
    // cos² θt η² = η² − sin² θ′ = (η² − 1) + cos² θ′, which is exact for η = 1 (no interface,
    // F = 0) where 1 − (1 − cos²)/η² cancelled to rounding noise. ≤ 0: total internal
    // reflection.
    let ct2_eta2 = (eta * eta - 1.0) + cos_i * cos_i;
    if ct2_eta2 <= 0.0 {
        return 1.0;
    }
    let cos_t = ct2_eta2.sqrt() / eta;
    let r_par = (cos_t - eta * cos_i) / (cos_t + eta * cos_i);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_par * r_par + r_perp * r_perp)
}

/// Schlick's approximation F0 + (1 − F0)(1 − cos)^5 — an option, not the default.
#[inline]
pub fn schlick(cos_i: f64, f0: f64) -> f64 {
    let m = (1.0 - cos_i.clamp(0.0, 1.0)).powi(5);
    f0 + (1.0 - f0) * m
}

/// The Fresnel term of a model spec, in JSON:
/// `"none"` (F = 1), `{"conductor": "Au"}` (named metal), `{"n": X, "k": X}` (complex index),
/// `{"eta": X}` (dielectric), `{"schlick": X}` (Schlick with F0 = X).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum FresnelSpec {
    /// F = 1.
    #[default]
    None,
    /// A named metal from [`crate::metals`].
    Conductor(String),
    /// A complex index n + k j.
    Complex {
        /// Real part n.
        n: Value,
        /// Extinction coefficient k.
        k: Value,
    },
    /// A dielectric of relative index eta.
    Dielectric(Value),
    /// Schlick's approximation with normal-incidence reflectance F0.
    Schlick(Value),
}

impl Serialize for FresnelSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        match self {
            FresnelSpec::None => s.serialize_str("none"),
            FresnelSpec::Conductor(name) => {
                let mut m = s.serialize_map(Some(1))?;
                m.serialize_entry("conductor", name)?;
                m.end()
            }
            FresnelSpec::Complex { n, k } => {
                let mut m = s.serialize_map(Some(2))?;
                m.serialize_entry("n", n)?;
                m.serialize_entry("k", k)?;
                m.end()
            }
            FresnelSpec::Dielectric(eta) => {
                let mut m = s.serialize_map(Some(1))?;
                m.serialize_entry("eta", eta)?;
                m.end()
            }
            FresnelSpec::Schlick(f0) => {
                let mut m = s.serialize_map(Some(1))?;
                m.serialize_entry("schlick", f0)?;
                m.end()
            }
        }
    }
}

impl<'de> Deserialize<'de> for FresnelSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Obj {
            conductor: Option<String>,
            n: Option<Value>,
            k: Option<Value>,
            eta: Option<Value>,
            schlick: Option<Value>,
        }
        let v = serde_json::Value::deserialize(d)?;
        match v {
            serde_json::Value::String(s) if s == "none" => Ok(FresnelSpec::None),
            serde_json::Value::Object(_) => {
                let o: Obj = serde_json::from_value(v).map_err(D::Error::custom)?;
                match o {
                    Obj {
                        conductor: Some(c),
                        n: None,
                        k: None,
                        eta: None,
                        schlick: None,
                    } => Ok(FresnelSpec::Conductor(c)),
                    Obj {
                        conductor: None,
                        n: Some(n),
                        k,
                        eta: None,
                        schlick: None,
                    } => Ok(FresnelSpec::Complex {
                        n,
                        k: k.unwrap_or(Value::Grey(0.0)),
                    }),
                    Obj {
                        conductor: None,
                        n: None,
                        k: None,
                        eta: Some(eta),
                        schlick: None,
                    } => Ok(FresnelSpec::Dielectric(eta)),
                    Obj {
                        conductor: None,
                        n: None,
                        k: None,
                        eta: None,
                        schlick: Some(f0),
                    } => Ok(FresnelSpec::Schlick(f0)),
                    _ => Err(D::Error::custom(
                        "expected exactly one of {\"conductor\": NAME}, {\"n\": X, \"k\": X}, {\"eta\": X}, {\"schlick\": X}",
                    )),
                }
            }
            other => Err(D::Error::custom(format!(
                "expected \"none\", {{\"conductor\": NAME}}, {{\"n\": X, \"k\": X}}, {{\"eta\": X}} or {{\"schlick\": X}}, got {other}"
            ))),
        }
    }
}

/// A Fresnel term resolved for a channel set: per-channel constants, ready to evaluate without
/// allocation, plus the spectral data for evaluation at arbitrary wavelengths.
#[derive(Debug, Clone)]
pub enum Fresnel {
    /// F = 1.
    None,
    /// Complex index per channel.
    Conductor {
        /// n per channel.
        n: Vec<f64>,
        /// k per channel.
        k: Vec<f64>,
        /// n as a spectrum.
        n_spec: Value,
        /// k as a spectrum.
        k_spec: Value,
    },
    /// Relative index per channel.
    Dielectric {
        /// eta per channel.
        eta: Vec<f64>,
        /// eta as a spectrum.
        eta_spec: Value,
    },
    /// Schlick's approximation, F0 per channel.
    Schlick {
        /// F0 per channel.
        f0: Vec<f64>,
        /// F0 as a spectrum.
        f0_spec: Value,
    },
}

impl Fresnel {
    /// Resolves a spec for `channels`, validating it; `field` names the spec field in errors.
    pub fn new(spec: &FresnelSpec, channels: &Channels, field: &str) -> Result<Self> {
        Ok(match spec {
            FresnelSpec::None => Fresnel::None,
            FresnelSpec::Conductor(name) => {
                let (n, k) = crate::metals::metal(name).ok_or_else(|| {
                    Error::spec(
                        format!("{field}.conductor"),
                        format!(
                            "unknown metal `{name}` (known: {})",
                            crate::metals::NAMES.join(", ")
                        ),
                    )
                })?;
                Fresnel::Conductor {
                    n: n.resolve(channels),
                    k: k.resolve(channels),
                    n_spec: n,
                    k_spec: k,
                }
            }
            FresnelSpec::Complex { n, k } => {
                n.validate(&format!("{field}.n"), 0.0)?;
                k.validate(&format!("{field}.k"), 0.0)?;
                if n.numbers().iter().any(|&x| x <= 0.0) {
                    return Err(Error::spec(format!("{field}.n"), "must be positive"));
                }
                Fresnel::Conductor {
                    n: n.resolve(channels),
                    k: k.resolve(channels),
                    n_spec: n.clone(),
                    k_spec: k.clone(),
                }
            }
            FresnelSpec::Dielectric(eta) => {
                eta.validate(&format!("{field}.eta"), 0.0)?;
                if eta.numbers().iter().any(|&x| x <= 0.0) {
                    return Err(Error::spec(format!("{field}.eta"), "must be positive"));
                }
                Fresnel::Dielectric {
                    eta: eta.resolve(channels),
                    eta_spec: eta.clone(),
                }
            }
            FresnelSpec::Schlick(f0) => {
                f0.validate(&format!("{field}.schlick"), 0.0)?;
                if f0.numbers().iter().any(|&x| x > 1.0) {
                    return Err(Error::spec(format!("{field}.schlick"), "F0 must be ≤ 1"));
                }
                Fresnel::Schlick {
                    f0: f0.resolve(channels),
                    f0_spec: f0.clone(),
                }
            }
        })
    }

    /// F for channel `c` at incidence cosine `cos_i` (the lecture's L·H or N·V).
    #[inline]
    pub fn eval(&self, cos_i: f64, c: usize) -> f64 {
        match self {
            Fresnel::None => 1.0,
            Fresnel::Conductor { n, k, .. } => conductor(cos_i, n[c], k[c]),
            Fresnel::Dielectric { eta, .. } => dielectric(cos_i, eta[c]),
            Fresnel::Schlick { f0, .. } => schlick(cos_i, f0[c]),
        }
    }

    /// Writes `scale[c] · s · F_c(cos_i)` as `f32` into `out[c]` for every channel: the last step
    /// of a microfacet model's `eval`. The variant is matched once, outside the channel loop, so
    /// the loop is straight-line arithmetic the compiler can vectorize.
    #[inline(always)]
    pub fn eval_scaled(&self, cos_i: f64, scale: &[f64], s: f64, out: &mut [f32]) {
        // No Fresnel term with RGB (the common case of plain microfacet lobes): three stores,
        // inline, rather than a call.
        if let (Fresnel::None, [o0, o1, o2, ..], [k0, k1, k2]) = (self, &mut *out, scale) {
            (*o0, *o1, *o2) = ((k0 * s) as f32, (k1 * s) as f32, (k2 * s) as f32);
            return;
        }
        self.eval_scaled_c2(cos_i, cos_i * cos_i, scale, s, out)
    }

    /// [`Fresnel::eval_scaled`] at the cosine x / √gg of a direction and an unnormalized normal
    /// g (x = w·g, gg = |g|²): RGB conductors use [`conductor_lanes_scaled`], which needs
    /// neither 1/gg nor √gg; other variants normalize.
    #[inline]
    pub fn eval_scaled_dot(&self, x: f64, gg: f64, scale: &[f64], s: f64, out: &mut [f32]) {
        if let (Fresnel::Conductor { n, k, .. }, [o0, o1, o2, ..], [k0, k1, k2]) =
            (self, &mut *out, scale)
            && let (&[n0, n1, n2], &[c0, c1, c2]) = (n.as_slice(), k.as_slice())
        {
            let f = conductor_lanes_scaled(x, gg, [n0, n1, n2, n0], [c0, c1, c2, c0]);
            (*o0, *o1, *o2) = (
                (k0 * s * f[0]) as f32,
                (k1 * s * f[1]) as f32,
                (k2 * s * f[2]) as f32,
            );
            return;
        }
        self.eval_scaled(x / gg.sqrt(), scale, s, out)
    }

    /// [`Fresnel::eval_scaled`] with cos² θ′ supplied by the caller (see
    /// [`conductor_lanes_c2`]; other variants use `cos_i` alone).
    #[inline]
    pub fn eval_scaled_c2(&self, cos_i: f64, cos2_i: f64, scale: &[f64], s: f64, out: &mut [f32]) {
        match self {
            Fresnel::None => {
                if let ([o0, o1, o2, ..], [k0, k1, k2]) = (&mut *out, scale) {
                    (*o0, *o1, *o2) = ((k0 * s) as f32, (k1 * s) as f32, (k2 * s) as f32);
                    return;
                }
                for (o, &k) in out.iter_mut().zip(scale) {
                    *o = (k * s) as f32;
                }
            }
            Fresnel::Conductor { n, k, .. } => {
                if let (Ok(o), Ok(ks), Ok(n), Ok(k)) = (
                    <&mut [f32; 3]>::try_from(&mut *out),
                    <&[f64; 3]>::try_from(scale),
                    <&[f64; 3]>::try_from(n.as_slice()),
                    <&[f64; 3]>::try_from(k.as_slice()),
                ) {
                    // RGB: the three channels as lanes of one fixed-size computation, which the
                    // compiler turns into packed square roots and divisions.
                    let f = conductor_lanes_c2(
                        cos_i,
                        cos2_i,
                        [n[0], n[1], n[2], n[0]],
                        [k[0], k[1], k[2], k[0]],
                    );
                    for c in 0..3 {
                        o[c] = (ks[c] * s * f[c]) as f32;
                    }
                    return;
                }
                for (((o, &ks), &n), &k) in out.iter_mut().zip(scale).zip(n).zip(k) {
                    *o = (ks * s * conductor(cos_i, n, k)) as f32;
                }
            }
            Fresnel::Dielectric { eta, .. } => {
                for ((o, &ks), &e) in out.iter_mut().zip(scale).zip(eta) {
                    *o = (ks * s * dielectric(cos_i, e)) as f32;
                }
            }
            Fresnel::Schlick { f0, .. } => {
                for ((o, &ks), &f) in out.iter_mut().zip(scale).zip(f0) {
                    *o = (ks * s * schlick(cos_i, f)) as f32;
                }
            }
        }
    }

    /// F at wavelength `nm` from the spectral data; NaN at a non-wavelength
    /// ([`crate::spectrum::is_wavelength`]).
    pub fn eval_at(&self, cos_i: f64, nm: f64) -> f64 {
        if !crate::spectrum::is_wavelength(nm) {
            return f64::NAN;
        }
        match self {
            Fresnel::None => 1.0,
            Fresnel::Conductor { n_spec, k_spec, .. } => {
                conductor(cos_i, n_spec.at(nm), k_spec.at(nm))
            }
            Fresnel::Dielectric { eta_spec, .. } => dielectric(cos_i, eta_spec.at(nm)),
            Fresnel::Schlick { f0_spec, .. } => schlick(cos_i, f0_spec.at(nm)),
        }
    }

    /// True for F = 1.
    pub fn is_none(&self) -> bool {
        matches!(self, Fresnel::None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scaled_conductor_matches_the_normalized_formula() {
        // Au-like and Cu-like indices, random cosines and normal lengths: the scaled formula is
        // the normalized one with every term multiplied by a power of gg, so they agree to
        // rounding (a few ulps, amplified by the conditioning of the differences t1 − t2).
        let n = [0.18, 0.42, 1.37, 0.27];
        let k = [3.4, 2.35, 1.77, 2.8];
        let mut rng = crate::rng::Pcg32::new(11);
        for _ in 0..20_000 {
            let cos = rng.next_f64().max(1e-6);
            let len = 0.01 + 10.0 * rng.next_f64();
            let (x, gg) = (cos * len, len * len);
            let f = conductor_lanes_scaled(x, gg, n, k);
            for i in 0..4 {
                let expect = conductor(cos, n[i], k[i]);
                assert!(
                    (f[i] - expect).abs() <= 1e-12 * expect,
                    "{cos} {len}: {} vs {expect}",
                    f[i]
                );
            }
        }
        assert_eq!(conductor_lanes_scaled(0.0, 1.0, n, k), [1.0; 4]);
        assert_eq!(conductor_lanes_scaled(-0.5, 1.0, n, k), [1.0; 4]);
        assert_eq!(conductor_lanes_scaled(f64::NAN, 1.0, n, k), [1.0; 4]);
    }

    #[test]
    fn lanes_are_bit_identical_to_the_scalar_formula() {
        let n = [0.2, 1.5, 0.05, 3.0];
        let k = [3.0, 0.0, 4.2, 0.1];
        for i in 0..=1000 {
            let c = i as f64 / 1000.0;
            let f = conductor_lanes(c, n, k);
            for l in 0..4 {
                assert_eq!(
                    f[l].to_bits(),
                    conductor(c, n[l], k[l]).to_bits(),
                    "c={c} lane {l}"
                );
            }
        }
        assert_eq!(conductor_lanes(f64::NAN, n, k), [1.0; 4]);
        assert_eq!(conductor_lanes(-0.5, n, k), [1.0; 4]);
    }

    #[test]
    fn normal_incidence_closed_form() {
        for &(n, k) in &[(1.5, 0.0), (0.2, 3.0), (0.15, 3.6), (1.1, 7.0), (2.5, 0.3)] {
            let expect = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
            let got = conductor(1.0, n, k);
            assert!(
                (got - expect).abs() < 1e-14,
                "n={n} k={k}: {got} vs {expect}"
            );
        }
        let expect = (0.5f64 / 2.5).powi(2);
        assert!((dielectric(1.0, 1.5) - expect).abs() < 1e-14);
    }

    #[test]
    fn real_closed_form_equals_complex_form() {
        for &(n, k) in &[
            (1.5, 0.0),
            (0.2, 3.0),
            (0.14, 3.697),
            (1.1, 7.0),
            (2.5, 0.3),
            (0.65, 0.0),
        ] {
            for i in 1..=200 {
                let c = i as f64 / 200.0;
                let (a, b) = conductor_polarized(c, n, k);
                let complex = 0.5 * (a + b);
                let real = conductor(c, n, k);
                assert!(
                    (real - complex).abs() < 1e-12,
                    "n={n} k={k} cos={c}: {real} vs {complex}"
                );
            }
        }
    }

    #[test]
    fn brewster_angle_zeroes_parallel() {
        for &eta in &[1.33, 1.5, 2.4] {
            let theta_b = f64::atan(eta);
            let (f_par, f_perp) = conductor_polarized(theta_b.cos(), eta, 0.0);
            assert!(f_par < 1e-15, "eta={eta}: F∥ = {f_par}");
            assert!(f_perp > 0.01);
        }
    }

    #[test]
    fn dielectric_matches_conductor_with_k_zero() {
        for i in 0..=100 {
            let c = i as f64 / 100.0;
            assert!((dielectric(c, 1.5) - conductor(c, 1.5, 0.0)).abs() < 1e-12);
        }
    }

    #[test]
    fn total_internal_reflection() {
        // From inside glass (cos_i < 0), beyond the critical angle asin(1/1.5) ≈ 41.8°.
        let theta = 50f64.to_radians();
        assert_eq!(dielectric(-theta.cos(), 1.5), 1.0);
        let theta = 30f64.to_radians();
        assert!(dielectric(-theta.cos(), 1.5) < 1.0);
    }

    #[test]
    fn grazing_incidence_reflects_everything() {
        assert!((conductor(1e-9, 0.2, 3.0) - 1.0).abs() < 1e-6);
        assert!((dielectric(1e-9, 1.5) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn an_index_matched_interface_reflects_nothing_and_never_nan() {
        // n = 1 + 0j is no interface: F = 0 at every cosine whose fourth power is a normal
        // number (the closed form's t1 − t2 and the dielectric's cos θt cancelled to ±1e-17
        // there; below it (η² − sin²)² is subnormal and inexact), and a number in [0, 1] at any
        // cosine (where cos² underflowed it was 0/0 = NaN: a mirror's sample weight).
        let mut c = 1.0f64;
        while c > 1e-75 {
            assert_eq!(conductor(c, 1.0, 0.0), 0.0, "cos {c:e}");
            assert_eq!(
                conductor_lanes(c, [1.0; 4], [0.0; 4]),
                [0.0; 4],
                "cos {c:e}"
            );
            assert_eq!(conductor_lanes_scaled(c, 1.0, [1.0; 4], [0.0; 4]), [0.0; 4]);
            assert_eq!(dielectric(c, 1.0), 0.0, "cos {c:e}");
            c *= 0.37;
        }
        for c in [1e-80, 1e-160, 1e-170, 1e-300, f64::from_bits(1)] {
            for f in [conductor(c, 1.0, 0.0), dielectric(c, 1.0)]
                .into_iter()
                .chain(conductor_lanes(c, [1.0; 4], [0.0; 4]))
                .chain(conductor_lanes_scaled(c, 1.0, [1.0; 4], [0.0; 4]))
            {
                assert!((0.0..=1.0).contains(&f), "cos {c:e}: {f}");
            }
        }
        // Near 1 + 0j the closed form stays non-negative (it gave −1e-17 for n = 1 at some
        // cosines) and agrees with the complex form.
        let mut rng = crate::rng::Pcg32::new(11);
        for _ in 0..100_000 {
            let c = rng.next_f64();
            let n = 1.0 + (rng.next_f64() - 0.5) * 1e-6;
            let k = rng.next_f64() * 1e-6;
            let f = conductor(c, n, k);
            let (p, q) = conductor_polarized(c, n, k);
            // Both forms cancel near 1 + 0j (the complex one in 1 − sin²/η², to ~1e-9 of F).
            let want = 0.5 * (p + q);
            assert!(
                f >= 0.0 && (f - want).abs() <= 1e-6 * want + 1e-15,
                "{c} {n} {k}: {f}"
            );
        }
    }

    #[test]
    fn spec_json_forms() {
        let a: FresnelSpec = serde_json::from_str("\"none\"").unwrap();
        assert_eq!(a, FresnelSpec::None);
        let b: FresnelSpec = serde_json::from_str(r#"{"n": 0.2, "k": 3}"#).unwrap();
        assert!(matches!(b, FresnelSpec::Complex { .. }));
        let c: FresnelSpec = serde_json::from_str(r#"{"eta": 1.5}"#).unwrap();
        assert!(matches!(c, FresnelSpec::Dielectric(_)));
        assert!(serde_json::from_str::<FresnelSpec>(r#"{"eta": 1.5, "n": 2}"#).is_err());
        assert!(serde_json::from_str::<FresnelSpec>(r#"{"bogus": 1}"#).is_err());
        assert!(serde_json::from_str::<FresnelSpec>("\"schlick\"").is_err());
        let back = serde_json::to_string(&b).unwrap();
        assert_eq!(serde_json::from_str::<FresnelSpec>(&back).unwrap(), b);
    }
}
