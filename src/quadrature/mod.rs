//! Hemispherical quadrature about a reflection lobe: the numeric core of directional albedo.
//!
//! The method and its accuracy are described in [`analysis::albedo`](crate::analysis::albedo),
//! which is the interface to use. This room sits below [`brdf`](crate::brdf) (it integrates a
//! closure, not a `Brdf`), so the trait's default `albedo` can call it without an import cycle.

use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

use crate::geometry;
use crate::spectrum::MAX_CHANNELS;

mod legendre;
mod lobe;

pub use legendre::gauss_legendre;
use lobe::lobe_centre;

/// Accuracy settings of `hemisphere`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Target relative error of the albedo (of its largest channel).
    pub rel_tol: f64,
    /// Most intervals the outer (φ) rule may use.
    pub max_outer: usize,
    /// Most intervals each inner (α) rule may use.
    pub max_inner: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            rel_tol: 1e-6,
            max_outer: 128,
            max_inner: 256,
        }
    }
}

impl Options {
    /// For data — tables, measured files: a 1e-4 target with at most 32 outer and 64 inner
    /// intervals. A piecewise-linear table's kinks (and a measurement's noise) defeat the
    /// default 1e-6 target, which then refines to its interval limits (seconds per direction);
    /// here about 30 000 evaluations per direction suffice, and the data are not more
    /// accurate than this anyway.
    pub const DATA: Options = Options {
        rel_tol: 1e-4,
        max_outer: 32,
        max_inner: 64,
    };

    /// The most times `hemisphere` calls `eval` with these options, whatever the integrand:
    /// the lobe search, then every G7/K15 rule the outer (φ) rule may apply (the 4 quadrants,
    /// then two per bisection up to `max_outer` intervals) times 15 nodes, each node an inner
    /// (α) integration of at most as many rules (1 to 5 initial intervals, two per bisection
    /// up to `max_inner`) times 15. With the default options 28,974,085: reached only by an
    /// integrand no tolerance can be met on (noise); smooth models take about 5 000.
    pub fn max_evals(&self) -> usize {
        let rules = |initial: &[usize], max: usize| {
            initial
                .iter()
                .map(|&k| k + 2 * max.saturating_sub(k))
                .max()
                .unwrap_or(0)
        };
        let outer = rules(&[4], self.max_outer);
        let inner = rules(&[1, 2, 3, 4, 5], self.max_inner);
        LOBE_EVALS.saturating_add(
            outer
                .saturating_mul(15)
                .saturating_mul(inner.saturating_mul(15)),
        )
    }
}

/// Evaluations of the lobe search ([`lobe_centre`]): the mirror direction, the probe grid and
/// 24 rounds of a 4-point pattern search.
const LOBE_EVALS: usize = 1 + LOBE_NT * LOBE_NP + 24 * 4;
const LOBE_NT: usize = 12;
const LOBE_NP: usize = 24;

/// The result of `hemisphere`.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The albedo per channel.
    pub value: Vec<f64>,
    /// The estimated absolute error (of the largest channel).
    pub error: f64,
    /// How many times `eval` was called.
    pub evals: usize,
    /// The lobe centre the integration frame was built around.
    pub centre: DVec3,
}

