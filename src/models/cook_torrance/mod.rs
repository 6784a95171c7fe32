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
//! Importance sampling draws the V-cavity's *visible* normals (Heitz & d'Eon 2014): the facet
//! H of a cavity as V sees it, density G₁(V, H) ⟨V, H⟩⁺ D(H) / (N·V) with the V-cavity's own
//! G₁ = min(1, 2 (N·H)(N·V)/(V·H)). A cavity is the pair H, H′ (H turned by π about N); the
//! visible one of the pair is H with probability ⟨V,H⟩⁺ / (⟨V,H⟩⁺ + ⟨V,H′⟩⁺), so the density
//! is D(H) cos α · 2⟨V,H⟩⁺ / (⟨V,H⟩⁺ + ⟨V,H′⟩⁺): α keeps the marginal of D cos α (drawn as
//! the Beckmann distribution draws it), and the azimuth of H relative to V's has the density
//! (1 + k cos φ′)/2π, k = tan α tan θv, clipped to [0, 1/π] ([`visible`]). L = 2 (V·H) H
//! − V has density D(H) cos α / (2 (⟨V,H⟩⁺ + ⟨V,H′⟩⁺)) and weight f cos θl / pdf =
//! F · G(L, V) / G₁(V, H) ≤ F: Fresnel alone wherever L is not shadowed. A draw below the
//! horizon is folded back above it (z → −z) and its density is that of both preimages. On rough
//! surfaces the V-cavity shadows much of what the visible normals send towards the horizon, so
//! a share (m − 0.3) cos θv (at most ½ cos θv, none for m ≤ 0.3) of the draws is
//! cosine-weighted instead ([`CookTorrance::cosine_share`]); the density is the exact mixture.
//! (The half-vector draw this replaces, with a cosine share of min(m/2, ½), refused a third of
//! its draws at grazing views and reached a weight CV of 1.05 for gold, m = 0.3.)

use glam::{DVec2, DVec3};
use std::f64::consts::FRAC_1_PI;

use crate::brdf::{Brdf, BrdfSample, Flags};
use crate::error::Result;
use crate::fresnel::{Fresnel, FresnelSpec};
use crate::geometry;
use crate::spectrum::{Channels, Value};

use super::beckmann::Beckmann;
use super::visible;

/// Below this cos θv a visible-normal draw takes its density and weight from `pdf` and `eval`
/// of the drawn direction rather than from the drawn half vector (see `sample`).
const GRAZING_VIEW: f64 = 1e-4;

/// Above [`GRAZING_VIEW`], a visible-normal draw with V·H below this is refused. The draw
/// reflects V to L = 2 (V·H) H − V, nearly −V, whose half vector with V,
/// normalize(2 (V·H) H + rounding), is H only to ~ε / V·H: below 1e-6 `pdf` of the folded
/// direction no longer finds the density the draw had (with D's steepest slope,
/// d ln D / dα ≈ 600 at m = 0.01, 1e-10 rad is 6e-8 of it). Such draws lie at the rim of the
/// visible facets, tan α tan θv cos φ′ = −1 (the edge u.y = 0 of a view with tan α tan θv > 1
/// lands on it, V·H = 0 to rounding, and its density was 0.6–1.9× what `pdf` gives there).
/// The azimuth's density vanishes linearly at that rim, so the refused share of the draws is
/// ~MIN_VH² / (4π cos θv sin θv sin α): below 1e-9 from cos θv = 1e-4 on. (A grazing view's
/// draws are weighed by `pdf` itself, see `sample`.)
const MIN_VH: f64 = 1e-6;

/// A visible-normal draw whose half vector is closer to the normal than this, in units of
/// the lobe's width (tan α / max(m, [`MIN_TAN_M`])), is refused. There the fold's other
/// preimage, mirror_z(L), lies next to −V: its half vector, L′ + V, is the difference of
/// nearly opposite vectors, whose direction (which decides its density: it depends on the
/// azimuth the drawn half vector approaches the normal from) the draw takes from u.y and
/// `pdf` from the rounding of L: u.x = 0 draws α = 0 exactly, and its density was 5 % from
/// what `pdf` gives (2⁻⁵³ above it, 50 %). With tan² α = −m² ln(1 − u.x), the refused draws
/// are those with u.x ≲ 10⁻¹² (≲ 10⁻¹² (MIN_TAN_M/m)² below m = MIN_TAN_M, 1e-6 of them at
/// m = 1e-12). (A bound on tan α alone, 1e-6, refused the share 1 − e^(−10⁻¹²/m²) of the
/// draws: 1 % at m = 1e-5, 63 % at m = 1e-6, all of them from m = 1e-7 on, so a sampler's
/// estimate of a nearly ideal mirror read 0.99, 0.37 and 0 where its albedo is 1.)
const MIN_TAN: f64 = 1e-6;

