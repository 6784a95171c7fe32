//! Symmetry reduction: isotropy, bilateral symmetry and Helmholtz reciprocity.
//!
//! Each symmetry is a map from any direction pair (wi, wo) to *canonical* coordinates in the
//! stored domains of a [`Grid`](super::Grid) ([`canonical_coords`]); a reduced table stores only
//! canonical nodes. The maps:
//!
//! | symmetry    | `inout`                                          | `halfdiff`                        |
//! |-------------|--------------------------------------------------|-----------------------------------|
//! | isotropic   | (θi, θo, Δφ = φo − φi), φi dropped               | φh dropped                        |
//! | bilateral   | Δφ → \|Δφ\| ∈ [0, π] (anisotropic: φi, φo → −φi, −φo when φi > π) | φd → −φd (anisotropic: (φh, φd) → (−φh, −φd) when φh < 0) |
//! | reciprocal  | swap so θ1 ≤ θ2 (Δφ → −Δφ), upper-triangle packing | φd ≡ φd + π: φd ∈ [0, π)         |
//!
//! Because full φ nodes sit at i·2π/N and folded axes keep exactly those nodes, every map sends
//! nodes to nodes and cells to cells, so interpolating a reduced table gives the same value as
//! interpolating the full table of a symmetric source. The one place where a cell crosses the
//! stored region is the diagonal θ1 = θ2 of packed `inout` reciprocity; lookups canonicalize
//! those corners individually ([`canonical_corner_inout`]).
//!
//! A symmetry is *declared* (from [`Flags`](crate::Flags) or by the user) or *detected*
//! ([`detect`]) and always *verified* ([`verify`]) before a reduced table is baked: a source
//! breaking a declared symmetry beyond tolerance gives [`Error::Symmetry`] unless forced.

use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};
use std::fmt;

use crate::brdf::Brdf;
pub use crate::error::SymmetryKind;
use crate::error::{Error, Result};
use crate::geometry;
use crate::rng::Pcg32;
use crate::spectrum::MAX_CHANNELS;
use crate::table::param::Param;

/// Which symmetries a table exploits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, Hash)]
#[serde(default, deny_unknown_fields)]
pub struct Symmetry {
    /// Invariance under a common rotation about the normal.
    pub isotropic: bool,
    /// Helmholtz reciprocity f(wi, wo) = f(wo, wi).
    pub reciprocal: bool,
    /// Mirror symmetry through the x–z plane (for isotropic sources: Δφ → −Δφ).
    pub bilateral: bool,
}

impl Symmetry {
    /// No reduction.
    pub const NONE: Symmetry = Symmetry {
        isotropic: false,
        reciprocal: false,
        bilateral: false,
    };
    /// All three.
    pub const ALL: Symmetry = Symmetry {
        isotropic: true,
        reciprocal: true,
        bilateral: true,
    };

    /// The symmetries a model declares in its flags.
    pub fn from_flags(f: crate::Flags) -> Symmetry {
        Symmetry {
            isotropic: f.isotropic,
            reciprocal: f.reciprocal,
            bilateral: f.bilateral,
        }
    }

    /// The symmetries present in both.
    pub fn intersect(self, o: Symmetry) -> Symmetry {
        Symmetry {
            isotropic: self.isotropic && o.isotropic,
            reciprocal: self.reciprocal && o.reciprocal,
            bilateral: self.bilateral && o.bilateral,
        }
    }
}

impl std::str::FromStr for Symmetry {
    type Err = crate::Error;

    /// Parses a comma-separated list: `isotropic,reciprocal,bilateral` (also `iso`, `recip`,
    /// `bilat`), `none` or `all`.
    fn from_str(s: &str) -> std::result::Result<Self, crate::Error> {
        let mut out = Symmetry::NONE;
        for w in s.split(',').map(|w| w.trim().to_ascii_lowercase()) {
            match w.as_str() {
                "" | "none" => {}
                "all" => out = Symmetry::ALL,
                "isotropic" | "iso" | "isotropy" => out.isotropic = true,
                "reciprocal" | "recip" | "reciprocity" => out.reciprocal = true,
                "bilateral" | "bilat" => out.bilateral = true,
                other => {
                    return Err(Error::arg(
                        "symmetry",
                        format!(
                            "`{other}`: expected auto, none, all or a list of isotropic, reciprocal, bilateral"
                        ),
                    ));
                }
            }
        }
        Ok(out)
    }
}

