//! Data-adaptive axis warps: where a measured material needs its nodes.
//!
//! Measured BRDFs put their detail in a few places — a near-mirror peak a fraction of a degree
//! wide in θh, a Fresnel rise at grazing θd — and are flat elsewhere. A fixed mapping (uniform,
//! square root, cosine) either wastes nodes on the flat parts or misses the peak. A [`Warp`] is a
//! mapping x → u ∈ [0, 1] built from the data: the node density follows the data's own
//! interpolation error ([`Warp::from_density`]), so a small table resolves the peak. The table
//! is still the design's dense table, with nodes at u = i/(n − 1) of a warped axis
//! ([`Mapping::Warp`](super::Mapping::Warp), [`Nodes::Edges`](super::Nodes::Edges)).
//!
//! A warp is piecewise linear in a cheap *variable* v ∈ [0, 1] of the angle ([`WarpVar`]) on
//! K + 1 knots uniform in v, so a lookup costs one multiply, one truncation and one linear
//! interpolation per axis — O(1), no search. The variables are chosen so that the fast lookup
//! ([`super::kernel`]) computes them from the direction vectors with square roots and one
//! division instead of acos and atan2:
//!
//! - θ axes: v = (sin θ)^½ ([`WarpVar::SqrtSine`], ≈ √θ: dense near θ = 0, for θh) or
//!   v = (1 − cos θ)^½ ([`WarpVar::HalfPower`], ≈ uniform in θ, for θd); v(π/2) = 1.
//! - a φ axis folded onto [0, π] (bilateral symmetry): the pseudo-angle
//!   v = ½ − ½ cos φ / (|cos φ| + |sin φ|) ([`WarpVar::PseudoAngle`]), monotone in φ, or
//!   its double on [0, π/2] (bilateral symmetry and reciprocity).

use std::hash::{Hash, Hasher};
use std::sync::Arc;

use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI};

use crate::error::{Error, Result};

/// The cheap variable v ∈ [0, 1] a [`Warp`] is piecewise linear in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WarpVar {
    /// v = (sin θ)^½ on θ ∈ [0, π/2]: about √θ near 0 (a near-mirror peak at θh = 0). From
    /// vectors: sin²θh = (h_x² + h_y²)/|h|², a quotient and two square roots.
    SqrtSine,
    /// v = (1 − cos θ)^½ = √2 sin(θ/2) on θ ∈ [0, π/2]: within 11% of uniform in θ.
    HalfPower,
    /// v = (1 − cos θ)^¼ on θ ∈ [0, π/2]: about √θ near 0 like [`WarpVar::SqrtSine`], but
    /// with a finite slope at π/2 (1/4 per radian), where (sin θ)^½ is flat — a θh axis in it
    /// can place nodes at 89° and 90°, which the grazing near-mirror peak needs. From vectors:
    /// 1 − cos θh = (hx² + hy²)/(|h|(|h| + hz)), a quotient and two square roots.
    QuarterPower,
    /// The pseudo-angle of φ on a folded φ axis [0, hi], hi = π or π/2:
    /// p(φ) = ½ − ½ cos φ / (|cos φ| + |sin φ|), v = p(φ)/p(hi).
    PseudoAngle,
}

impl WarpVar {
    /// v of angle `x` on an axis whose domain is [0, `hi`] (the reference definition; the fast
    /// lookup computes the same v from vectors).
    pub fn of_angle(self, x: f64, hi: f64) -> f64 {
        match self {
            WarpVar::SqrtSine => x.sin().max(0.0).sqrt(),
            // 1 − cos x = 2 sin²(x/2), without cancellation near 0.
            WarpVar::HalfPower => (2.0f64.sqrt() * (0.5 * x).sin()).abs(),
            WarpVar::QuarterPower => (2.0f64.sqrt() * (0.5 * x).sin()).abs().sqrt(),
            WarpVar::PseudoAngle => pseudo(x) / pseudo(hi),
        }
    }