/// The smallest lobe width [`MIN_TAN`] scales with: tan α ≥ 1e-15 keeps the drawn half
/// vector's tangential part, and so that of the other preimage's L′ + V, well above the
/// rounding of V's components (~1e-16), which would otherwise leave L′ + V pointing anywhere.
const MIN_TAN_M: f64 = 1e-9;

/// Cook-Torrance: k_s · D · G · F / (4 (N·V)(N·L)), normalized Beckmann D, V-cavity G, F at L·H.
#[derive(Debug, Clone)]
pub struct CookTorrance {
    channels: Channels,
    d: Beckmann,
    ks_spec: Value,
    ks: Vec<f64>,
    fresnel_spec: FresnelSpec,
    fresnel: Fresnel,
    /// (m − 0.3) clamped to [0, ½] ([`CookTorrance::cosine_share`]).
    cos_share: f64,
    /// The square of the smallest tan α a visible-normal draw keeps ([`MIN_TAN`]).
    min_tan2: f64,
}

/// The geometric part D·G / (4 (N·V)(N·L)) and the Fresnel cosine L·H of a pair.
struct Geometry {
    dg: f64,
    l_dot_h: f64,
}

impl CookTorrance {
    /// A Cook-Torrance model with Beckmann roughness `m` (> 0), scale `ks` (≥ 0) and Fresnel term.
    pub fn new(m: f64, ks: Value, fresnel: &FresnelSpec, channels: &Channels) -> Result<Self> {
        channels.validate()?;
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
            cos_share: (m - 0.3).clamp(0.0, 0.5),
            min_tan2: (MIN_TAN * m.max(MIN_TAN_M)).powi(2),
        })
    }

    /// The share of [`Brdf::sample`]'s draws from a view at cos θv = `cos_v` that are
    /// cosine-weighted rather than visible normals: (m − 0.3) clamped to [0, ½], times cos θv.
    /// On rough surfaces the V-cavity shadows much of what the visible normals send towards the
    /// horizon (weights G(L)/G₁(V) well below 1 there), most of all from views near the normal;
    /// the cosine share evens that out (m = 0.6, weight CV at 3°: 0.40 → 0.32). Glossy surfaces
    /// (m ≤ 0.3) and grazing views need none.
    pub fn cosine_share(&self, cos_v: f64) -> f64 {
        self.cos_share * cos_v
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

    /// The density with which the visible-normal draw gives direction `x` for unit `v`
    /// ([`visible::density`] with this model's D), `x` on either side of the horizon.
    #[inline]
    fn visible_density(&self, x: DVec3, v: DVec3) -> f64 {
        visible::density(x, v, |h| {
            self.d.d_tan2((h.x * h.x + h.y * h.y) / (h.z * h.z))
        })
    }

    /// The density of [`Brdf::sample`] at unit `l` above the horizon: both preimages of the
    /// fold.
    #[inline]
    fn folded_density(&self, l: DVec3, v: DVec3) -> f64 {
        self.visible_density(l, v) + self.visible_density(geometry::mirror_z(l), v)
    }

    /// D·G / (4 (N·V)(N·L)) and L·H for a pair, or `None` when invalid or below the horizon
    /// (D·G = 0 where D underflows).
    ///
    /// Written for speed with the half vector left unnormalized: with l, v unit and h = l + v,
    /// cos² α = h_z² / |h|², L·H = V·H = |h| / 2, and the V-cavity factor
    /// 2 (N·H) / (V·H) = 4 h_z / |h|². Two square roots and one division normalize the inputs,
    /// one root gives L·H, one division D and two G / (4 cos θl cos θv); every expression is
    /// symmetric in (l, v), so reciprocity holds bit for bit.
    #[inline(always)]
    fn geometry(&self, wi: DVec3, wo: DVec3) -> Option<Geometry> {
        let (l, v) = crate::geometry::upper_pair(wi, wo)?;
        let h = l + v;
        let hh = h.length_squared();
        let hz2 = h.z * h.z;
        // tan² α = (h_x² + h_y²) / h_z² and 1 / cos² α = 1 + tan² α. (As |h|²/h_z² − 1 it
        // cancelled below tan² α ≈ 1e-16: for m ≤ 1e-8 every half vector within ~1e-8 rad of
        // the normal read the peak of D, and the albedo of m = 1e-9 came out as 83.)
        let tan2 = (h.x * h.x + h.y * h.y) / hz2;
        let inv_c2 = 1.0 + tan2;
        let x = tan2 * self.d.inv_m2();
        if x.is_nan() || x >= 700.0 {
            // exp(−x) underflows (or h_z² did): D = 0, and inv_c2 may be infinite.
            return Some(Geometry {
                dg: 0.0,
                l_dot_h: 0.5 * hh.sqrt(),
            });
        }
        // Everything but exp(−x) is grouped into factors computed while `exp` runs, so only
        // one multiplication follows it on each output's dependency chain.
        let inv_hh = 1.0 / hh;
        // G / (4 cos θl cos θv) with G = min(4 h_z min(l_z, v_z) / |h|², 1), as
        // min(h_z / (|h|² max(l_z, v_z)), 1 / (4 l_z v_z)): the cosine G shares with the
        // denominator cancels before anything is multiplied, so a subnormal cosine cannot
        // underflow the product into a wrong or infinite f
        // (`weights_and_values_stay_bounded_at_subnormal_view_cosines`).
        let g_over = (h.z * inv_hh / l.z.max(v.z)).min(1.0 / (4.0 * l.z * v.z));
        let d_scale = self.d.inv_pi_m2() * (inv_c2 * inv_c2);
        let dg_scale = d_scale * g_over;
        let e = (-x).exp();
        Some(Geometry {
            dg: e * dg_scale,
            l_dot_h: 0.5 * hh.sqrt(),
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
        if !crate::spectrum::is_wavelength(nm) {
            return f64::NAN; // not a wavelength: no value (Channels::mix_at)
        }
        match self.geometry(wi, wo) {
            Some(g) => self.ks_spec.at(nm) * g.dg * self.fresnel.eval_at(g.l_dot_h, nm),
            None => 0.0,
        }
    }

    fn flags(&self) -> Flags {
        Flags::SMOOTH_SYMMETRIC
    }

    /// The quadrature's albedo, or where the lobe is far narrower than any quadrature
    /// resolves (m < 1e-6) and than the view's height above the horizon (m < 1e-3 cos θi), its
    /// m → 0 limit k_s F(cos θi): D tends to δ(H − N), where V·H = cos θi and the V-cavity's
    /// G = 1 (corrections of order (m / cos θi)²). Below m ≈ 1e-10 the Beckmann lobe, with no
    /// tails, fell between every node and the albedo read 0.
    fn albedo(&self, wi: DVec3, out: &mut [f64]) {
        let cos = geometry::normalize(wi).map_or(0.0, |w| w.z);
        if self.d.m < 1e-6 && self.d.m < 1e-3 * cos {
            for (c, o) in out[..self.ks.len()].iter_mut().enumerate() {
                *o = self.ks[c] * self.fresnel.eval(cos, c);
            }
            return;
        }
        crate::analysis::albedo::quadrature(self, wi, out)
    }

    /// False, although f_r is unbounded in one corner: where both directions near the horizon
    /// in the mirror configuration the V-cavity hides nothing (H = N, V·H = N·V, G = 1) and
    /// f_r = k_s D(N) F / (4 cos θi cos θo) grows like 1/cos² θ. Everywhere else f_r stays
    /// bounded at the horizon (G ≤ 2 (N·H)(N·V)/(V·H) cancels the 1/cos θo), and a table of
    /// f_r cos θi cos θo, whose lookup divides by the cosines, turns its interpolation residual
    /// at the horizon into f_r ∝ 1/cos θo for every light direction (gold, m = 0.3, θi = 42°:
    /// +13 % at θo = 89.9°, +68 % at 89.99°, 10¹² at 90°, where the source is 0.80). The table
    /// of f_r is off only in that corner (8 % at 89° on the mirror, 61 % low at 89.9°);
    /// BENCHMARKS.md, session 26.
    fn grows_at_horizon(&self) -> bool {
        false
    }

    fn describe(&self) -> String {
        format!(
            "cook_torrance m={} ks={} fresnel={}",
            self.d.m,
            serde_json::to_string(&self.ks_spec).unwrap_or_default(),
            serde_json::to_string(&self.fresnel_spec).unwrap_or_default()
        )
    }

    /// The V-cavity's visible normals, folded at the horizon (module docs): u.x draws α as the
    /// Beckmann distribution does (with D at the drawn normal, no `exp`), u.y the azimuth
    /// relative to V's ([`visible::normal`]). The density is that of both preimages of the
    /// result, the draw's own (from the inversion, no `exp`) and its mirror image's (one `exp`,
    /// none where the mirror image's half vector is below the horizon); f is the draw's where
    /// nothing folds and is evaluated at the folded direction where something does.
    /// `CookTorrance::folded_density` is the same density in plain terms (`pdf`; the contract
    /// tests hold them equal).
    fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
        let v = geometry::unit(wo)?;
        if v.z <= 0.0 || !geometry::in_unit_square(u) {
            return None;
        }
        let c = self.ks.len();
        let p = self.cosine_share(v.z);
        if u.x < p {
            let l = geometry::cosine_hemisphere(DVec2::new(u.x / p, u.y));
            if !(l.z > 0.0) {
                return None;
            }
            let gm = self.geometry(l, v)?;
            let pdf = (1.0 - p) * self.folded_density(l, v) + p * l.z * FRAC_1_PI;
            if !(pdf > 0.0 && pdf < f64::INFINITY) {
                return None;
            }
            self.fresnel
                .eval_scaled(gm.l_dot_h, &self.ks, gm.dg * l.z / pdf, &mut weight[..c]);
            return Some(BrdfSample {
                wi: l,
                pdf,
                delta: false,
            });
        }
        let one_minus = ((1.0 - u.x) / (1.0 - p)).max(f64::EPSILON);
        let tan2 = (-self.d.m * self.d.m * crate::fastmath::ln(one_minus)).max(0.0);
        if tan2 < self.min_tan2 {
            return None;
        }
        let inv_c2 = 1.0 + tan2;
        let cos_a = 1.0 / inv_c2.sqrt();
        let tan_a = tan2.sqrt();
        // D = exp(−tan² α/m²) / (π m² cos⁴ α) with exp(−tan² α/m²) = 1 − u.x.
        let d = one_minus * self.d.inv_pi_m2() * (inv_c2 * inv_c2);
        let h = visible::normal(cos_a, tan_a, v, u.y);
        let vh = v.dot(h);
        if !(vh > 0.0) || (vh < MIN_VH && v.z >= GRAZING_VIEW) {
            return None;
        }
        let p_drawn = d * cos_a / (2.0 * (vh + visible::partner_dot(v, h)));
        let drawn = (2.0 * vh) * h - v;
        let other = geometry::mirror_z(drawn);
        let (l, dg, l_dot_h, pdf) = if drawn.z > 0.0 {
            // f at the drawn normal: D·G / (4 cos θl cos θv), L·H = V·H, with
            // G = min(2 cos α min(l_z, v_z) / (V·H), 1) cancelled as in `geometry`.
            let g_over = (cos_a / (2.0 * vh * drawn.z.max(v.z))).min(1.0 / (4.0 * drawn.z * v.z));
            let dg = d * g_over;
            (
                drawn,
                dg,
                vh,
                (1.0 - p) * (p_drawn + self.visible_density(other, v)) + p * drawn.z * FRAC_1_PI,
            )
        } else {
            if !(other.z > 0.0) {
                return None;
            }
            let gm = self.geometry(other, v)?;
            (
                other,
                gm.dg,
                gm.l_dot_h,
                (1.0 - p) * (p_drawn + self.visible_density(other, v)) + p * other.z * FRAC_1_PI,
            )
        };
        if v.z < GRAZING_VIEW {
            // The drawn direction's density and value recomputed from the direction itself, as
            // `pdf` and `eval` see it: at a grazing view V·H is small and the half vector of the
            // rounded direction differs from the drawn one by up to 50 % in density at
            // cos θv = 1e-12 (1e-4 at 1e-10 for m = 0.01), where they agree to 1e-9 above 1e-4.
            let pdf = self.pdf(l, v);
            if !(pdf > 0.0 && pdf < f64::INFINITY) {
                return None;
            }
            self.eval(l, v, &mut weight[..c]);
            for w in &mut weight[..c] {
                *w = (*w as f64 * (l.z / pdf)) as f32;
            }
            return Some(BrdfSample {
                wi: l,
                pdf,
                delta: false,
            });
        }
        if !(pdf > 0.0 && pdf < f64::INFINITY) {
            return None;
        }
        self.fresnel
            .eval_scaled(l_dot_h, &self.ks, dg * l.z / pdf, &mut weight[..c]);
        Some(BrdfSample {
            wi: l,
            pdf,
            delta: false,
        })
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        match geometry::upper_pair(wi, wo) {
            Some((l, v)) => {
                let p = self.cosine_share(v.z);
                (1.0 - p) * self.folded_density(l, v) + p * l.z * FRAC_1_PI
            }
            None => 0.0,
        }
    }
}

#[cfg(test)]
mod tests;