impl fmt::Display for Symmetry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut v = Vec::new();
        if self.isotropic {
            v.push("isotropic");
        }
        if self.reciprocal {
            v.push("reciprocal");
        }
        if self.bilateral {
            v.push("bilateral");
        }
        if v.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&v.join("+"))
        }
    }
}

/// Canonical coordinates of a pair in the stored domains of a grid with parameterization
/// `param` and symmetry `sym`: `[θ1, φ1, θ2, φ2]` (`inout` isotropic: `[θi, 0, θo, Δφ]`;
/// `halfdiff` isotropic: `[θh, 0, θd, φd]`). `None` below the horizon or for invalid input.
///
/// Angles come from vector algebra where possible (one `atan2` for Δφ instead of two) and from
/// the exact `libm` functions; [`canonical_coords_fast`] uses polynomial approximations.
#[inline]
pub fn canonical_coords(param: Param, sym: Symmetry, wi: DVec3, wo: DVec3) -> Option<[f64; 4]> {
    coords::<false>(param, sym, wi, wo)
}

/// [`canonical_coords`] with polynomial `acos`/`atan2` (absolute error below 2e-7 rad): for
/// linear interpolation, where that is far below a node spacing. Nearest lookups use the exact
/// version so that cell boundaries (MERL's `int(...)`) are reproduced exactly.
#[inline]
pub fn canonical_coords_fast(
    param: Param,
    sym: Symmetry,
    wi: DVec3,
    wo: DVec3,
) -> Option<[f64; 4]> {
    coords::<true>(param, sym, wi, wo)
}

#[inline(always)]
fn acos<const FAST: bool>(x: f64) -> f64 {
    if FAST {
        fast_acos(x)
    } else {
        x.clamp(-1.0, 1.0).acos()
    }
}

#[inline(always)]
fn atan2<const FAST: bool>(y: f64, x: f64) -> f64 {
    if FAST { fast_atan2(y, x) } else { y.atan2(x) }
}

/// acos with absolute error ≤ 2e-8 (Abramowitz & Stegun 4.4.46); input clamped to [−1, 1].
#[inline(always)]
pub fn fast_acos(x: f64) -> f64 {
    let a = x.abs().min(1.0);
    let p = -0.0012624911;
    let p = p * a + 0.0066700901;
    let p = p * a - 0.0170881256;
    let p = p * a + 0.0308918810;
    let p = p * a - 0.0501743046;
    let p = p * a + 0.0889789874;
    let p = p * a - 0.2145988016;
    let p = p * a + 1.5707963050;
    let r = (1.0 - a).sqrt() * p;
    if x < 0.0 { PI - r } else { r }
}

