//! The Cook-Torrance model as the lecture derives it.
//!
//! The surface is a collection of randomly oriented perfect mirrors. A photon is reflected from
//! L to V when (1) the facet it meets has normal H = normalize(L + V) — probability
//! Pr(H) dω_H with dω_H/dω = 1/(4 (H·L)); (2) it is neither masked nor shadowed — the V-cavity
//! G(N, L, V) = min(1, 2(N·H)(N·V)/(V·H), 2(N·H)(N·L)/(L·H)); (3) it is not absorbed — the
//! Fresnel term F(L·H, λ). Dividing the probability by dω and by N·L gives
//!
//! ```text
//! f_r(L, V) = k_s · D(H) · G(N, L, V) · F(L·H, λ) / (4 (N·V)(N·L))
//! ```
//!
//! with the *normalized* Beckmann D = exp(−tan² α / m²) / (π m² cos⁴ α) ([`Beckmann`]), so that
//! with G = F = k_s = 1 the model is a proper microfacet BRDF. (The lecture's warning holds: the
//! V-cavity G lets the albedo grow at grazing angles.)
//!
//! Importance sampling draws H with density D(H) cos α and reflects V about it; the density of L
//! is D cos α / (4 |V·H|), and the weight of that strategy alone, f·cos θ′/pdf =
//! k_s G F (V·H) / ((N·V)(N·H)) ≤ 2 k_s F, is bounded. For rough surfaces many reflected
//! directions fall below the horizon (more than half at m = 1.2 and normal incidence), so a
//! fraction [`CookTorrance::cosine_prob`] = min(m/2, 1/2) of the samples is drawn cosine-weighted
//! instead; the reported pdf is the exact mixture density.

use glam::{DVec2, DVec3};
use std::f64::consts::FRAC_1_PI;

use crate::brdf::{Brdf, BrdfSample, Flags};
use crate::error::Result;
use crate::fresnel::{Fresnel, FresnelSpec};
use crate::geometry;
use crate::spectrum::{Channels, Value};

use super::beckmann::Beckmann;

/// Cook-Torrance: k_s · D · G · F / (4 (N·V)(N·L)), normalized Beckmann D, V-cavity G, F at L·H.
#[derive(Debug, Clone)]
pub struct CookTorrance {
    channels: Channels,
    d: Beckmann,
    ks_spec: Value,
    ks: Vec<f64>,
    fresnel_spec: FresnelSpec,
    fresnel: Fresnel,
    cos_prob: f64,
    /// 1 / (1 − cos_prob), to rescale u.x in the half-vector branch.
    inv_1mp: f64,
}

/// The geometric part D·G / (4 (N·V)(N·L)) and the Fresnel cosine L·H of a pair.
struct Geometry {
    dg: f64,
    l_dot_h: f64,
    /// The half-vector strategy's density D cos α / (4 V·H).
    d_cos_over_4vh: f64,
    /// cos θ of the (normalized) first direction.
    l_z: f64,
}

impl CookTorrance {
    /// A Cook-Torrance model with Beckmann roughness `m` (> 0), scale `ks` (≥ 0) and Fresnel term.
    pub fn new(m: f64, ks: Value, fresnel: &FresnelSpec, channels: &Channels) -> Result<Self> {
        if !m.is_finite() || m <= 0.0 {
            return Err(crate::Error::spec(
                "m",
                format!("{m} must be a finite number > 0"),
            ));
        }
        crate::spectrum::check_range(m, "m")?;
        ks.validate("ks", 0.0)?;
        Ok(CookTorrance {
            channels: channels.clone(),
            d: Beckmann::new(m),
            ks: ks.resolve(channels),
            ks_spec: ks,
            fresnel: Fresnel::new(fresnel, channels, "fresnel")?,
            fresnel_spec: fresnel.clone(),
            cos_prob: (0.5 * m).min(0.5),
            inv_1mp: 1.0 / (1.0 - (0.5 * m).min(0.5)),
        })
    }

    /// Probability with which [`Brdf::sample`] draws a cosine-weighted direction instead of a
    /// Beckmann half vector: min(m/2, 1/2).
    pub fn cosine_prob(&self) -> f64 {
        self.cos_prob
    }

