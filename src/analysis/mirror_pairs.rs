//! Pairs for the relative RMSE that a near-mirror peak does not turn into a lottery.
//!
//! [`super::accuracy::compare_region`] estimates an average over pairs uniform in solid angle of
//! (f̂ − f)² times cosines. A glossy measurement's peak is a fraction of a degree wide and
//! thousands of times brighter than the rest, so a uniform pair that lands on it carries most of
//! a 100 000-pair figure: `cg_sunflower`'s default table read 1.5–5.0 % in the grazing band over
//! five seeds (one pair at θh = 0.03°, 56 % of the squared error of four million). The quantity
//! stays, the pairs change: half are drawn uniformly, half with the outgoing direction mirrored
//! about a half vector near the normal (uniform in one of five cones of 0.1° to 24°, chosen at
//! random), and every pair is weighted by the uniform density over the mixture density
//! (defensive importance sampling: the weight is at most 2, and the peak is sampled thousands of
//! times instead of once or never). Pairs outside the region are drawn again; that rescales
//! every weight by one constant, which the ratio of two weighted sums cancels.

use glam::DVec3;

use crate::geometry;
use crate::rng::Pcg32;

/// Half angles of the half-vector cones (degrees), each drawn with equal probability.
const CONES_DEG: [f64; 5] = [0.1, 0.4, 1.5, 6.0, 24.0];

/// Share of the pairs drawn near the mirror direction.
const MIRROR_SHARE: f64 = 0.5;

/// The mixture of a region (see the module docs).
#[derive(Debug, Clone)]
pub struct MirrorMixture {
    /// Lowest cos θ of either direction (the cap's edge).
    cap_z: f64,
    /// 1 − cap_z.
    span: f64,
    /// Solid angle of the cap.
    omega: f64,
    /// A pair of the band has a direction with cos θ below this (∞: the region is a cap).
    band_z: f64,
    /// Per cone: cos of its half angle and its density (1 / solid angle).
    cones: [(f64, f64); CONES_DEG.len()],
}

impl MirrorMixture {
    /// The mixture over pairs with both directions within `cap` of the normal (radians, in
    /// (0, π/2]) and, when `band` is given, one of them farther than `band` from it (radians, in
    /// [0, π/2); then `cap` is π/2): the regions of [`super::accuracy::Region`], which checks
    /// the angles.
    pub fn new(cap: f64, band: Option<f64>) -> Self {
        // 1 − cos without cancellation (for θmax = π/2 exactly 1).
        let one_minus_cos = |a: f64| 2.0 * (0.5 * a).sin().powi(2);
        let span = one_minus_cos(cap);
        let cones = CONES_DEG.map(|d| {
            let m = one_minus_cos(d.to_radians());
            (1.0 - m, 1.0 / (2.0 * std::f64::consts::PI * m))
        });
        MirrorMixture {
            cap_z: 1.0 - span,
            span,
            omega: 2.0 * std::f64::consts::PI * span,
            band_z: band.map_or(f64::INFINITY, f64::cos),
            cones,
        }
    }

    fn uniform(&self, rng: &mut Pcg32) -> DVec3 {
        let u = rng.next_dvec2();
        geometry::uniform_hemisphere(glam::DVec2::new(self.cap_z + self.span * u.x, u.y))
    }

    /// A pair of the region and its weight, the uniform density over the mixture's (up to one
    /// constant factor for all pairs).
    pub fn draw(&self, rng: &mut Pcg32) -> (DVec3, DVec3, f64) {
        loop {
            let wi = self.uniform(rng);
            let wo = if rng.next_f64() < MIRROR_SHARE {
                let (cos_s, _) = self.cones[rng.below(self.cones.len() as u32) as usize];
                let u = rng.next_dvec2();
                let h =
                    geometry::uniform_hemisphere(glam::DVec2::new(1.0 - u.x * (1.0 - cos_s), u.y));
                geometry::reflect(wi, h)
            } else {
                self.uniform(rng)
            };
            if wo.z <= 0.0 || wo.z < self.cap_z || wi.z.min(wo.z) >= self.band_z {
                continue;
            }
            // The mirror component's density of wo: the half vector's over the reflection's
            // Jacobian 4 (wi·h).
            let mirror = geometry::normalize(wi + wo).map_or(0.0, |h| {
                let d: f64 = self
                    .cones
                    .iter()
                    .filter(|&&(cos_s, _)| h.z >= cos_s)
                    .map(|&(_, d)| d)
                    .sum();
                d / self.cones.len() as f64 / (4.0 * wi.dot(h))
            });
            let uniform = 1.0 / self.omega;
            let p = (1.0 - MIRROR_SHARE) * uniform + MIRROR_SHARE * mirror;
            return (wi, wo, uniform / p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_are_at_most_two_and_pairs_stay_in_the_region() {
        let mut rng = Pcg32::new(5);
        let half_pi = std::f64::consts::FRAC_PI_2;
        for (cap, band) in [(1.0, None), (half_pi, Some(80f64.to_radians()))] {
            let m = MirrorMixture::new(cap, band);
            for _ in 0..20_000 {
                let (wi, wo, w) = m.draw(&mut rng);
                assert!(w > 0.0 && w <= 2.0 + 1e-12, "{w}");
                assert!(wi.z >= m.cap_z && wo.z >= m.cap_z && wo.z > 0.0);
                assert!(wi.z.min(wo.z) < m.band_z);
            }
        }
    }
}
