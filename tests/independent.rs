//! The lecture's models re-implemented independently and compared with the library.
//!
//! The library writes its models with vectors (dot products, half vectors, reflect()); the
//! reference here is written straight from the lecture in spherical angles and trigonometry
//! (cos ψ from the spherical law of cosines, the half angle from the half-angle formula, the
//! complex Fresnel equations with complex arithmetic), in f64. Every model is compared on 2 000
//! random direction pairs at 1e-4 relative.

use brdftab::testkit::Pcg32;
use brdftab::{Brdf, Channels, ModelSpec};
use glam::DVec3;
use std::f64::consts::PI;

/// A direction pair in spherical angles: (θ′, φ′) of the light wi, (θ, φ) of the viewer wo.
#[derive(Debug, Clone, Copy)]
struct Pair {
    ti: f64,
    pi: f64,
    to: f64,
    po: f64,
}

impl Pair {
    fn vectors(&self) -> (DVec3, DVec3) {
        let v = |t: f64, p: f64| DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
        (v(self.ti, self.pi), v(self.to, self.po))
    }

    /// cos ψ: the angle between wo and the mirror direction of wi, whose azimuth is φ′ + π.
    fn cos_psi(&self) -> f64 {
        self.ti.cos() * self.to.cos()
            + self.ti.sin() * self.to.sin() * (self.po - self.pi - PI).cos()
    }

    /// cos γ: the angle between wi and wo.
    fn cos_gamma(&self) -> f64 {
        self.ti.cos() * self.to.cos() + self.ti.sin() * self.to.sin() * (self.po - self.pi).cos()
    }
}

fn pairs(seed: u64, n: usize) -> Vec<Pair> {
    let mut r = Pcg32::new(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        // Uniform on the hemisphere (cos θ uniform); every third pair near the mirror
        // configuration, where the specular lobes are.
        let ti = r.next_f64().acos();
        let pi = 2.0 * PI * r.next_f64();
        let (to, po) = if out.len() % 3 == 0 {
            (
                (ti + 0.05 * (r.next_f64() - 0.5)).clamp(1e-3, 1.5),
                pi + PI + 0.05 * (r.next_f64() - 0.5),
            )
        } else {
            (r.next_f64().acos(), 2.0 * PI * r.next_f64())
        };
        if ti < 1.5 && to < 1.5 && ti > 1e-3 && to > 1e-3 {
            out.push(Pair { ti, pi, to, po });
        }
    }
    out
}

fn build(spec: &str) -> Box<dyn Brdf + Send + Sync> {
    ModelSpec::parse(spec)
        .and_then(|s| s.build(&Channels::Rgb))
        .unwrap_or_else(|e| panic!("{spec}: {e}"))
}

/// Compares the library's `spec` with `reference(pair, channel)` on 2 000 pairs.
fn compare(spec: &str, reference: impl Fn(&Pair, usize) -> f64) {
    let brdf = build(spec);
    let mut f = [0.0f32; 3];
    let (mut worst, mut compared) = (0.0f64, 0);
    for p in pairs(7, 2000) {
        let (wi, wo) = p.vectors();
        brdf.eval(wi, wo, &mut f);
        for (c, &got) in f.iter().enumerate() {
            let want = reference(&p, c);
            let err = (got as f64 - want).abs() / want.abs().max(1e-30);
            // f32 output: values below the f32 normal range carry no relative precision.
            if want.abs() > 1e-30 || got != 0.0 {
                assert!(
                    err < 1e-4 || (got as f64 - want).abs() < 1e-35,
                    "{spec}: channel {c} at {p:?}: library {got:e}, reference {want:e}"
                );
                compared += 1;
            }
            worst = worst.max(err.min(1.0));
        }
    }
    // Both sides zero everywhere would compare nothing.
    assert!(
        compared > 0,
        "{spec}: zero at every pair, library and reference"
    );
    eprintln!("{spec}: worst relative difference {worst:.2e}");
}

const KS: [f64; 3] = [0.2, 0.5, 0.8];

fn phong_family(name: &str, extra: &str, x: impl Fn(&Pair) -> f64) {
    for n in [1.0, 20.0, 500.0] {
        let spec = format!(r#"{{"model": "{name}", "ks": [0.2, 0.5, 0.8], "n": {n}{extra}}}"#);
        compare(&spec, |p, c| {
            let cos_psi = p.cos_psi();
            if cos_psi <= 0.0 {
                0.0
            } else {
                KS[c] * cos_psi.powf(n) / x(p)
            }
        });
    }
}

#[test]
fn lambert_is_kd() {
    compare(r#"{"model": "lambert", "kd": [0.1, 0.2, 0.3]}"#, |_, c| {
        [0.1f32, 0.2, 0.3][c] as f64
    });
}

