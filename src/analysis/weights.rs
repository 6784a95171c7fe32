//! How well a sampler follows its BRDF: statistics of the sample weights w = f_r cos θi / pdf.
//!
//! A perfect importance sampler of f_r cos θi gives every sample the same weight, the directional
//! albedo; the spread of the weights is what a renderer pays for in noise. [`weight_stats`]
//! draws `samples` directions for one `wo` and reports the coefficient of variation (σ/mean) of
//! the channel-mean weight, counting a draw that gives no direction as weight 0 (it is a sample
//! an estimator spends and gets nothing from), and the largest weight relative to the mean.

use glam::DVec3;

use crate::brdf::Brdf;
use crate::rng::Pcg32;
use crate::spectrum::MAX_CHANNELS;

/// Statistics of the channel-mean sample weights for one outgoing direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WeightStats {
    /// Draws made.
    pub samples: usize,
    /// Mean weight (an estimate of the channel-mean directional albedo).
    pub mean: f64,
    /// Coefficient of variation of one weight: σ/mean (0 = perfect importance sampling; NaN
    /// when the mean is 0).
    pub cv: f64,
    /// Largest weight / mean.
    pub max_over_mean: f64,
    /// Fraction of draws that returned no direction.
    pub refused: f64,
}

/// Draws `samples` directions from `brdf.sample(wo, ·)` with PCG32 stream `seed` and returns
/// the statistics of the channel-mean weights (see the module docs). Non-finite or negative
/// weights count as they are (they make the figures non-finite, which a test then catches).
pub fn weight_stats(brdf: &dyn Brdf, wo: DVec3, samples: usize, seed: u64) -> WeightStats {
    let c = brdf.channels().len().clamp(1, MAX_CHANNELS);
    let mut w = [0.0f32; MAX_CHANNELS];
    let mut rng = Pcg32::new(seed);
    let (mut sum, mut sum2, mut max, mut refused) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    for _ in 0..samples {
        let x = match brdf.sample(wo, rng.next_dvec2(), &mut w[..c]) {
            Some(_) => w[..c].iter().map(|&v| v as f64).sum::<f64>() / c as f64,
            None => {
                refused += 1;
                0.0
            }
        };
        sum += x;
        sum2 += x * x;
        max = max.max(x);
    }
    let n = samples.max(1) as f64;
    let mean = sum / n;
    let var = (sum2 / n - mean * mean).max(0.0);
    WeightStats {
        samples,
        mean,
        cv: var.sqrt() / mean,
        max_over_mean: max / mean,
        refused: refused as f64 / n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::lambert::Lambert;
    use crate::spectrum::{Channels, Value};

    #[test]
    fn cosine_sampling_of_lambert_has_constant_weights() {
        let b = Lambert::new(Value::Grey(0.2), &Channels::Rgb).unwrap();
        let s = weight_stats(&b, DVec3::new(0.3, 0.2, 0.8), 1000, 1);
        assert!((s.mean - 0.2 * std::f64::consts::PI).abs() < 1e-6);
        assert!(s.cv < 1e-6 && s.refused == 0.0);
    }
}