/// atan2 with absolute error ≤ 2e-7 (Cephes `atanf` range reduction and polynomial), same
/// quadrant conventions as `f64::atan2` for finite input: result in [−π, π].
#[inline(always)]
pub fn fast_atan2(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let (num, den, swap) = if ay > ax {
        (ax, ay, true)
    } else {
        (ay, ax, false)
    };
    // z = min/max in [0, 1]; reduce to [0, tan(π/8)].
    let z = if den > 0.0 { num / den } else { 0.0 };
    let (base, t) = if z > 0.414_213_562_373_095 {
        (std::f64::consts::FRAC_PI_4, (z - 1.0) / (z + 1.0))
    } else {
        (0.0, z)
    };
    let t2 = t * t;
    let mut r = base
        + (((8.053_744_495_38e-2 * t2 - 1.387_768_560_32e-1) * t2 + 1.997_771_064_78e-1) * t2
            - 3.333_294_915_39e-1)
            * t2
            * t
        + t;
    if swap {
        r = std::f64::consts::FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 { -r } else { r }
}

#[inline(always)]
fn coords<const FAST: bool>(param: Param, sym: Symmetry, wi: DVec3, wo: DVec3) -> Option<[f64; 4]> {
    let (wi, wo) = if FAST {
        // Unit inputs (the usual case) skip the two normalizations.
        let (wi, wo) = (geometry::unit(wi)?, geometry::unit(wo)?);
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return None;
        }
        (wi, wo)
    } else {
        geometry::upper_pair(wi, wo)?
    };
    match param {
        Param::InOut => {
            let ti = acos::<FAST>(wi.z);
            let to = acos::<FAST>(wo.z);
            if sym.isotropic {
                let dot = wi.x * wo.x + wi.y * wo.y;
                let cross = wi.x * wo.y - wi.y * wo.x;
                let mut d = atan2::<FAST>(cross, dot);
                let (mut t1, mut t2) = (ti, to);
                if sym.reciprocal && t1 > t2 {
                    std::mem::swap(&mut t1, &mut t2);
                    d = -d;
                }
                if sym.bilateral {
                    d = d.abs();
                } else if d < 0.0 {
                    d += TAU;
                }
                Some([t1, 0.0, t2, d])
            } else {
                let mut a = [ti, atan2::<FAST>(wi.y, wi.x), to, atan2::<FAST>(wo.y, wo.x)];
                if sym.reciprocal && a[0] > a[2] {
                    a.swap(0, 2);
                    a.swap(1, 3);
                }
                if sym.bilateral && a[1] < 0.0 {
                    a[1] = -a[1];
                    a[3] = -a[3];
                }
                if a[1] < 0.0 {
                    a[1] += TAU;
                }
                if a[3] < 0.0 {
                    a[3] += TAU;
                }
                Some(a)
            }
        }
        Param::HalfDiff => {
            let (th, td, pd, h) = if FAST {
                half_diff_angles_fast(wi, wo)?
            } else {
                let (h, d) = geometry::half_diff_vectors(wi, wo)?;
                (
                    acos::<FAST>(h.z),
                    acos::<FAST>(d.z),
                    atan2::<FAST>(d.y, d.x),
                    h,
                )
            };
            let ph = if sym.isotropic {
                0.0
            } else {
                atan2::<FAST>(h.y, h.x)
            };
            Some(fold_half_diff(sym, th, ph, td, pd))
        }
    }
}

/// The symmetry folds of `halfdiff` coordinates: (θh, φh, θd, φd) with φh, φd in [−π, π] (φh
/// ignored for isotropic grids) to the stored domains.
#[inline(always)]
fn fold_half_diff(sym: Symmetry, th: f64, mut ph: f64, td: f64, mut pd: f64) -> [f64; 4] {
    if sym.isotropic {
        ph = 0.0;
    } else {
        if sym.bilateral && ph < 0.0 {
            ph = -ph;
            pd = -pd;
        }
        if ph < 0.0 {
            ph += TAU;
        }
    }
    let iso_bilat = sym.isotropic && sym.bilateral;
    if sym.reciprocal && iso_bilat {
        let a = pd.abs();
        pd = a.min(PI - a);
    } else if sym.reciprocal {
        // As the MERL reader: φd + π when negative.
        if pd < 0.0 {
            pd += PI;
        }
    } else if iso_bilat {
        pd = pd.abs();
    } else if pd < 0.0 {
        pd += TAU;
    }
    [th, ph, td, pd]
}

/// Canonical stored `halfdiff` coordinates of Rusinkiewicz angles under `sym`: the folds of
/// [`canonical_coords`] applied to angles directly, without going through directions (so a pair
/// with a direction below the horizon still has coordinates). Azimuths may be given in any
/// period; they are first brought to (−π, π].
pub fn canonical_half_diff(sym: Symmetry, hd: geometry::HalfDiff) -> [f64; 4] {
    let wrap = |a: f64| {
        let a = a.rem_euclid(TAU);
        if a > PI { a - TAU } else { a }
    };
    let [th, ph, td, pd] =
        fold_half_diff(sym, hd.theta_h, wrap(hd.phi_h), hd.theta_d, wrap(hd.phi_d));
    // φd = π folds to π under reciprocity alone (the reader's φd + π applies to negative φd
    // only); it is the same direction pair as φd = 0.
    let pd = if sym.reciprocal && !(sym.isotropic && sym.bilateral) && pd >= PI {
        pd - PI
    } else {
        pd
    };
    [th, ph, td, pd]
}