/// ∫ f(wi, wo) cos θo dωo over the upper hemisphere for `c` channels, where `eval(wo, out)`
/// writes f(wi, wo) for the fixed (normalized here) `wi`: the integrator behind
/// [`analysis::albedo::integrate`](crate::analysis::albedo::integrate) and the default
/// [`Brdf::albedo`](crate::Brdf::albedo), written against a closure so that the trait's default
/// and this numeric room need not know each other.
pub fn hemisphere(
    c: usize,
    wi: DVec3,
    opts: &Options,
    eval: impl Fn(DVec3, DVec3, &mut [f32]),
) -> Estimate {
    let c = c.min(MAX_CHANNELS);
    let zero = Estimate {
        value: vec![0.0; c],
        error: 0.0,
        evals: 0,
        centre: DVec3::Z,
    };
    let Some(wi) = geometry::normalize(wi) else {
        return zero;
    };
    if wi.z <= 0.0 || c == 0 {
        return zero;
    }
    let mut evals = 0usize;
    let mut fbuf = [0.0f32; MAX_CHANNELS];
    // f·cos θo summed over channels: the scalar the lobe search maximizes.
    let mut g = |wo: DVec3, evals: &mut usize| -> f64 {
        *evals += 1;
        if wo.z <= 0.0 {
            return 0.0;
        }
        eval(wi, wo, &mut fbuf[..c]);
        fbuf[..c].iter().map(|&x| x as f64).sum::<f64>() * wo.z
    };
    let (centre, scale) = lobe_centre(&mut g, wi, &mut evals);

    // Orthonormal frame about the centre: e2 horizontal, e1 in the vertical plane through c
    // (pointing down towards the horizon for φ = 0).
    let e2 = geometry::normalize(DVec3::new(-centre.y, centre.x, 0.0)).unwrap_or(DVec3::Y);
    let e1 = e2.cross(centre);

    // Absolute floors from the coarse estimate of the albedo, so directions far from the lobe
    // are not integrated to a pointless relative accuracy; and never below what f32 values
    // resolve: f below f32::MIN_POSITIVE is subnormal, its relative precision falls to nothing
    // and a relative tolerance would bisect f32 rounding noise to the last interval allowed
    // (a GGX with α = 1e14, f ≈ 1e-43, made 28.7 M evaluations before this floor). So an
    // albedo is accurate to max(tolerance, f32::MIN_POSITIVE ≈ 1.2e-38) absolute.
    let floor = f32::MIN_POSITIVE as f64;
    let outer_abs = (opts.rel_tol * 0.1 * scale).max(floor);
    let inner_rel = opts.rel_tol * 0.01;
    let inner_abs = (opts.rel_tol * 0.01 * scale).max(floor) / TAU;

    let mut inner_out = [0.0f64; MAX_CHANNELS];
    let mut inner = |phi: f64, out: &mut [f64], evals: &mut usize| {
        let (sp, cp) = phi.sin_cos();
        let t = cp * e1 + sp * e2;
        // z(α) = c_z cos α + t_z sin α = R cos(α − δ) first vanishes at α = δ + π/2.
        let alpha_max = t.z.atan2(centre.z) + FRAC_PI_2;
        let breaks: Vec<f64> = [0.0, 0.01, 0.04, 0.15, 0.5]
            .into_iter()
            .filter(|&a| a < alpha_max)
            .chain(std::iter::once(alpha_max))
            .collect();
        let mut fb = [0.0f32; MAX_CHANNELS];
        // On the first interval [0, b1] the rule's variable x is graded: α = b1 (x/b1)³. A
        // sharp lobe seen at grazing is a sliver — as long as ~m in the plane of incidence, but
        // ~m cos θi across it (2e-6 rad for m = 0.001 at 89.9°) — so along most azimuths its
        // peak at α ≈ 0 is narrower than the rule's first node (4e-5 of 0.01): both estimates
        // missed it and agreed (the albedo 6e-4 low at 89.9°, reported converged to 1e-10).
        let b1 = breaks[1];
        let mut f = |x: f64, o: &mut [f64], evals: &mut usize| {
            *evals += 1;
            let (alpha, jac) = match x < b1 {
                true => {
                    let u = x / b1;
                    (b1 * u * u * u, 3.0 * u * u)
                }
                false => (x, 1.0),
            };
            let (sa, ca) = alpha.sin_cos();
            let wo = ca * centre + sa * t;
            if wo.z <= 0.0 {
                o.fill(0.0);
                return;
            }
            eval(wi, wo, &mut fb[..c]);
            let w = wo.z * sa * jac;
            for (ok, &fk) in o.iter_mut().zip(&fb[..c]) {
                *ok = fk as f64 * w;
            }
        };
        adaptive(
            &mut f,
            &breaks,
            c,
            inner_rel,
            inner_abs,
            opts.max_inner,
            &mut inner_out[..c],
            evals,
        );
        out.copy_from_slice(&inner_out[..c]);
    };
    let mut value = vec![0.0; c];
    let error = adaptive(
        &mut inner,
        &[0.0, FRAC_PI_2, PI, 1.5 * PI, TAU],
        c,
        opts.rel_tol,
        outer_abs,
        opts.max_outer,
        &mut value,
        &mut evals,
    );
    Estimate {
        value,
        error,
        evals,
        centre,
    }
}

