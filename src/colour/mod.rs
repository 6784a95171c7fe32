//! Colour: how RGB data becomes a spectrum, and how a spectrum becomes RGB, so that colour
//! survives a spectral renderer.
//!
//! A spectral renderer (pbrt-v4, Mitsuba's spectral variants) turns the spectrum it computes into
//! a pixel by the CIE 1931 observer: XYZ = ∫ s(λ) E(λ) (x̄, ȳ, z̄)(λ) dλ, then linear sRGB. An
//! RGB source evaluated at a wavelength must therefore give a spectrum whose projection is its
//! RGB again — otherwise a saturated red lobe renders orange (session 32 measured +13 % green
//! for an RGB file written spectral and rendered in pbrt-v4 under the older rule, values
//! interpolated between three representative wavelengths).
//!
//! [`rgb_basis_at`] is that map: three smooth, non-negative spectra b_R, b_G, b_B that sum to 1
//! at every wavelength and project to (1, 0, 0), (0, 1, 0), (0, 0, 1) exactly. RGB data c becomes
//! the spectrum c_R b_R + c_G b_G + c_B b_B: linear (a table's interpolation commutes with it),
//! grey exactly flat, non-negative for non-negative RGB, and [`srgb_of`] of it is c.
//!
//! The projection is the reflectance convention of renderers: a surface seen under CIE D65 light
//! (the white of sRGB), normalised so that a perfect white reflector is (1, 1, 1). The integral
//! is the CIE sum at 1 nm over 360–830 nm with the 5 nm tables of [`cie`] interpolated
//! linearly; the XYZ → linear sRGB matrix is built from the sRGB primaries (IEC 61966-2-1) and
//! the white these tables give, so that white maps to (1, 1, 1) to rounding.
//!
//! Each basis spectrum is a softmax of quadratics in λ, exp(g_i) / Σ_j exp(g_j) with g_G = 0
//! and g_R, g_B quadratic: six coefficients for the six conditions P(b_R) = (1, 0, 0) and
//! P(b_B) = (0, 0, 1) (P(b_G) follows from P(1) = (1, 1, 1)), solved by Newton's method once,
//! on first use. b_R rises again towards the violet end (0.06 at 400 nm, 0.45 at 360 nm, where
//! the observer sees almost nothing): the sRGB red primary has a little Z (x + y = 0.97), which
//! long wavelengths alone cannot give — Jakob and Hanika's sigmoid spectra for red do the same.
//!
//! ```
//! use brdftab::colour::{rgb_basis_at, srgb_of};
//!
//! let rgb = [0.8, 0.3, 0.1];
//! let spectrum = |nm: f64| {
//!     let b = rgb_basis_at(nm);
//!     rgb[0] * b[0] + rgb[1] * b[1] + rgb[2] * b[2]
//! };
//! let back = srgb_of(spectrum);
//! assert!((0..3).all(|i| (back[i] - rgb[i]).abs() < 1e-9));
//! ```

pub mod cie;

use std::sync::OnceLock;

/// The range the projection integrates over and the basis is tabulated on (nm); outside it the
/// basis is held at its end values.
pub const RANGE_NM: (f64, f64) = (360.0, 830.0);

/// Points of the 1 nm grid over [`RANGE_NM`].
const N: usize = 471;

/// sRGB primaries' chromaticities (x, y), IEC 61966-2-1.
const SRGB_PRIMARIES: [[f64; 2]; 3] = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];

struct Tables {
    /// Linear sRGB weight of the spectrum's value at each 1 nm point (rows R, G, B).
    weights: [[f64; 3]; N],
    /// The basis b_R, b_G, b_B at each 1 nm point.
    basis: [[f64; 3]; N],
}

#[inline]
fn tables() -> &'static Tables {
    static T: OnceLock<Box<Tables>> = OnceLock::new();
    T.get_or_init(|| {
        let weights = projection_weights();
        let basis = solve_basis(&weights);
        Box::new(Tables { weights, basis })
    })
}

/// The CIE tables at `nm` (on the 1 nm grid), linearly interpolated: (x̄, ȳ, z̄) · D65.
fn cmf_d65(nm: f64) -> [f64; 3] {
    let u = (nm - cie::START_NM) / cie::STEP_NM;
    let i = (u.floor() as usize).min(cie::D65.len() - 2);
    let t = u - i as f64;
    let lerp = |a: f64, b: f64| a + t * (b - a);
    let e = lerp(cie::D65[i], cie::D65[i + 1]);
    let c = |k: usize| lerp(cie::CMF_1931[i][k], cie::CMF_1931[i + 1][k]) * e;
    [c(0), c(1), c(2)]
}