    /// The microfacet distribution.
    pub fn distribution(&self) -> &Beckmann {
        &self.d
    }

    /// V-cavity masking-shadowing, the lecture's
    /// G = min(1, 2(N·H)(N·V)/(V·H), 2(N·H)(N·L)/(L·H)); note V·H = L·H.
    #[inline]
    pub fn g(n_dot_h: f64, n_dot_v: f64, n_dot_l: f64, v_dot_h: f64) -> f64 {
        let k = 2.0 * n_dot_h / v_dot_h;
        (k * n_dot_v).min(k * n_dot_l).min(1.0)
    }

    /// D·G / (4 (N·V)(N·L)) and L·H for a pair, or `None` when invalid or below the horizon
    /// (D·G = 0 where D underflows).
    ///
    /// Written for speed with the half vector left unnormalized: with l, v unit and h = l + v,
    /// cos² α = h_z² / |h|², L·H = V·H = |h| / 2, and the V-cavity factor
    /// 2 (N·H) / (V·H) = 4 h_z / |h|². Two square roots and one division normalize the inputs,
    /// one root gives L·H, one division each D, G and the final quotient; every expression is
    /// symmetric in (l, v), so reciprocity holds bit for bit.
    #[inline(always)]
    fn geometry(&self, wi: DVec3, wo: DVec3) -> Option<Geometry> {
        let (l, v) = super::unit_upper_pair(wi, wo)?;
        let h = l + v;
        let hh = h.length_squared();
        let hz2 = h.z * h.z;
        // 1 / cos² α and tan² α = 1/cos² α − 1.
        let inv_c2 = hh / hz2;
        let x = (inv_c2 - 1.0) * self.d.inv_m2();
        if x.is_nan() || x >= 700.0 {
            // exp(−x) underflows (or h_z² did): D = 0, and inv_c2 may be infinite.
            return Some(Geometry {
                dg: 0.0,
                l_dot_h: 0.5 * hh.sqrt(),
                d_cos_over_4vh: 0.0,
                l_z: l.z,
            });
        }
        // Everything but exp(−x) is grouped into factors computed while `exp` runs, so only
        // one multiplication follows it on each output's dependency chain.
        let inv_hh = 1.0 / hh;
        let g = (4.0 * h.z * inv_hh * l.z.min(v.z)).min(1.0);
        let d_scale = self.d.inv_pi_m2() * (inv_c2 * inv_c2);
        let dg_scale = d_scale * (g / (4.0 * l.z * v.z));
        // D cos α / (4 V·H) with cos α = h_z/|h| and V·H = |h|/2.
        let pdf_scale = d_scale * (0.5 * h.z * inv_hh);
        let e = (-x).exp();
        Some(Geometry {
            dg: e * dg_scale,
            l_dot_h: 0.5 * hh.sqrt(),
            d_cos_over_4vh: e * pdf_scale,
            l_z: l.z,
        })
    }
}

impl Brdf for CookTorrance {
    fn channels(&self) -> &Channels {
        &self.channels
    }