// Gauss-Kronrod 7/15 abscissae (non-negative half) and weights (QUADPACK's qk15).
const XGK: [f64; 8] = [
    0.991_455_371_120_812_6,
    0.949_107_912_342_758_5,
    0.864_864_423_359_769_1,
    0.741_531_185_599_394_4,
    0.586_087_235_467_691_1,
    0.405_845_151_377_397_2,
    0.207_784_955_007_898_5,
    0.0,
];
const WGK: [f64; 8] = [
    0.022_935_322_010_529_22,
    0.063_092_092_629_978_55,
    0.104_790_010_322_250_2,
    0.140_653_259_715_525_9,
    0.169_004_726_639_267_9,
    0.190_350_578_064_785_4,
    0.204_432_940_075_298_9,
    0.209_482_141_084_727_8,
];
// Gauss 7-point weights for XGK[1], XGK[3], XGK[5], XGK[7].
const WG: [f64; 4] = [
    0.129_484_966_168_869_7,
    0.279_705_391_489_276_7,
    0.381_830_050_505_118_9,
    0.417_959_183_673_469_4,
];

/// One G7/K15 rule on [a, b] for a vector integrand: Kronrod result into `k`, returns the error
/// estimate max_channel |K15 − G7|.
fn gk15<F: FnMut(f64, &mut [f64], &mut usize)>(
    f: &mut F,
    a: f64,
    b: f64,
    k: &mut [f64],
    evals: &mut usize,
) -> f64 {
    let c = k.len();
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    let mut gs = [0.0f64; MAX_CHANNELS];
    let mut v = [0.0f64; MAX_CHANNELS];
    k.fill(0.0);
    for (j, (&x, &wk)) in XGK.iter().zip(&WGK).enumerate() {
        let pts: &[f64] = if x == 0.0 {
            &[mid]
        } else {
            &[mid - half * x, mid + half * x]
        };
        for &p in pts {
            f(p, &mut v[..c], evals);
            for ch in 0..c {
                k[ch] += wk * v[ch];
                if j % 2 == 1 {
                    gs[ch] += WG[j / 2] * v[ch];
                }
            }
        }
    }
    let mut err = 0.0f64;
    for ch in 0..c {
        k[ch] *= half;
        err = err.max((k[ch] - gs[ch] * half).abs());
    }
    if err.is_nan() { f64::INFINITY } else { err }
}

/// Globally adaptive G7/K15 quadrature of a vector integrand over the intervals between
/// consecutive `breaks`: bisects the interval with the largest error estimate until the total
/// estimate is ≤ max(`abs`, `rel`·max_channel |I|) or `max_segs` intervals are used. Writes the
/// integral into `out` and returns the error estimate.
#[allow(clippy::too_many_arguments)]
fn adaptive<F: FnMut(f64, &mut [f64], &mut usize)>(
    f: &mut F,
    breaks: &[f64],
    c: usize,
    rel: f64,
    abs: f64,
    max_segs: usize,
    out: &mut [f64],
    evals: &mut usize,
) -> f64 {
    // Segments (a, b, err) and their values, c per segment.
    let mut segs: Vec<(f64, f64, f64)> = Vec::with_capacity(max_segs + 8);
    let mut vals: Vec<f64> = Vec::with_capacity((max_segs + 8) * c);
    let mut tmp = [0.0f64; MAX_CHANNELS];
    for w in breaks.windows(2) {
        if w[1] > w[0] {
            let e = gk15(f, w[0], w[1], &mut tmp[..c], evals);
            segs.push((w[0], w[1], e));
            vals.extend_from_slice(&tmp[..c]);
        }
    }
    loop {
        out[..c].fill(0.0);
        let mut err = 0.0;
        for (s, v) in segs.iter().zip(vals.chunks_exact(c)) {
            err += s.2;
            for ch in 0..c {
                out[ch] += v[ch];
            }
        }
        let mag = out[..c].iter().fold(0.0f64, |m, x| m.max(x.abs()));
        if err <= abs.max(rel * mag) || segs.len() >= max_segs || err.is_nan() {
            return err;
        }
        // Bisect the worst segment.
        let (worst, _) =
            segs.iter().enumerate().fold(
                (0, -1.0),
                |(bi, be), (i, s)| if s.2 > be { (i, s.2) } else { (bi, be) },
            );
        let (a, b, _) = segs[worst];
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            // Cannot split further: accept this segment as it is.
            segs[worst].2 = 0.0;
            continue;
        }
        let e1 = gk15(f, a, m, &mut tmp[..c], evals);
        segs[worst] = (a, m, e1);
        vals[worst * c..(worst + 1) * c].copy_from_slice(&tmp[..c]);
        let e2 = gk15(f, m, b, &mut tmp[..c], evals);
        segs.push((m, b, e2));
        vals.extend_from_slice(&tmp[..c]);
    }
}