    /// The angle of v (inverse of [`WarpVar::of_angle`]).
    pub fn angle_of(self, v: f64, hi: f64) -> f64 {
        let v = v.clamp(0.0, 1.0);
        match self {
            WarpVar::SqrtSine => (v * v).asin(),
            // x = acos(1 − y) = 2 asin(√(y/2)), y = 1 − cos x.
            WarpVar::HalfPower => 2.0 * (v * std::f64::consts::FRAC_1_SQRT_2).asin(),
            WarpVar::QuarterPower => 2.0 * (v * v * std::f64::consts::FRAC_1_SQRT_2).asin(),
            WarpVar::PseudoAngle => {
                let p = v * pseudo(hi);
                // p(φ) = sin/(2(cos + sin)) on [0, π/2]; p(π − φ) = 1 − p(φ).
                let first = |p: f64| (2.0 * p).atan2(1.0 - 2.0 * p);
                if p <= 0.5 {
                    first(p)
                } else {
                    PI - first(1.0 - p)
                }
            }
        }
    }

    /// The domain end the variable is normalized to on a θ axis (π/2) or the folded φ end.
    fn check_domain(self, hi: f64) -> Result<()> {
        let ok = match self {
            WarpVar::SqrtSine | WarpVar::HalfPower | WarpVar::QuarterPower => {
                (hi - FRAC_PI_2).abs() < 1e-12
            }
            WarpVar::PseudoAngle => (hi - PI).abs() < 1e-12 || (hi - FRAC_PI_2).abs() < 1e-12,
        };
        if ok {
            Ok(())
        } else {
            Err(Error::arg(
                "grid",
                format!("a {self:?} warp does not fit an axis over [0, {hi}]"),
            ))
        }
    }
}

/// p(φ) = ½ − ½ cos φ / (|cos φ| + |sin φ|) for φ ∈ [0, π]: 0, ½, 1 at 0, π/2, π.
fn pseudo(phi: f64) -> f64 {
    let (s, c) = phi.sin_cos();
    let d = c.abs() + s.abs();
    if d > 0.0 { 0.5 - 0.5 * c / d } else { 0.0 }
}

/// A data-adaptive mapping x → u ∈ [0, 1]: piecewise linear in v = `var`(x) on K + 1 knots
/// uniform in v (see the module docs). Cheap to clone (the knots are shared).
#[derive(Clone, Serialize, Deserialize)]
#[serde(try_from = "WarpRepr", into = "WarpRepr")]
pub struct Warp {
    var: WarpVar,
    /// u at v = k/K, k = 0..=K: 0 first, 1 last, strictly increasing.
    knots: Arc<[f32]>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct WarpRepr {
    var: WarpVar,
    knots: Vec<f32>,
}

impl TryFrom<WarpRepr> for Warp {
    type Error = Error;
    fn try_from(r: WarpRepr) -> Result<Warp> {
        Warp::new(r.var, r.knots)
    }
}

impl From<Warp> for WarpRepr {
    fn from(w: Warp) -> WarpRepr {
        WarpRepr {
            var: w.var,
            knots: w.knots.to_vec(),
        }
    }
}

impl std::fmt::Debug for Warp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Warp({:?}, {} knots)", self.var, self.knots.len())
    }
}

impl PartialEq for Warp {
    fn eq(&self, o: &Warp) -> bool {
        self.var == o.var
            && self.knots.len() == o.knots.len()
            && self
                .knots
                .iter()
                .zip(o.knots.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits())
    }
}

impl Eq for Warp {}

impl Hash for Warp {
    fn hash<H: Hasher>(&self, h: &mut H) {
        self.var.hash(h);
        for k in self.knots.iter() {
            k.to_bits().hash(h);
        }
    }
}

impl Warp {
    /// A warp from its knots (u at v = k/K): at least 2, the first 0, the last 1, strictly
    /// increasing and finite.
    pub fn new(var: WarpVar, knots: Vec<f32>) -> Result<Warp> {
        let bad = |m: &str| Err(Error::arg("warp", m.to_string()));
        if knots.len() < 2 || knots.len() > 1 << 16 {
            return bad("a warp needs 2 to 65536 knots");
        }
        if knots[0] != 0.0 || knots[knots.len() - 1] != 1.0 {
            return bad("a warp's knots must run from 0 to 1");
        }
        if !knots.windows(2).all(|w| w[1] > w[0]) {
            return bad("a warp's knots must increase strictly");
        }
        Ok(Warp {
            var,
            knots: knots.into(),
        })
    }

