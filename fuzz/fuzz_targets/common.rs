//! Shared by the SOURCE fuzz targets: evaluate an opened BRDF at a few fixed pairs (normal
//! incidence, grazing, below the horizon, NaN) through every trait method a host calls, then
//! ask its health — any outcome but a panic, a hang or a non-finite value from a healthy
//! source is a finding.

use brdftab::Brdf;
use glam::{DVec2, DVec3};

#[allow(dead_code)]
pub fn exercise(b: &dyn Brdf) {
    let c = b.channels().len();
    assert!(c >= 1 && c <= brdftab::spectrum::MAX_CHANNELS, "{c} channels");
    let dirs = [
        DVec3::Z,
        DVec3::new(0.6, 0.0, 0.8),
        DVec3::new(-0.3, 0.9, 0.1),
        DVec3::new(0.0, 1.0, 1e-9),
        DVec3::new(0.2, 0.1, -0.9),
        DVec3::new(f64::NAN, 0.0, 1.0),
        DVec3::ZERO,
    ];
    let mut f = vec![0.0f32; c];
    for &wi in &dirs {
        for &wo in &dirs {
            b.eval(wi, wo, &mut f);
            if !wi.is_finite() || !wo.is_finite() || wi == DVec3::ZERO || wo == DVec3::ZERO {
                assert!(f.iter().all(|&x| x == 0.0), "NaN rule: {wi} {wo} -> {f:?}");
            }
            let _ = b.pdf(wi, wo);
        }
        let _ = b.sample(wi, DVec2::new(0.3, 0.7), &mut f);
    }
    let wi: Vec<DVec3> = dirs.iter().cycle().take(64).copied().collect();
    let mut out = vec![0.0f32; 64 * c];
    b.eval_batch(&wi, &wi, &mut out);
    let _ = b.health();
}

/// A well-mixed 64-bit hash of the whole input (FNV-1a, then the SplitMix64 finalizer): the
/// harnesses pick their costly steps from it, so a step runs on a fixed fraction of all
/// executions — every mutation draws again — rather than on whatever share of the corpus
/// descends from a seed that asked for it (as a flag byte would).
#[allow(dead_code)]
pub fn hash(data: &[u8]) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for &b in data {
        h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
    }
    h ^= h >> 30;
    h = h.wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h ^= h >> 27;
    h = h.wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^ (h >> 31)
}

/// The directional albedo by the library's quadrature (`analysis::albedo::integrate`, the code
/// behind the default `Brdf::albedo`) with a coarse tolerance and 4 × 2 intervals, at two
/// angles: the same lobe search, G7/K15 rules and bisection as the default options at 1/4,000
/// of their worst-case work (4,885 evaluations per angle, not 28,974,085), which must hold.
#[allow(dead_code)]
pub fn coarse_albedo(b: &dyn Brdf) {
    use brdftab::analysis::albedo::{Options, integrate};
    let o = Options {
        rel_tol: 1e-3,
        max_outer: 4,
        max_inner: 2,
    };
    for wi in [DVec3::new(0.5, 0.0, 0.866), DVec3::new(0.999, 0.0, 0.04)] {
        let est = integrate(b, wi, &o);
        assert!(est.evals <= o.max_evals(), "{} evaluations", est.evals);
        assert_eq!(est.value.len(), b.channels().len());
    }
}
