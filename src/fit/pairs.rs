//! The direction pairs a fit compares source and model on.
//!
//! Deterministic (PCG32 with a seed) and drawn in two parts:
//!
//! - `wo` is cosine-distributed over the upper hemisphere (density cos θo / π);
//! - with probability `1 − specular_fraction`, `wi` is cosine-distributed too;
//! - otherwise `wi` lies near the mirror direction of `wo`, at an angle δ = δmax·u² (δmax = 20°)
//!   from it, uniform in azimuth around it: the u² concentrates samples in the first degree, so
//!   lobes as sharp as Phong n = 10⁴ or roughness 0.01 are still seen by a few percent of all
//!   pairs. Directions that fall below the horizon are redrawn.
//!
//! Both directions are kept within `max_theta` of the normal (default 80°, as Ngan et al. 2005
//! discard grazing measurements): measured data is least reliable there, and the 1/(cos θi cos θo)
//! of microfacet models (and tables interpolating them) would let a few grazing pairs dominate
//! the sum of squares.
//!
//! Each pair appears once in the sum of squares (no density compensation): the fit minimizes
//! Σ (f̂ cos θi − f cos θi)² over these pairs, which weights the specular cone more than a
//! uniform integral would, on purpose.

use glam::DVec3;

use crate::geometry::{self, Frame};
use crate::rng::Pcg32;

/// Largest angle of a specular-cone sample from the mirror direction (20°).
pub const SPECULAR_CONE: f64 = 20.0 * std::f64::consts::PI / 180.0;

/// Default largest polar angle of either direction (80°).
pub const MAX_THETA: f64 = 80.0 * std::f64::consts::PI / 180.0;

/// Direction pairs: `wi[k]`, `wo[k]`, both unit, within `max_theta` of the normal.
#[derive(Debug, Clone, Default)]
pub struct Pairs {
    /// Directions towards the light.
    pub wi: Vec<DVec3>,
    /// Directions towards the viewer.
    pub wo: Vec<DVec3>,
}

impl Pairs {
    /// `n` pairs, a fraction `specular_fraction` of them near the mirror direction, both
    /// directions at most `max_theta` (radians, clamped to [1°, 90°)) from the normal.
    pub fn sample(n: usize, specular_fraction: f64, max_theta: f64, seed: u64) -> Self {
        let mut rng = Pcg32::with_stream(seed, 0x6f69_7421);
        let mut wi = Vec::with_capacity(n);
        let mut wo = Vec::with_capacity(n);
        let min_z = max_theta
            .clamp(1f64.to_radians(), 89.9f64.to_radians())
            .cos()
            .max(1e-3);
        while wi.len() < n {
            let o = geometry::cosine_hemisphere(rng.next_dvec2());
            let specular = rng.next_f64() < specular_fraction;
            if o.z < min_z {
                continue;
            }
            let i = if specular {
                let r = geometry::reflect_z(o);
                let (u1, u2) = (rng.next_f64(), rng.next_f64());
                let delta = SPECULAR_CONE * u1 * u1;
                let local = geometry::spherical(delta, 2.0 * std::f64::consts::PI * u2);
                Frame::from_normal(r).to_world(local)
            } else {
                geometry::cosine_hemisphere(rng.next_dvec2())
            };
            let Some(i) = geometry::normalize(i) else {
                continue;
            };
            if i.z < min_z {
                continue;
            }
            wi.push(i);
            wo.push(o);
        }
        Pairs { wi, wo }
    }

    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.wi.len()
    }

    /// True when there are no pairs.
    pub fn is_empty(&self) -> bool {
        self.wi.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_above_horizon_and_some_specular() {
        let a = Pairs::sample(2000, 0.3, MAX_THETA, 7);
        let b = Pairs::sample(2000, 0.3, MAX_THETA, 7);
        assert_eq!(a.wi, b.wi);
        assert_eq!(a.len(), 2000);
        let mut near = 0;
        for (i, o) in a.wi.iter().zip(&a.wo) {
            assert!(i.z >= MAX_THETA.cos() - 1e-12 && o.z >= MAX_THETA.cos() - 1e-12);
            assert!((i.length() - 1.0).abs() < 1e-12);
            if i.dot(geometry::reflect_z(*o)) > 1.0f64.to_radians().cos() {
                near += 1;
            }
        }
        // About 0.3 · sqrt(1/20) ≈ 6.7% lie within 1° of the mirror direction.
        assert!(near > 80 && near < 200, "{near}");
        assert_ne!(
            Pairs::sample(10, 0.3, MAX_THETA, 8).wi,
            Pairs::sample(10, 0.3, MAX_THETA, 7).wi
        );
    }
}