/// (θh, θd, φd, h) of a pair of unit directions with the unnormalized half vector
/// h = wi + wo, one square root and one reciprocal (besides the polynomial `atan2`):
/// cos θh = h_z/|h|, cos θd = wi·h/|h|, and φd = atan2(d_y, d_x) where the difference vector's
/// components, multiplied by the positive |h|·|h_xy|, are
/// d_y ∝ (wi_y h_x − wi_x h_y)|h| and d_x ∝ (wi_x h_x + wi_y h_y) h_z − wi_z |h_xy|²
/// (rotate wi by −φh about z, then by −θh about y; `geometry::half_diff_vectors` step by
/// step). At the pole (h_xy = 0, φh = 0 by convention) d = wi.
#[inline(always)]
fn half_diff_angles_fast(wi: DVec3, wo: DVec3) -> Option<(f64, f64, f64, DVec3)> {
    let h = wi + wo;
    let hxy2 = h.x * h.x + h.y * h.y;
    let hh = hxy2 + h.z * h.z;
    if !(hh > 1e-300) {
        return None;
    }
    let len = hh.sqrt();
    let inv = 1.0 / len;
    let th = fast_acos(h.z * inv);
    let td = fast_acos(wi.dot(h) * inv);
    let pd = if hxy2 > 1e-24 * hh {
        let y = (wi.y * h.x - wi.x * h.y) * len;
        let x = (wi.x * h.x + wi.y * h.y) * h.z - wi.z * hxy2;
        fast_atan2(y, x)
    } else {
        fast_atan2(wi.y, wi.x)
    };
    Some((th, td, pd, h))
}

/// Canonicalizes a corner `[a, p, b, q]` of packed `inout` reciprocity (stored θ1 ≤ θ2): when
/// a > b, the reciprocal node is returned. `n1`, `n3` are the full φ sizes (φi, φo);
/// the stored axis-1/axis-3 conventions follow the grid (see the module table).
#[inline]
pub fn canonical_corner_inout(sym: Symmetry, idx: [usize; 4], n3: usize) -> [usize; 4] {
    let [a, p, b, q] = idx;
    if a <= b {
        return idx;
    }
    if sym.isotropic {
        // (θi, θo, Δφ) → (θo, θi, −Δφ); with bilateral symmetry the stored |Δφ| is unchanged.
        let q2 = if sym.bilateral || q == 0 { q } else { n3 - q };
        [b, 0, a, q2]
    } else if sym.bilateral && q > n3 / 2 {
        // Swap, then reflect both φ through the x–z plane to bring φ1 into [0, π].
        let p2 = if p == 0 { 0 } else { n3 - p };
        [b, n3 - q, a, p2]
    } else {
        [b, q, a, p]
    }
}

/// The three symmetry tests on one pair: which transformed pair to compare with.
fn transformed(which: usize, wi: DVec3, wo: DVec3, angle: f64) -> (DVec3, DVec3) {
    match which {
        0 => {
            let (s, c) = angle.sin_cos();
            let r = |v: DVec3| DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z);
            (r(wi), r(wo))
        }
        1 => (wo, wi),
        _ => (DVec3::new(wi.x, -wi.y, wi.z), DVec3::new(wo.x, -wo.y, wo.z)),
    }
}

/// The worst relative difference between f(wi, wo) and f at the transformed pair, for
/// `which` = 0 (isotropy: common rotation), 1 (reciprocity: swap), 2 (bilateral: y → −y), over
/// `pairs` random pairs uniform on the hemisphere (seeded). Relative to max(|a|, |b|) floored at
/// 1e-6 × the largest value seen, so values that are 0 up to rounding do not count.
/// Returns (error, a description of the worst pair).
pub fn violation(brdf: &dyn Brdf, which: usize, pairs: usize, seed: u64) -> (f64, String) {
    let mut rng = Pcg32::with_stream(seed, which as u64 + 11);
    worst_violation(brdf, which, pairs, &mut rng, |rng| {
        let wi = geometry::uniform_hemisphere(rng.next_dvec2());
        let wo = geometry::uniform_hemisphere(rng.next_dvec2());
        Some((wi, wo))
    })
}