fn solve3(m: [[f64; 3]; 3], b: [f64; 3]) -> [f64; 3] {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(m);
    let mut x = [0.0; 3];
    for (j, xj) in x.iter_mut().enumerate() {
        let mut mj = m;
        for i in 0..3 {
            mj[i][j] = b[i];
        }
        *xj = det(mj) / d;
    }
    x
}

/// The XYZ → linear sRGB matrix whose white is `white` (XYZ with Y = 1).
fn xyz_to_srgb(white: [f64; 3]) -> [[f64; 3]; 3] {
    // Columns: the primaries' XYZ at Y = 1, scaled so that they sum to the white.
    let p: [[f64; 3]; 3] = {
        let col = |k: usize| {
            let [x, y] = SRGB_PRIMARIES[k];
            [x / y, 1.0, (1.0 - x - y) / y]
        };
        let (r, g, b) = (col(0), col(1), col(2));
        [[r[0], g[0], b[0]], [r[1], g[1], b[1]], [r[2], g[2], b[2]]]
    };
    let s = solve3(p, white);
    let rgb_to_xyz = [
        [p[0][0] * s[0], p[0][1] * s[1], p[0][2] * s[2]],
        [p[1][0] * s[0], p[1][1] * s[1], p[1][2] * s[2]],
        [p[2][0] * s[0], p[2][1] * s[1], p[2][2] * s[2]],
    ];
    // Invert column by column.
    let mut inv = [[0.0; 3]; 3];
    for j in 0..3 {
        let mut e = [0.0; 3];
        e[j] = 1.0;
        let c = solve3(rgb_to_xyz, e);
        for i in 0..3 {
            inv[i][j] = c[i];
        }
    }
    inv
}

fn projection_weights() -> [[f64; 3]; N] {
    let mut xyz = [[0.0; 3]; N];
    let mut y_sum = 0.0;
    for (i, w) in xyz.iter_mut().enumerate() {
        *w = cmf_d65(RANGE_NM.0 + i as f64);
        y_sum += w[1];
    }
    let mut white = [0.0; 3];
    for w in xyz.iter_mut() {
        for k in 0..3 {
            w[k] /= y_sum;
            white[k] += w[k];
        }
    }
    let m = xyz_to_srgb(white);
    let mut out = [[0.0; 3]; N];
    for (o, w) in out.iter_mut().zip(&xyz) {
        for (r, row) in m.iter().enumerate() {
            o[r] = row[0] * w[0] + row[1] * w[1] + row[2] * w[2];
        }
    }
    out
}

/// The softmax basis for coefficients `p` (g_R = p0 + p1 x + p2 x², g_B = p3 + p4 x + p5 x²,
/// x = (λ − 550 nm) / 100 nm) at the 1 nm points.
fn basis_for(p: &[f64; 6]) -> [[f64; 3]; N] {
    let mut out = [[0.0; 3]; N];
    for (i, o) in out.iter_mut().enumerate() {
        let x = (RANGE_NM.0 + i as f64 - 550.0) / 100.0;
        let g = [
            p[0] + x * (p[1] + x * p[2]),
            0.0,
            p[3] + x * (p[4] + x * p[5]),
        ];
        let top = g[0].max(g[1]).max(g[2]);
        let e = g.map(|v| (v - top).exp());
        let s = e[0] + e[1] + e[2];
        *o = e.map(|v| v / s);
    }
    out
}

fn project(weights: &[[f64; 3]; N], s: impl Fn(usize) -> f64) -> [f64; 3] {
    let mut c = [0.0; 3];
    for (i, w) in weights.iter().enumerate() {
        let v = s(i);
        for k in 0..3 {
            c[k] += w[k] * v;
        }
    }
    c
}

/// Residuals of the six conditions: P(b_R) − (1, 0, 0), P(b_B) − (0, 0, 1).
fn residual(weights: &[[f64; 3]; N], p: &[f64; 6]) -> [f64; 6] {
    let b = basis_for(p);
    let r = project(weights, |i| b[i][0]);
    let bl = project(weights, |i| b[i][2]);
    [r[0] - 1.0, r[1], r[2], bl[0], bl[1], bl[2] - 1.0]
}

fn solve_basis(weights: &[[f64; 3]; N]) -> [[f64; 3]; N] {
    // A start near the solution (found once by Levenberg–Marquardt from g_R = 8x, g_B = −8x);
    // Newton's method converges from it in three steps to rounding.
    let mut p = [-4.92, 6.32, 13.0, -4.09, -0.89, 9.04];
    for _ in 0..6 {
        let f = residual(weights, &p);
        let mut jac = [[0.0; 6]; 6];
        for k in 0..6 {
            let (mut a, mut b) = (p, p);
            a[k] += 1e-6;
            b[k] -= 1e-6;
            let (fa, fb) = (residual(weights, &a), residual(weights, &b));
            for r in 0..6 {
                jac[r][k] = (fa[r] - fb[r]) / 2e-6;
            }
        }
        let step = solve6(jac, f);
        for k in 0..6 {
            p[k] -= step[k];
        }
    }
    basis_for(&p)
}