#[test]
fn original_phong_is_ks_cos_n_psi_over_cos_theta_light() {
    phong_family("phong", "", |p| p.ti.cos());
}

#[test]
fn reciprocal_phong_is_ks_cos_n_psi() {
    phong_family("reciprocal_phong", "", |_| 1.0);
}

#[test]
fn max_phong_divides_by_the_larger_cosine() {
    phong_family("max_phong", "", |p| p.ti.cos().max(p.to.cos()));
}

#[test]
fn pumped_phong_divides_by_x() {
    phong_family("pumped_phong", r#", "x": "mean""#, |p| {
        (p.ti.cos() + p.to.cos()) / 2.0
    });
    phong_family("pumped_phong", r#", "x": "product""#, |p| {
        p.ti.cos() * p.to.cos()
    });
    phong_family("pumped_phong", r#", "x": "sqrt""#, |p| {
        (p.ti.cos() * p.to.cos()).sqrt()
    });
}

/// Minimal complex arithmetic for the Fresnel equations.
#[derive(Clone, Copy)]
struct C(f64, f64);

impl C {
    fn add(self, o: C) -> C {
        C(self.0 + o.0, self.1 + o.1)
    }
    fn sub(self, o: C) -> C {
        C(self.0 - o.0, self.1 - o.1)
    }
    fn mul(self, o: C) -> C {
        C(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    fn div(self, o: C) -> C {
        let d = o.0 * o.0 + o.1 * o.1;
        C(
            (self.0 * o.0 + self.1 * o.1) / d,
            (self.1 * o.0 - self.0 * o.1) / d,
        )
    }
    fn abs2(self) -> f64 {
        self.0 * self.0 + self.1 * self.1
    }
    /// Principal square root via polar form.
    fn sqrt(self) -> C {
        let r = self.abs2().sqrt().sqrt();
        let a = self.1.atan2(self.0) / 2.0;
        C(r * a.cos(), r * a.sin())
    }
}

/// The lecture's Fresnel function for unpolarized light: (F∥ + F⊥)/2 with the refraction angle
/// from Snell's law n + kj = sin θ′ / sin θ (complex).
fn fresnel(cos_in: f64, n: f64, k: f64) -> f64 {
    let eta = C(n, k);
    let sin2_in = 1.0 - cos_in * cos_in;
    // sin θ = sin θ′ / η  ⇒  cos θ = sqrt(1 − sin²θ′ / η²).
    let cos_t = C(1.0, 0.0).sub(C(sin2_in, 0.0).div(eta.mul(eta))).sqrt();
    let ci = C(cos_in, 0.0);
    let f_par = cos_t.sub(eta.mul(ci)).div(cos_t.add(eta.mul(ci))).abs2();
    let f_perp = ci.sub(eta.mul(cos_t)).div(ci.add(eta.mul(cos_t))).abs2();
    (f_par + f_perp) / 2.0
}

#[test]
fn fresnel_reference_has_the_textbook_limits() {
    // Normal incidence: |(η − 1)/(η + 1)|²; glass ≈ 0.04; grazing → 1.
    assert!((fresnel(1.0, 1.5, 0.0) - 0.04).abs() < 1e-12);
    let (n, k) = (0.2, 3.0);
    let normal = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
    assert!((fresnel(1.0, n, k) - normal).abs() < 1e-12);
    assert!(fresnel(1e-9, 1.5, 0.0) > 0.999_999);
}

#[test]
fn cook_torrance_is_beckmann_vcavity_fresnel() {
    // Gold-like complex index per RGB channel.
    let n = [0.18, 0.42, 1.37];
    let k = [3.42, 2.35, 1.77];
    for m in [0.05, 0.3, 0.8] {
        let spec = format!(
            r#"{{"model": "cook_torrance", "m": {m}, "ks": [0.9, 1.0, 0.7], "fresnel": {{"n": [0.18, 0.42, 1.37], "k": [3.42, 2.35, 1.77]}}}}"#
        );
        compare(&spec, |p, c| {
            let (cos_l, cos_v) = (p.ti.cos(), p.to.cos());
            // The half vector bisects the angle γ between L and V: L·H = V·H = cos(γ/2).
            let half = p.cos_gamma().acos() / 2.0;
            let lh = half.cos();
            let nh = (cos_l + cos_v) / (2.0 * lh);
            let alpha = nh.min(1.0).acos();
            // Normalized Beckmann: exp(−tan²α / m²) / (π m² cos⁴α).
            let d = (-(alpha.tan().powi(2)) / (m * m)).exp() / (PI * m * m * alpha.cos().powi(4));
            let g = (2.0 * nh * cos_v / lh).min(2.0 * nh * cos_l / lh).min(1.0);
            let f = fresnel(lh, n[c], k[c]);
            [0.9, 1.0, 0.7][c] * d * g * f / (4.0 * cos_v * cos_l)
        });
    }
}
