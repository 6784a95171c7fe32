//! Shared by the SOURCE fuzz targets: evaluate an opened BRDF at a few fixed pairs (normal
//! incidence, grazing, below the horizon, NaN) through every trait method a host calls, then
//! ask its health — any outcome but a panic, a hang or a non-finite value from a healthy
//! source is a finding.

use brdftab::Brdf;
use glam::{DVec2, DVec3};

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