/// [`violation`] over pairs where the source is large: wo uniform on the hemisphere, wi drawn
/// by the source's own sampler ([`Brdf::sample`]; delta draws are skipped). Random pairs never
/// meet a lobe narrower than a degree or so — f_r is 0 to f32 at every one of them and at its
/// transformed pair, which looks symmetric whatever the lobe is.
pub fn sampled_violation(brdf: &dyn Brdf, which: usize, pairs: usize, seed: u64) -> (f64, String) {
    let mut rng = Pcg32::with_stream(seed, which as u64 + 23);
    let mut weight = [0.0f32; MAX_CHANNELS];
    let c = brdf.channels().len().min(MAX_CHANNELS);
    worst_violation(brdf, which, pairs, &mut rng, |rng| {
        let wo = geometry::uniform_hemisphere(rng.next_dvec2());
        let s = brdf.sample(wo, rng.next_dvec2(), &mut weight[..c])?;
        (!s.delta).then_some((s.wi, wo))
    })
}

/// The worst relative difference over `pairs` draws of `draw` (module docs of [`violation`]).
fn worst_violation(
    brdf: &dyn Brdf,
    which: usize,
    pairs: usize,
    rng: &mut Pcg32,
    mut draw: impl FnMut(&mut Pcg32) -> Option<(DVec3, DVec3)>,
) -> (f64, String) {
    let c = brdf.channels().len().min(MAX_CHANNELS);
    let mut fa = [0.0f32; MAX_CHANNELS];
    let mut fb = [0.0f32; MAX_CHANNELS];
    let mut samples = Vec::with_capacity(pairs);
    let mut scale = 0.0f64;
    for _ in 0..pairs {
        let Some((wi, wo)) = draw(rng) else {
            continue;
        };
        // Keep away from the horizon: grazing values are numerically fragile in many models.
        if wi.z < 0.02 || wo.z < 0.02 {
            continue;
        }
        let angle = rng.next_f64() * TAU;
        let (ti, to) = transformed(which, wi, wo, angle);
        brdf.eval(wi, wo, &mut fa[..c]);
        brdf.eval(ti, to, &mut fb[..c]);
        for k in 0..c {
            let (a, b) = (fa[k] as f64, fb[k] as f64);
            if a.is_finite() && b.is_finite() {
                scale = scale.max(a.abs()).max(b.abs());
                samples.push((a, b, wi, wo));
            }
        }
    }
    let floor = (scale * 1e-6).max(1e-30);
    let mut worst = (0.0, String::new());
    for (a, b, wi, wo) in samples {
        let e = (a - b).abs() / a.abs().max(b.abs()).max(floor);
        if e > worst.0 {
            worst = (
                e,
                format!(
                    "wi=({:.4},{:.4},{:.4}) wo=({:.4},{:.4},{:.4}): {a:.6e} vs {b:.6e}",
                    wi.x, wi.y, wi.z, wo.x, wo.y, wo.z
                ),
            );
        }
    }
    worst
}

/// The violation of symmetry `which` that [`verify`] and [`detect`] judge: over random pairs
/// ([`violation`]) and, for a symmetry the source does not declare, over pairs where it is
/// large too ([`sampled_violation`]): a model's flags are exact where it has a symmetry, and a
/// lobe random pairs miss must not pass for symmetric against them (Ward α = (1e-4, 4e-4) was
/// detected isotropic and its table baked so). The larger of the two.
fn judged_violation(brdf: &dyn Brdf, which: usize, tol: f64) -> (f64, String) {
    let v = violation(brdf, which, CHECK_PAIRS, 0x5EED);
    let f = brdf.flags();
    let declared = [f.isotropic, f.reciprocal, f.bilateral][which];
    if declared || !(v.0 <= tol) {
        return v;
    }
    let s = sampled_violation(brdf, which, CHECK_PAIRS, 0x5EED);
    if s.0 > v.0 || s.0.is_nan() { s } else { v }
}

