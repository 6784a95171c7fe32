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

mod spec;
mod term;
#[cfg(test)]
mod tests;

pub use spec::FresnelSpec;
pub use term::Fresnel;

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