    #[inline]
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let out = &mut out[..self.ks.len()];
        let Some(g) = self.geometry(wi, wo) else {
            out.fill(0.0);
            return;
        };
        self.fresnel.eval_scaled(g.l_dot_h, &self.ks, g.dg, out);
    }

    fn eval_wavelength(&self, wi: DVec3, wo: DVec3, nm: f64) -> f64 {
        match self.geometry(wi, wo) {
            Some(g) => self.ks_spec.at(nm) * g.dg * self.fresnel.eval_at(g.l_dot_h, nm),
            None => 0.0,
        }
    }

    fn flags(&self) -> Flags {
        Flags::SMOOTH_SYMMETRIC
    }

    fn describe(&self) -> String {
        format!(
            "cook_torrance m={} ks={} fresnel={}",
            self.d.m,
            serde_json::to_string(&self.ks_spec).unwrap_or_default(),
            serde_json::to_string(&self.fresnel_spec).unwrap_or_default()
        )
    }

    /// Half-vector sampling of D(H) cos θh (L = 2(V·H)H − V, density D cos θh / (4 |V·H|)),
    /// mixed with cosine sampling with probability [`CookTorrance::cosine_prob`].
    ///
    /// The half-vector branch is fused: D comes with the sampled normal
    /// ([`Beckmann::sample_h_d`]), so f, the mixture pdf and the weight cost no `exp` and no
    /// renormalization; the cosine branch evaluates the model as `eval` and `pdf` do.
    fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
        let v = geometry::unit(wo)?;
        if v.z <= 0.0 {
            return None;
        }
        let p = self.cos_prob;
        let c = self.ks.len();
        if u.x >= p {
            // 1 − u0 for u0 = (u.x − p)/(1 − p), the half-vector branch's rescaled u.x; at least
            // ε so that the logarithm stays finite.
            let one_minus = ((1.0 - u.x) * self.inv_1mp).max(f64::EPSILON);
            // With the slope-space normal h′ = H / cos α (|h′|² = 1/cos² α): V·H = (V·h′) cos α
            // and L = 2 (V·H) H − V = 2 (V·h′) cos² α h′ − V. Every factor cos α cancels from
            // the pdf and the weight below, so H is never normalized.
            let (hp, cos2, d) = self.d.slope_d(one_minus, u.y);
            let vhp = v.dot(hp);
            if !(vhp > 0.0) {
                return None;
            }
            let l = (2.0 * vhp * cos2) * hp - v;
            if !(l.z > 0.0) {
                return None;
            }
            // pdf = (1−p) D cos α / (4 V·H) + p cos θl / π = den / (4 V·h′), and
            // f cos θl / pdf = D G (V·H) / ((N·V) den) · … with G·(V·h′) = min(V·h′, 2 min(N·V, N·L)):
            // two independent divisions, no reciprocal of V·H.
            let den = (1.0 - p) * d + 4.0 * vhp * p * l.z * FRAC_1_PI;
            let pdf = den / (4.0 * vhp);
            if !(pdf > 0.0 && pdf < f64::INFINITY) {
                return None;
            }
            let s = d * vhp.min(2.0 * v.z.min(l.z)) / (v.z * den);
            // Fresnel at V·H = (V·h′) cos α, computed off the critical path.
            let v_dot_h = vhp * cos2.sqrt();
            self.fresnel
                .eval_scaled(v_dot_h, &self.ks, s, &mut weight[..c]);
            return Some(BrdfSample {
                wi: l,
                pdf,
                delta: false,
            });
        }
        let l = geometry::cosine_hemisphere(DVec2::new(u.x / p, u.y));
        if l.z.is_nan() || l.z <= 0.0 {
            return None;
        }
        // Cosine branch: one pass of `geometry` gives f's D·G and, since D cos α / (4 V·H) =
        // D·(h_z/|h|)/(2|h|) with the unnormalized h = l + v, the half-vector density too.
        let gm = self.geometry(l, v)?;
        let pdf = (1.0 - p) * gm.d_cos_over_4vh + p * l.z * FRAC_1_PI;
        if !(pdf > 0.0 && pdf < f64::INFINITY) {
            return None;
        }
        self.fresnel
            .eval_scaled(gm.l_dot_h, &self.ks, gm.dg * l.z / pdf, &mut weight[..c]);
        Some(BrdfSample {
            wi: l,
            pdf,
            delta: false,
        })
    }

    /// One pass of the shared geometry gives f and the half-vector density.
    fn eval_pdf(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) -> f64 {
        let out = &mut out[..self.ks.len()];
        let Some(g) = self.geometry(wi, wo) else {
            out.fill(0.0);
            return 0.0;
        };
        self.fresnel.eval_scaled(g.l_dot_h, &self.ks, g.dg, out);
        let p = self.cos_prob;
        (1.0 - p) * g.d_cos_over_4vh + p * g.l_z * FRAC_1_PI
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        match self.geometry(wi, wo) {
            Some(g) => {
                let p = self.cos_prob;
                (1.0 - p) * g.d_cos_over_4vh + p * g.l_z * FRAC_1_PI
            }
            None => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_formula_at_a_hand_computed_pair() {
        let m = 0.3;
        let ct =
            CookTorrance::new(m, Value::Grey(0.8), &FresnelSpec::None, &Channels::Rgb).unwrap();
        let l = geometry::spherical(0.5, 0.2);
        let v = geometry::spherical(0.3, 2.9);
        let h = (l + v).normalize();
        let tan2 = (1.0 - h.z * h.z) / (h.z * h.z);
        let d = (-tan2 / (m * m)).exp() / (std::f64::consts::PI * m * m * h.z.powi(4));
        let g = 1f64
            .min(2.0 * h.z * v.z / v.dot(h))
            .min(2.0 * h.z * l.z / l.dot(h));
        let expect = 0.8 * d * g / (4.0 * v.z * l.z);
        let mut f = [0.0f32; 3];
        ct.eval(l, v, &mut f);
        assert!(
            (f[0] as f64 - expect).abs() < 1e-6 * expect,
            "{} vs {expect}",
            f[0]
        );
    }

    #[test]
    fn fresnel_is_taken_at_l_dot_h_per_channel() {
        let spec = FresnelSpec::Conductor("Au".into());
        let ct = CookTorrance::new(0.2, Value::Grey(1.0), &spec, &Channels::Rgb).unwrap();
        let plain =
            CookTorrance::new(0.2, Value::Grey(1.0), &FresnelSpec::None, &Channels::Rgb).unwrap();
        let l = geometry::spherical(0.7, 0.0);
        let v = geometry::spherical(0.5, 2.5);
        let lh = l.dot((l + v).normalize());
        let fr = Fresnel::new(&spec, &Channels::Rgb, "f").unwrap();
        let (mut a, mut b) = ([0.0f32; 3], [0.0f32; 3]);
        ct.eval(l, v, &mut a);
        plain.eval(l, v, &mut b);
        for c in 0..3 {
            let expect = b[c] as f64 * fr.eval(lh, c);
            assert!((a[c] as f64 - expect).abs() < 1e-6 * expect);
        }
        // Gold is redder than blue.
        assert!(a[0] > a[2]);
        // The spectral path agrees with the channel at the representative wavelength.
        let at = ct.eval_wavelength(l, v, crate::spectrum::RGB_WAVELENGTHS[0]);
        assert!((at - a[0] as f64).abs() < 1e-6 * at);
    }

    #[test]
    fn v_cavity_g_is_in_unit_interval() {
        let mut rng = crate::rng::Pcg32::new(5);
        for _ in 0..10_000 {
            let l = geometry::uniform_hemisphere(rng.next_dvec2());
            let v = geometry::uniform_hemisphere(rng.next_dvec2());
            let h = (l + v).normalize();
            let g = CookTorrance::g(h.z, v.z, l.z, v.dot(h));
            assert!((0.0..=1.0).contains(&g), "{g}");
        }
    }

    #[test]
    fn invalid_inputs_give_zero() {
        let ct =
            CookTorrance::new(0.3, Value::Grey(1.0), &FresnelSpec::None, &Channels::Rgb).unwrap();
        for (wi, wo) in [
            (DVec3::new(0.0, 0.0, -1.0), DVec3::Z),
            (DVec3::Z, DVec3::new(1.0, 0.0, 0.0)),
            (DVec3::ZERO, DVec3::Z),
            (DVec3::new(f64::NAN, 0.0, 1.0), DVec3::Z),
        ] {
            let mut f = [1.0f32; 3];
            ct.eval(wi, wo, &mut f);
            assert_eq!(f, [0.0; 3]);
            assert_eq!(ct.pdf(wi, wo), 0.0);
        }
        // Directions so close to the horizon that h_z² underflows: 0, not NaN.
        let mut f = [1.0f32; 3];
        ct.eval(
            DVec3::new(1.0, 0.0, 1e-200),
            DVec3::new(-1.0, 0.1, 1e-200),
            &mut f,
        );
        assert_eq!(f, [0.0; 3]);
        ct.eval(
            DVec3::new(1.0, 0.0, 1e-200),
            DVec3::new(1.0, 0.0, 1e-200),
            &mut f,
        );
        assert!(f.iter().all(|x| x.is_finite()), "{f:?}");
        assert!(
            CookTorrance::new(0.0, Value::Grey(1.0), &FresnelSpec::None, &Channels::Rgb).is_err()
        );
    }
}