    /// The identity in v (u = v), e.g. before the data are known.
    pub fn identity(var: WarpVar) -> Warp {
        Warp {
            var,
            knots: vec![0.0, 1.0].into(),
        }
    }

    /// A warp whose node density follows `density`: `density[j]` ≥ 0 is the wanted density of
    /// nodes on the j-th of M equal cells of v. It is normalized, blended with a uniform
    /// density of weight `floor` ∈ (0, 1] (so that no region is left without nodes and the knots
    /// increase strictly), integrated, and sampled at `knots` + 1 knots.
    pub fn from_density(var: WarpVar, density: &[f64], knots: usize, floor: f64) -> Result<Warp> {
        if density.is_empty() || knots == 0 || !(floor > 0.0 && floor <= 1.0) {
            return Err(Error::arg(
                "warp",
                "a density needs cells, knots and a floor in (0, 1]",
            ));
        }
        let m = density.len();
        let sane = |d: f64| if d.is_finite() && d > 0.0 { d } else { 0.0 };
        let total: f64 = density.iter().map(|&d| sane(d)).sum();
        let cell = |j: usize| {
            let d = if total > 0.0 {
                sane(density[j]) / total * m as f64
            } else {
                1.0
            };
            (1.0 - floor) * d + floor
        };
        // Cumulative density at the M + 1 cell edges, then normalized to [0, 1].
        let mut cdf = Vec::with_capacity(m + 1);
        cdf.push(0.0);
        for j in 0..m {
            cdf.push(cdf[j] + cell(j));
        }
        let end = cdf[m];
        let mut k = Vec::with_capacity(knots + 1);
        for i in 0..=knots {
            let t = i as f64 / knots as f64 * m as f64;
            let j = (t as usize).min(m - 1);
            let u = cdf[j] + (t - j as f64) * (cdf[j + 1] - cdf[j]);
            k.push((u / end) as f32);
        }
        k[0] = 0.0;
        k[knots] = 1.0;
        // f32 rounding of nearly equal knots: keep them strictly increasing.
        for i in 1..knots {
            if k[i] <= k[i - 1] {
                k[i] = f32::from_bits(k[i - 1].to_bits() + 1);
            }
        }
        if knots > 1 && k[knots - 1] >= 1.0 {
            return Err(Error::arg("warp", "knots too crowded for f32"));
        }
        Warp::new(var, k)
    }

    /// The variable the warp is piecewise linear in.
    pub fn var(&self) -> WarpVar {
        self.var
    }

    /// u at the knots v = k/K.
    pub fn knots(&self) -> &[f32] {
        &self.knots
    }

    /// Checks that the warp fits an axis over [0, `hi`].
    pub fn check_domain(&self, hi: f64) -> Result<()> {
        self.var.check_domain(hi)
    }

    /// u of variable v ∈ [0, 1] (clamped): linear between knots.
    #[inline]
    pub fn u_of_v(&self, v: f64) -> f64 {
        let k = &self.knots;
        let n = k.len() - 1;
        let t = v.clamp(0.0, 1.0) * n as f64;
        let j = (t as usize).min(n - 1);
        let (a, b) = (k[j] as f64, k[j + 1] as f64);
        a + (t - j as f64) * (b - a)
    }

    /// v of u ∈ [0, 1] (inverse of [`Warp::u_of_v`]; a binary search, for baking).
    pub fn v_of_u(&self, u: f64) -> f64 {
        let k = &self.knots;
        let n = k.len() - 1;
        let u = u.clamp(0.0, 1.0);
        // The last knot j with k[j] ≤ u, at most n − 1.
        let j = k.partition_point(|&x| (x as f64) <= u).clamp(1, n) - 1;
        let (a, b) = (k[j] as f64, k[j + 1] as f64);
        (j as f64 + ((u - a) / (b - a)).clamp(0.0, 1.0)) / n as f64
    }

    /// u of angle `x` on an axis over [0, `hi`].
    #[inline]
    pub fn u_of_angle(&self, x: f64, hi: f64) -> f64 {
        self.u_of_v(self.var.of_angle(x, hi))
    }