/// Gaussian elimination with partial pivoting (the Jacobian is well conditioned here).
fn solve6(mut a: [[f64; 6]; 6], mut b: [f64; 6]) -> [f64; 6] {
    for c in 0..6 {
        let piv = (c..6)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap_or(c);
        a.swap(c, piv);
        b.swap(c, piv);
        let pivot = a[c];
        for r in c + 1..6 {
            let f = a[r][c] / pivot[c];
            for (x, p) in a[r][c..].iter_mut().zip(&pivot[c..]) {
                *x -= f * p;
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = [0.0; 6];
    for r in (0..6).rev() {
        let s: f64 = (r + 1..6).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

/// Weights (R, G, B) of the RGB basis spectra at `nm`: RGB data (r, g, b) at this wavelength is
/// `r w[0] + g w[1] + b w[2]`. The weights are ≥ 0 and sum to 1; they are interpolated linearly
/// between 1 nm points and held at their end values outside [`RANGE_NM`]. At a non-wavelength
/// (NaN, ±∞, ≤ 0 nm: not a finite number of nm > 0, the rule of `spectrum::is_wavelength`) they
/// are NaN: RGB data read there is NaN, not the violet or red end's colour passed off as data.
#[inline]
pub fn rgb_basis_at(nm: f64) -> [f64; 3] {
    let b = &tables().basis;
    let u = nm - RANGE_NM.0;
    if !(u > 0.0) || u >= (N - 1) as f64 {
        // Only here can a non-wavelength land (NaN fails `u > 0`, ∞ and ≤ 0 are outside).
        // `spectrum::is_wavelength`, written out: `spectrum` builds on this module.
        if !(nm.is_finite() && nm > 0.0) {
            return [f64::NAN; 3];
        }
        return if u > 0.0 { b[N - 1] } else { b[0] };
    }
    let i = u as usize;
    let t = u - i as f64;
    let (a, c) = (b[i], b[i + 1]);
    [
        a[0] + t * (c[0] - a[0]),
        a[1] + t * (c[1] - a[1]),
        a[2] + t * (c[2] - a[2]),
    ]
}

/// Linear sRGB of a spectrum (a reflectance seen under D65; the spectrum 1 gives (1, 1, 1)),
/// summed at the 1 nm points of [`RANGE_NM`].
pub fn srgb_of(spectrum: impl Fn(f64) -> f64) -> [f64; 3] {
    project(&tables().weights, |i| spectrum(RANGE_NM.0 + i as f64))
}

/// Linear sRGB of a sampled spectrum: `values` at `wavelengths` (nm, strictly increasing),
/// interpolated linearly between them and held at the end values, as brdftab reads sampled
/// spectra everywhere. Returns per-sample weights: RGB = Σ_k `w[k] values[k]`, so that a caller can
/// project many spectra on the same wavelengths at three multiply-adds per sample.
pub fn srgb_weights(wavelengths: &[f64]) -> Vec<[f64; 3]> {
    let n = wavelengths.len();
    let mut out = vec![[0.0; 3]; n];
    if n == 0 {
        return out;
    }
    for (i, w) in tables().weights.iter().enumerate() {
        let nm = RANGE_NM.0 + i as f64;
        let (k0, k1, t) = if n == 1 || nm <= wavelengths[0] {
            (0, 0, 0.0)
        } else if nm >= wavelengths[n - 1] {
            (n - 1, n - 1, 0.0)
        } else {
            let k = wavelengths.partition_point(|&x| x <= nm).clamp(1, n - 1);
            let t = (nm - wavelengths[k - 1]) / (wavelengths[k] - wavelengths[k - 1]);
            (k - 1, k, t)
        };
        for c in 0..3 {
            out[k0][c] += (1.0 - t) * w[c];
            out[k1][c] += t * w[c];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tables_give_the_d65_white_point_and_the_luminance_peak() {
        let mut xyz = [0.0; 3];
        for i in 0..N {
            let c = cmf_d65(RANGE_NM.0 + i as f64);
            for k in 0..3 {
                xyz[k] += c[k];
            }
        }
        let s = xyz[0] + xyz[1] + xyz[2];
        // CIE 015:2018: D65 is x 0.31272, y 0.32903 with the 2° observer.
        assert!((xyz[0] / s - 0.31272).abs() < 5e-5, "x {}", xyz[0] / s);
        assert!((xyz[1] / s - 0.32903).abs() < 5e-5, "y {}", xyz[1] / s);
        assert_eq!(cie::CMF_1931[39][1], 1.0); // ȳ(555 nm)
        assert_eq!(cie::D65[40], 100.0); // D65(560 nm)
    }

    #[test]
    fn white_projects_to_one_and_the_matrix_is_srgb() {
        let w = srgb_of(|_| 1.0);
        for c in w {
            assert!((c - 1.0).abs() < 1e-12, "{w:?}");
        }
        // IEC 61966-2-1 publishes the XYZ → sRGB matrix to four decimals; ours, built from the
        // same primaries and the white these tables give, agrees to that precision.
        let white = {
            let mut y = 0.0;
            let mut xyz = [0.0; 3];
            for i in 0..N {
                let c = cmf_d65(RANGE_NM.0 + i as f64);
                y += c[1];
                for k in 0..3 {
                    xyz[k] += c[k];
                }
            }
            xyz.map(|v| v / y)
        };
        let m = xyz_to_srgb(white);
        let published = [
            [3.2406, -1.5372, -0.4986],
            [-0.9689, 1.8758, 0.0415],
            [0.0557, -0.2040, 1.0570],
        ];
        for r in 0..3 {
            for c in 0..3 {
                assert!((m[r][c] - published[r][c]).abs() < 6e-4, "{m:?}");
            }
        }
    }

    #[test]
    fn the_basis_is_a_non_negative_partition_of_unity_that_projects_to_the_primaries() {
        let t = tables();
        for b in &t.basis {
            assert!(b.iter().all(|&v| v >= 0.0), "{b:?}");
            assert!((b[0] + b[1] + b[2] - 1.0).abs() < 1e-15);
        }
        for k in 0..3 {
            let p = project(&t.weights, |i| t.basis[i][k]);
            for (c, v) in p.iter().enumerate() {
                let want = if c == k { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-12, "P(b_{k}) = {p:?}");
            }
        }
    }

    #[test]
    fn rgb_round_trips_through_the_spectrum_and_grey_is_flat() {
        for rgb in [
            [1.0, 0.0, 0.0],
            [0.05, 0.9, 0.3],
            [2.0, 0.5, 7.0],
            [0.3, 0.3, 0.3],
        ] {
            let s = |nm: f64| {
                let b = rgb_basis_at(nm);
                rgb[0] * b[0] + rgb[1] * b[1] + rgb[2] * b[2]
            };
            let back = srgb_of(s);
            for c in 0..3 {
                assert!(
                    (back[c] - rgb[c]).abs() < 1e-11 * rgb[c].max(1.0),
                    "{rgb:?} → {back:?}"
                );
            }
        }
        for nm in [1e-300, 300.0, 360.0, 444.4, 555.0, 700.0, 900.0, 1e300] {
            let b = rgb_basis_at(nm);
            assert!((0.3 * b[0] + 0.3 * b[1] + 0.3 * b[2] - 0.3).abs() < 1e-15);
        }
    }

    #[test]
    fn sampled_spectra_project_by_their_weights() {
        // A spectrum sampled every 10 nm and read linearly between samples: the weights give
        // the projection of that piecewise linear function exactly.
        let wl: Vec<f64> = (0..48).map(|i| 360.0 + 10.0 * i as f64).collect();
        let vals: Vec<f64> = wl
            .iter()
            .map(|&x| 0.5 + 0.4 * ((x - 360.0) / 60.0).sin())
            .collect();
        let w = srgb_weights(&wl);
        let mut by_weights = [0.0; 3];
        for (wk, v) in w.iter().zip(&vals) {
            for c in 0..3 {
                by_weights[c] += wk[c] * v;
            }
        }
        let lerped = |nm: f64| {
            let k = wl.partition_point(|&x| x <= nm).clamp(1, wl.len() - 1);
            let t = ((nm - wl[k - 1]) / 10.0).min(1.0);
            vals[k - 1] + t * (vals[k] - vals[k - 1])
        };
        let direct = srgb_of(lerped);
        for c in 0..3 {
            assert!(
                (by_weights[c] - direct[c]).abs() < 1e-12,
                "{by_weights:?} {direct:?}"
            );
        }
        // The weights of any sampling sum, per channel, to the projection of 1.
        let sums = srgb_weights(&[500.0, 600.0])
            .iter()
            .fold([0.0; 3], |a, w| [a[0] + w[0], a[1] + w[1], a[2] + w[2]]);
        assert!(sums.iter().all(|s| (s - 1.0).abs() < 1e-12));
    }
}
