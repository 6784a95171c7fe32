//! The chi-square test's expected counts: the pdf integrated over each bin ([`expected_mass`]),
//! on pieces graded towards the mirror direction, by [`adaptive_simpson`].

use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

use super::Chi2Options;
use crate::brdf::Brdf;

/// Integral of `pdf(·, wo)` over each bin (solid angle), by adaptive Simpson quadrature nested in
/// cos θ and φ, on pieces of the bins graded towards the mirror direction of `wo`.
///
/// Why graded: a reflection sampler's density divides by wo·h = |wi + wo| / 2, which vanishes at
/// wi = −wo; a sampler that folds draws at the horizon (`geometry::mirror_z`) carries that
/// singularity to the mirror direction (−wo.x, −wo.y, wo.z), on the upper side, and at a grazing
/// view the lobe's mass near it lies in wedges a few cos θo wide (89.999°: 1.7e-5), between the
/// nodes of Simpson's rule on whole bins. That rule read a half-vector lobe whose density
/// integrates to 1 as 0.99949–0.99953 at 89.999°, 1e-6 and 1e-12 rad from the horizon and
/// failed its correct sampler (p ~ 1e-6; `a_grazing_mirror_spike_is_integrated`). Breaks at
/// z_r ± w 2⁻ᵏ and φ_r ± w_φ 2⁻ᵏ (w a bin's width, k = 0, 1, … down to a thousandth of
/// cos θo) cut the bins around (z_r, φ_r) into pieces of every scale, each seeing a density that
/// varies by a bounded factor; a bin away from the mirror direction is cut at most once per axis.
pub fn expected_mass<B: Brdf + ?Sized>(brdf: &B, wo: DVec3, o: &Chi2Options) -> Vec<f64> {
    let nbins = o.cos_bins * o.phi_bins;
    let wz = 2.0 / o.cos_bins as f64;
    let wp = 2.0 * PI / o.phi_bins as f64;
    let mirror = crate::geometry::unit(wo).map_or(DVec3::NAN, |w| DVec3::new(-w.x, -w.y, w.z));
    let (zb, pb) = match crate::geometry::unit(wo) {
        Some(w) => {
            // Pieces down to a thousandth of the spike's width (cos θo, at least 1e-12).
            let levels = |width: f64| {
                (width / (1e-3 * w.z.abs().max(1e-12)))
                    .log2()
                    .ceil()
                    .clamp(0.0, 52.0) as i32
            };
            let phi_r = (-w.y).atan2(-w.x).rem_euclid(2.0 * PI);
            (
                graded_breaks(w.z, wz, levels(wz), -1.0, 1.0, false),
                graded_breaks(phi_r, wp, levels(wp), 0.0, 2.0 * PI, true),
            )
        }
        None => (Vec::new(), Vec::new()),
    };
    crate::par::install(|| {
        (0..nbins)
            .into_par_iter()
            .map(|b| {
                let (ci, pi) = (b / o.phi_bins, b % o.phi_bins);
                let z0 = -1.0 + 2.0 * ci as f64 / o.cos_bins as f64;
                let z1 = -1.0 + 2.0 * (ci + 1) as f64 / o.cos_bins as f64;
                let p0 = 2.0 * PI * pi as f64 / o.phi_bins as f64;
                let p1 = 2.0 * PI * (pi + 1) as f64 / o.phi_bins as f64;
                // dω = dz dφ on the sphere. The mirror direction itself is a node of the pieces
                // (z_r, φ_r), where a folded density's partner −wo gives 1/|wi + wo| of rounding
                // (~1e16 at 60°: ∫pdf read 1.0018 and correct samplers failed): that one point,
                // of measure zero, counts as 0 (the nearest other nodes are ≥ 1e-11 away, at
                // 89.999°).
                let f = |z: f64, phi: f64| {
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    let wi = DVec3::new(r * phi.cos(), r * phi.sin(), z);
                    if (wi - mirror).length_squared() < 1e-24 {
                        return 0.0;
                    }
                    let p = brdf.pdf(wi, wo);
                    if p.is_finite() { p } else { 0.0 }
                };
                let (zs, ps) = (pieces(&zb, z0, z1), pieces(&pb, p0, p1));
                // The whole bin's tolerance for each piece: a piece near the mirror direction
                // holds little mass, and a tolerance shared out by widths drove every piece to
                // the depth limit (`a_grazing_mirror_spike_is_integrated`: 33 s that way, 1.95 s
                // this way, 0.75 s on whole bins).
                let inner = |z: f64| {
                    ps.windows(2)
                        .map(|p| adaptive_simpson(&|phi| f(z, phi), p[0], p[1], 1e-7, 8))
                        .sum::<f64>()
                };
                zs.windows(2)
                    .map(|z| adaptive_simpson(&inner, z[0], z[1], 1e-7, 8))
                    .sum()
            })
            .collect()
    })
}

/// Sorted breaks c and c ± w 2⁻ᵏ (k = 0…`levels`) within (lo, hi) (taken modulo hi − lo when
/// `periodic`).
fn graded_breaks(c: f64, w: f64, levels: i32, lo: f64, hi: f64, periodic: bool) -> Vec<f64> {
    let mut v = vec![c];
    for k in 0..=levels {
        let d = w * 2f64.powi(-k);
        v.extend([c - d, c + d]);
    }
    let mut v: Vec<f64> = v
        .into_iter()
        .map(|x| {
            if periodic {
                lo + (x - lo).rem_euclid(hi - lo)
            } else {
                x
            }
        })
        .filter(|&x| x > lo && x < hi)
        .collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}

/// [a, b] cut at the `breaks` (sorted) inside it: the ends of its pieces.
fn pieces(breaks: &[f64], a: f64, b: f64) -> Vec<f64> {
    let i = breaks.partition_point(|&x| x <= a);
    let j = breaks.partition_point(|&x| x < b);
    let mut v = Vec::with_capacity(j.saturating_sub(i) + 2);
    v.push(a);
    v.extend_from_slice(&breaks[i.min(j)..j]);
    v.push(b);
    v
}

/// Adaptive Simpson quadrature of `f` over [a, b] with absolute tolerance `eps` and at most
/// `depth` levels of bisection (after an initial 4-panel split).
pub fn adaptive_simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, eps: f64, depth: u32) -> f64 {
    #[allow(clippy::too_many_arguments)]
    fn rec(
        f: &dyn Fn(f64) -> f64,
        a: f64,
        b: f64,
        fa: f64,
        fm: f64,
        fb: f64,
        whole: f64,
        eps: f64,
        depth: u32,
    ) -> f64 {
        let m = 0.5 * (a + b);
        let (lm, rm) = (0.5 * (a + m), 0.5 * (m + b));
        let (flm, frm) = (f(lm), f(rm));
        let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
        let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
        let delta = left + right - whole;
        if depth == 0 || delta.abs() <= 15.0 * eps {
            left + right + delta / 15.0
        } else {
            rec(f, a, m, fa, flm, fm, left, eps * 0.5, depth - 1)
                + rec(f, m, b, fm, frm, fb, right, eps * 0.5, depth - 1)
        }
    }
    let n = 4;
    let h = (b - a) / n as f64;
    (0..n)
        .map(|i| {
            let (x0, x1) = (a + i as f64 * h, a + (i + 1) as f64 * h);
            let (f0, fm, f1) = (f(x0), f(0.5 * (x0 + x1)), f(x1));
            let whole = (x1 - x0) / 6.0 * (f0 + 4.0 * fm + f1);
            rec(f, x0, x1, f0, fm, f1, whole, eps / n as f64, depth)
        })
        .sum()
}