/// Default tolerance of [`verify`] and [`detect`] (relative).
pub const DEFAULT_TOLERANCE: f64 = 1e-3;
/// Number of random pairs [`verify`] and [`detect`] evaluate.
pub const CHECK_PAIRS: usize = 20_000;

/// Checks that `brdf` has every symmetry in `sym` within relative tolerance `tol` (on random
/// pairs, and one the source does not declare also where it is large, as [`detect`]); the
/// first violated one gives [`Error::Symmetry`].
pub fn verify(brdf: &dyn Brdf, sym: Symmetry, tol: f64) -> Result<()> {
    let wanted = [sym.isotropic, sym.reciprocal, sym.bilateral];
    for (k, &w) in wanted.iter().enumerate() {
        if !w {
            continue;
        }
        let (e, at) = judged_violation(brdf, k, tol);
        if e > tol || e.is_nan() {
            return Err(Error::Symmetry {
                symmetry: SymmetryKind::ALL[k],
                error: e,
                tolerance: tol,
                at,
            });
        }
    }
    Ok(())
}

/// Detects which symmetries `brdf` has within relative tolerance `tol` by evaluating it on
/// [`CHECK_PAIRS`] random pairs per symmetry, and a symmetry it does not declare on as many
/// pairs drawn by its own sampler, where it is large (a lobe random pairs miss).
pub fn detect(brdf: &dyn Brdf, tol: f64) -> Symmetry {
    let ok = |k| judged_violation(brdf, k, tol).0 <= tol;
    Symmetry {
        isotropic: ok(0),
        reciprocal: ok(1),
        bilateral: ok(2),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast coordinates (polynomial trig, division-free half/diff angles, no renormalization
    /// of unit inputs) agree with the exact ones for every parameterization and symmetry: θ to
    /// the polynomials' error, φ the same up to the period of a periodic axis (a value on one
    /// side of 0 may land on the other side of the period).
    #[test]
    fn fast_coordinates_match_the_exact_ones() {
        let mut rng = Pcg32::new(11);
        let syms = [
            Symmetry::NONE,
            Symmetry::ALL,
            Symmetry {
                isotropic: true,
                reciprocal: true,
                bilateral: false,
            },
            Symmetry {
                isotropic: true,
                reciprocal: false,
                bilateral: true,
            },
            Symmetry {
                isotropic: false,
                reciprocal: true,
                bilateral: true,
            },
        ];
        let mut worst: f64 = 0.0;
        for k in 0..40_000 {
            let mut wi = geometry::uniform_hemisphere(rng.next_dvec2());
            let mut wo = geometry::uniform_hemisphere(rng.next_dvec2());
            match k % 4 {
                // Near the pole of the half vector (wo ≈ mirror of wi).
                1 => wo = (geometry::reflect_z(wi) + 1e-7 * wo).normalize(),
                // Non-unit inputs.
                2 => {
                    wi *= 3.0;
                    wo *= 0.25;
                }
                _ => {}
            }
            if k % 7 == 0 {
                wi = DVec3::new(wi.x, wi.y, wi.z.abs().max(1e-9));
            }
            for param in [Param::InOut, Param::HalfDiff] {
                for sym in syms {
                    let (Some(a), Some(b)) = (
                        canonical_coords(param, sym, wi, wo),
                        canonical_coords_fast(param, sym, wi, wo),
                    ) else {
                        panic!("{param:?} {sym}: {wi} {wo} valid for one path only");
                    };
                    for ax in 0..4 {
                        let mut d = (a[ax] - b[ax]).abs();
                        if ax % 2 == 1 {
                            d = d.min((d - PI).abs()).min((d - TAU).abs());
                        }
                        // fast_atan2 ≤ 2e-7, fast_acos ≤ 5e-8 (see fast_trig_is_accurate), and
                        // rounding well below both.
                        assert!(
                            d < 3e-7,
                            "{param:?} {sym} axis {ax}: exact {a:?} fast {b:?} ({wi}, {wo})"
                        );
                        worst = worst.max(d);
                    }
                }
            }
        }
        assert!(worst > 0.0, "the paths should differ by rounding somewhere");
    }

    /// A lobe narrower than random pairs ever hit — Ward α = (1e-4, 4e-4), whose f_r is 0 to
    /// f32 outside θh ≲ 0.1° — is anisotropic where it is not 0: random pairs see 0 = 0 on
    /// every rotation and took it for isotropic, and its table was baked isotropic (at 4e-4
    /// of the half vector off the mirror towards y the source is 2.5e5, the table 3.4e4). A
    /// symmetry the source does not declare must also hold on pairs where the source is
    /// large (drawn by its own sampler); declared ones, and sources that have the symmetry,
    /// are detected as before.
    #[test]
    fn a_sharp_anisotropic_lobe_is_not_detected_isotropic() {
        use crate::models::ward::Ward;
        use crate::spectrum::{Channels, Value};
        let ward = Ward::new(Value::Grey(0.3), 1e-4, 4e-4, &Channels::Rgb).unwrap();
        assert!(!ward.flags().isotropic);
        let d = detect(&ward, DEFAULT_TOLERANCE);
        assert!(!d.isotropic, "detected {d}");
        assert!(d.reciprocal && d.bilateral, "detected {d}");
        let iso = Symmetry {
            isotropic: true,
            ..Symmetry::NONE
        };
        assert!(matches!(
            verify(&ward, iso, DEFAULT_TOLERANCE),
            Err(Error::Symmetry {
                symmetry: SymmetryKind::Isotropic,
                ..
            })
        ));
        // The same lobe, isotropic: detected so.
        let round = Ward::new(Value::Grey(0.3), 2e-4, 2e-4, &Channels::Rgb).unwrap();
        assert_eq!(detect(&round, DEFAULT_TOLERANCE), Symmetry::ALL);
        // A symmetric source that declares nothing: still detected symmetric.
        struct Undeclared(crate::models::lambert::Lambert);
        impl Brdf for Undeclared {
            fn channels(&self) -> &crate::spectrum::Channels {
                self.0.channels()
            }
            fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
                self.0.eval(wi, wo, out)
            }
            fn flags(&self) -> crate::Flags {
                crate::Flags::default()
            }
            fn describe(&self) -> String {
                "undeclared".into()
            }
        }
        let lambert =
            crate::models::lambert::Lambert::new(Value::Grey(0.3), &Channels::Rgb).unwrap();
        assert_eq!(
            detect(&Undeclared(lambert), DEFAULT_TOLERANCE),
            Symmetry::ALL
        );
    }

    #[test]
    fn fast_trig_is_accurate() {
        let mut rng = Pcg32::new(1);
        let mut worst: f64 = 0.0;
        for _ in 0..200_000 {
            let x = rng.next_f64() * 2.0 - 1.0;
            worst = worst.max((fast_acos(x) - x.acos()).abs());
        }
        for x in [-1.0, 0.0, 1.0, 1.0 - 1e-12, -1.0 + 1e-12] {
            worst = worst.max((fast_acos(x) - x.acos()).abs());
        }
        assert!(worst < 5e-8, "acos {worst}");
        let mut worst: f64 = 0.0;
        for _ in 0..200_000 {
            let (y, x) = (rng.next_f64() * 2.0 - 1.0, rng.next_f64() * 2.0 - 1.0);
            worst = worst.max((fast_atan2(y, x) - y.atan2(x)).abs());
        }
        for (y, x) in [
            (0.0, 1.0),
            (1.0, 0.0),
            (0.0, -1.0),
            (-1.0, 0.0),
            (0.0, 0.0),
            (1e-300, 1.0),
        ] {
            worst = worst.max((fast_atan2(y, x) - f64::atan2(y, x)).abs());
        }
        assert!(worst < 2e-7, "atan2 {worst}");
    }
}