    /// The angle at u (inverse of [`Warp::u_of_angle`]).
    pub fn angle_of_u(&self, u: f64, hi: f64) -> f64 {
        self.var.angle_of(self.v_of_u(u), hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variables_invert() {
        for var in [WarpVar::SqrtSine, WarpVar::HalfPower, WarpVar::QuarterPower] {
            for i in 0..=100 {
                let x = i as f64 / 100.0 * FRAC_PI_2;
                let v = var.of_angle(x, FRAC_PI_2);
                assert!((0.0..=1.0 + 1e-15).contains(&v));
                // asin(v²) near v = 1 (θ → π/2, where sin is flat) keeps about half the digits.
                let tol = if var == WarpVar::SqrtSine {
                    1e-7
                } else {
                    1e-14
                };
                assert!((var.angle_of(v, FRAC_PI_2) - x).abs() < tol, "{var:?} {x}");
            }
        }
        for hi in [PI, FRAC_PI_2] {
            for i in 0..=100 {
                let x = i as f64 / 100.0 * hi;
                let v = WarpVar::PseudoAngle.of_angle(x, hi);
                assert!((WarpVar::PseudoAngle.angle_of(v, hi) - x).abs() < 1e-12);
            }
            assert_eq!(WarpVar::PseudoAngle.of_angle(0.0, hi), 0.0);
            assert!((WarpVar::PseudoAngle.of_angle(hi, hi) - 1.0).abs() < 1e-15);
        }
    }

    #[test]
    fn pseudo_angle_is_monotone() {
        let mut last = -1.0;
        for i in 0..=1000 {
            let p = pseudo(i as f64 / 1000.0 * PI);
            assert!(p > last);
            last = p;
        }
    }

    #[test]
    fn a_uniform_density_is_the_identity() {
        let w = Warp::from_density(WarpVar::HalfPower, &[1.0; 64], 32, 0.1).unwrap();
        for i in 0..=32 {
            let v = i as f64 / 32.0;
            assert!((w.u_of_v(v) - v).abs() < 1e-6);
        }
    }

    #[test]
    fn nodes_crowd_where_the_density_is() {
        // All the density on the first tenth of v: with floor 0.2, u(0.1) = 0.8 + 0.2·0.1.
        let mut d = vec![0.0; 100];
        d[..10].fill(1.0);
        let w = Warp::from_density(WarpVar::SqrtSine, &d, 100, 0.2).unwrap();
        assert!((w.u_of_v(0.1) - 0.82).abs() < 1e-6);
        assert!((w.u_of_v(1.0) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn u_and_v_invert() {
        let d: Vec<f64> = (0..200).map(|j| 1.0 / (1.0 + j as f64)).collect();
        let w = Warp::from_density(WarpVar::SqrtSine, &d, 64, 0.05).unwrap();
        for i in 0..=1000 {
            let v = i as f64 / 1000.0;
            assert!((w.v_of_u(w.u_of_v(v)) - v).abs() < 1e-6, "{v}");
        }
        let hi = FRAC_PI_2;
        for i in 0..=100 {
            let u = i as f64 / 100.0;
            assert!((w.u_of_angle(w.angle_of_u(u, hi), hi) - u).abs() < 1e-6);
        }
    }

    #[test]
    fn bad_knots_are_errors() {
        assert!(Warp::new(WarpVar::HalfPower, vec![0.0]).is_err());
        assert!(Warp::new(WarpVar::HalfPower, vec![0.0, 0.5, 0.5, 1.0]).is_err());
        assert!(Warp::new(WarpVar::HalfPower, vec![0.1, 1.0]).is_err());
        assert!(Warp::new(WarpVar::HalfPower, vec![0.0, f32::NAN, 1.0]).is_err());
        assert!(Warp::from_density(WarpVar::HalfPower, &[], 8, 0.1).is_err());
        assert!(Warp::from_density(WarpVar::HalfPower, &[1.0], 8, 0.0).is_err());
    }

    #[test]
    fn serde_round_trip() {
        let w = Warp::from_density(WarpVar::PseudoAngle, &[3.0, 1.0, 1.0, 2.0], 8, 0.3).unwrap();
        let s = serde_json::to_string(&w).unwrap();
        let back: Warp = serde_json::from_str(&s).unwrap();
        assert_eq!(w, back);
        assert!(serde_json::from_str::<Warp>(r#"{"var":"half_power","knots":[0,2,1]}"#).is_err());
    }
}
