//! Importance sampling for tables: tabulated, piecewise-constant distributions of f_r·cos θi.
//!
//! A [`TableSampler`] draws `wi` given `wo` for any [`Brdf`] that is cheap to evaluate (it is what
//! [`TabulatedBrdf`](super::TabulatedBrdf) uses for `sample` and `pdf`).
//!
//! # Design
//!
//! - **Conditioning grid.** Nodes over the outgoing direction: `theta_o` nodes over
//!   t = sqrt(1 − cos θo) ∈ [0, 1] (cell centres, t_k = (k + ½)/n; t = √2 sin(θo/2) is within 10 %
//!   of linear in θo, so the nodes are nearly uniform in θo, and finding them needs no `acos`).
//!   Isotropic sources: one node per θo at azimuth 0, and a query `wo` is rotated into that frame
//!   by vector algebra (cos φo = wo.x/|wo.xy|, sin φo = wo.y/|wo.xy|). Anisotropic sources: also
//!   `phi_o` periodic nodes over φo (no rotation).
//! - **Per node**: the hemisphere of `wi` is parameterized by the **equal-area** map
//!   square \[0,1\]² → concentric disk (Shirley–Chiu) → hemisphere (z = 1 − r², xy scaled by
//!   √(2 − r²), Lambert's azimuthal projection), so a uniform density on the square is the
//!   uniform density 1/(2π) on the hemisphere and a square cell has solid angle 2π/n². Cells
//!   near the pole are as compact as elsewhere (unlike (cos θ, φ) cells), which matters for lobes
//!   at normal incidence. Each of the `square`² cells gets the mean of f_r·cos θi (channel mean)
//!   over `supersample`² stratified points; rows (v) get a marginal CDF, each row a conditional
//!   CDF over u. A node whose values are all zero is uniform.
//! - **Interpolation between nodes**: stochastic. The linear weights w_k of the (2, or 4 for
//!   anisotropic sources) nodes around `wo` select node k with probability w_k, so the density
//!   is the mixture Σ_k w_k p_k(wi) — exactly what [`TableSampler::pdf`] returns.
//! - **Defensive mixture**: a fraction `cosine_fraction` (default 0.1) of the samples are
//!   cosine-distributed, so the support is the whole hemisphere even where the tabulated cells
//!   are zero (a lobe narrower than the supersampling): pdf = α cos θi/π + (1 − α) Σ w_k p_k.
//! - **Random numbers**: the two uniforms are reused by rescaling (u.x picks cosine-or-table,
//!   then the node, then the column; u.y picks the row), so sampling needs no third number and
//!   never allocates. A table-branch sample costs two CDF searches (branch-free counts over n + 1 entries), one
//!   `sin_cos` (the concentric map), a few `sqrt`, and one lookup of the source for the weight;
//!   all nodes share the square's cells, so the mixture pdf needs no inverse map. The cosine
//!   branch and [`TableSampler::pdf`] add the inverse map (one `atan`).
//!
//! # Resolution and memory
//!
//! Defaults ([`SamplingResolution::default`]): isotropic 48 × 48 cells per node, 24 θo nodes
//! (≈ 2 f32 per cell → 440 KB); anisotropic ([`SamplingResolution::anisotropic`]) 32 × 32 cells,
//! 16 θo × 16 φo nodes (≈ 2 MB). Building evaluates the source
//! nodes × cells × supersample² times (isotropic default: 221 k evaluations, ~20 ms for a
//! table); it runs on the calling thread (no rayon: a lazy build inside `OnceLock` must not
//! re-enter itself through rayon's work stealing).

use glam::{DVec2, DVec3};
use std::f64::consts::{FRAC_1_PI, FRAC_PI_4, TAU};

use crate::brdf::{Brdf, BrdfSample};
use crate::geometry;
use crate::spectrum::MAX_CHANNELS;

/// Resolution of a [`TableSampler`] (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SamplingResolution {
    /// Cells per side of the equal-area square (cells per node = square²).
    pub square: usize,
    /// Conditioning nodes over t = sqrt(1 − cos θo).
    pub theta_o: usize,
    /// Conditioning nodes over φo (anisotropic sources only).
    pub phi_o: usize,
    /// Evaluation points per cell side when building.
    pub supersample: usize,
    /// Fraction of cosine-distributed samples (0 < α < 1).
    pub cosine_fraction: f64,
}

impl Default for SamplingResolution {
    fn default() -> Self {
        SamplingResolution {
            square: 48,
            theta_o: 24,
            phi_o: 16,
            supersample: 2,
            cosine_fraction: 0.1,
        }
    }
}

impl SamplingResolution {
    /// The default for anisotropic sources (fewer cells per node, 16 × 16 nodes).
    pub fn anisotropic() -> Self {
        SamplingResolution {
            square: 32,
            theta_o: 16,
            phi_o: 16,
            ..Default::default()
        }
    }
}

/// One node's piecewise-constant distribution over the equal-area square.
#[derive(Debug, Clone)]
struct Node {
    /// Density on the unit square per cell (mean 1), row-major (row = v index).
    density: Box<[f32]>,
    /// Marginal CDF over rows, n + 1 entries from 0 to 1.
    rows: Box<[f32]>,
    /// Conditional CDF over columns per row, n × (n + 1) entries.
    cols: Box<[f32]>,
}

/// Tabulated importance sampling of f_r·cos θi (see the module docs).
#[derive(Debug, Clone)]
pub struct TableSampler {
    n: usize,
    nt: usize,
    np: usize,
    isotropic: bool,
    alpha: f64,
    nodes: Box<[Node]>,
}

/// Up to four (node, weight) pairs.
#[derive(Clone, Copy)]
struct Mix {
    idx: [usize; 4],
    w: [f64; 4],
    len: usize,
}

/// The equal-area map square \[0,1\]² → upper hemisphere (constant Jacobian 2π).
#[inline]
pub fn square_to_hemisphere(p: DVec2) -> DVec3 {
    let d = geometry::concentric_disk(p);
    let r2 = d.length_squared().min(1.0);
    let s = (2.0 - r2).sqrt();
    DVec3::new(d.x * s, d.y * s, 1.0 - r2)
}

/// The inverse of [`square_to_hemisphere`] for a unit `w` with z ≥ 0.
#[inline]
pub fn hemisphere_to_square(w: DVec3) -> DVec2 {
    let z = w.z.clamp(0.0, 1.0);
    // Disk point: direction of w.xy, radius r = sqrt(1 − z); |w.xy| = r·sqrt(1 + z).
    let inv = 1.0 / (1.0 + z).sqrt();
    let (dx, dy) = (w.x * inv, w.y * inv);
    let r = (1.0 - z).sqrt();
    let (a, b) = if dx == 0.0 && dy == 0.0 {
        (0.0, 0.0)
    } else if dx.abs() >= dy.abs() {
        let a = r.copysign(dx);
        (a, a * (dy / dx).atan() / FRAC_PI_4)
    } else {
        let b = r.copysign(dy);
        (b * (dx / dy).atan() / FRAC_PI_4, b)
    };
    DVec2::new(0.5 * (a + 1.0), 0.5 * (b + 1.0))
}

/// Index of the interval of `cdf` (n + 1 nondecreasing entries, 0 … 1, the last exactly 1)
/// containing `u` ∈ [0, 1), skipping empty intervals: the number of inner entries ≤ u. A
/// branch-free count (vectorized) beats a binary search at these sizes (n ≤ 64): no mispredicts.
#[inline]
fn find_interval(cdf: &[f32], u: f64) -> usize {
    let n = cdf.len() - 1;
    cdf[1..n].iter().map(|&x| ((x as f64) <= u) as usize).sum()
}

impl TableSampler {
    /// Builds the distributions of `brdf` (f_r·cos θi, channel mean). `isotropic`: condition on
    /// θo only and rotate by φo.
    pub fn build(brdf: &dyn Brdf, isotropic: bool, res: &SamplingResolution) -> TableSampler {
        let n = res.square.max(1);
        let nt = res.theta_o.max(1);
        let np = if isotropic { 1 } else { res.phi_o.max(1) };
        let ss = res.supersample.max(1);
        let c = brdf.channels().len().clamp(1, MAX_CHANNELS);
        let mut f = [0.0f32; MAX_CHANNELS];
        let mut nodes = Vec::with_capacity(nt * np);
        let mut mass = vec![0.0f64; n * n];
        for kt in 0..nt {
            let t = (kt as f64 + 0.5) / nt as f64;
            let zo = 1.0 - t * t;
            let ro = (1.0 - zo * zo).max(0.0).sqrt();
            for kp in 0..np {
                let (sp, cp) = (TAU * kp as f64 / np as f64).sin_cos();
                let wo = DVec3::new(ro * cp, ro * sp, zo);
                for (cell, m) in mass.iter_mut().enumerate() {
                    let (i, j) = (cell / n, cell % n);
                    let mut sum = 0.0;
                    for a in 0..ss {
                        for b in 0..ss {
                            let p = DVec2::new(
                                (j as f64 + (b as f64 + 0.5) / ss as f64) / n as f64,
                                (i as f64 + (a as f64 + 0.5) / ss as f64) / n as f64,
                            );
                            let wi = square_to_hemisphere(p);
                            if wi.z <= 0.0 {
                                continue;
                            }
                            brdf.eval(wi, wo, &mut f[..c]);
                            let v: f64 = f[..c].iter().map(|&x| x as f64).sum::<f64>() / c as f64;
                            if v.is_finite() && v > 0.0 {
                                sum += v * wi.z;
                            }
                        }
                    }
                    *m = sum;
                }
                nodes.push(Node::from_mass(&mass, n));
            }
        }
        TableSampler {
            n,
            nt,
            np,
            isotropic,
            alpha: res.cosine_fraction.clamp(1e-6, 1.0),
            nodes: nodes.into(),
        }
    }

    /// Bytes held by the distributions.
    pub fn memory_bytes(&self) -> usize {
        self.nodes
            .iter()
            .map(|n| 4 * (n.density.len() + n.rows.len() + n.cols.len()))
            .sum()
    }

    /// Rotation (cos φo, sin φo) into the node frame (isotropic) or identity.
    #[inline]
    fn frame(&self, wo: DVec3) -> (f64, f64) {
        if !self.isotropic {
            return (1.0, 0.0);
        }
        let r2 = wo.x * wo.x + wo.y * wo.y;
        if r2 > 1e-300 {
            let inv = 1.0 / r2.sqrt();
            (wo.x * inv, wo.y * inv)
        } else {
            (1.0, 0.0)
        }
    }

    /// The nodes around a unit `wo` and their linear weights.
    #[inline]
    fn mix(&self, wo: DVec3) -> Mix {
        let t = (1.0 - wo.z).max(0.0).sqrt();
        let s = (t * self.nt as f64 - 0.5).clamp(0.0, (self.nt - 1) as f64);
        let t0 = (s as usize).min(self.nt - 1);
        let t1 = (t0 + 1).min(self.nt - 1);
        let ft = s - t0 as f64;
        if self.np == 1 {
            return Mix {
                idx: [t0, t1, 0, 0],
                w: [1.0 - ft, ft, 0.0, 0.0],
                len: 2,
            };
        }
        let mut phi = wo.y.atan2(wo.x);
        if phi < 0.0 {
            phi += TAU;
        }
        let sp = phi / TAU * self.np as f64;
        let p0 = (sp as usize).min(self.np - 1);
        let p1 = (p0 + 1) % self.np;
        let fp = (sp - p0 as f64).clamp(0.0, 1.0);
        let np = self.np;
        Mix {
            idx: [t0 * np + p0, t0 * np + p1, t1 * np + p0, t1 * np + p1],
            w: [
                (1.0 - ft) * (1.0 - fp),
                (1.0 - ft) * fp,
                ft * (1.0 - fp),
                ft * fp,
            ],
            len: 4,
        }
    }

    /// Density of a unit local-frame `wl` (z > 0) under the mixture `m`.
    #[inline]
    fn pdf_local(&self, wl: DVec3, m: &Mix) -> f64 {
        let p = hemisphere_to_square(wl);
        let n = self.n;
        let i = ((p.y * n as f64) as usize).min(n - 1);
        let j = ((p.x * n as f64) as usize).min(n - 1);
        self.pdf_cell(i * n + j, wl.z, m)
    }

    /// Density of a local-frame direction with z = `z` in square cell `cell` under `m`.
    #[inline]
    fn pdf_cell(&self, cell: usize, z: f64, m: &Mix) -> f64 {
        let mut d = 0.0;
        for k in 0..m.len {
            if m.w[k] > 0.0 {
                d += m.w[k] * self.nodes[m.idx[k]].density[cell] as f64;
            }
        }
        self.alpha * z * FRAC_1_PI + (1.0 - self.alpha) * d * (0.5 * FRAC_1_PI)
    }

    /// The density (solid angle) with which [`TableSampler::sample`] draws `wi` given `wo`;
    /// 0 when either is invalid or at/below the horizon.
    pub fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let (Some(wi), Some(wo)) = (geometry::normalize(wi), geometry::normalize(wo)) else {
            return 0.0;
        };
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let (c, s) = self.frame(wo);
        let wl = DVec3::new(c * wi.x + s * wi.y, -s * wi.x + c * wi.y, wi.z);
        self.pdf_local(wl, &self.mix(wo))
    }

    /// Draws `wi` for `wo` from `u` ∈ [0,1)²; evaluates `brdf` for the weight f_r cos θi / pdf.
    pub fn sample(
        &self,
        brdf: &dyn Brdf,
        wo: DVec3,
        u: DVec2,
        weight: &mut [f32],
    ) -> Option<BrdfSample> {
        let wo = geometry::unit(wo)?;
        if wo.z <= 0.0 {
            return None;
        }
        let (c, s) = self.frame(wo);
        let m = self.mix(wo);
        // The table branch knows its cell: no inverse map needed for the pdf (the cell of a point
        // within rounding of a cell edge may differ from `pdf()`'s by that rounding — a
        // measure-zero event).
        let (wl, pdf) = if u.x < self.alpha {
            let wl = geometry::cosine_hemisphere(DVec2::new(u.x / self.alpha, u.y));
            (wl, self.pdf_local(wl, &m))
        } else {
            let mut ux = ((u.x - self.alpha) / (1.0 - self.alpha)).min(1.0 - f64::EPSILON);
            // Choose node k with probability w_k, reusing ux.
            let (mut k, mut start, mut acc) = (0, 0.0, 0.0);
            for q in 0..m.len {
                let w = m.w[q];
                if w <= 0.0 {
                    continue;
                }
                (k, start) = (q, acc);
                acc += w;
                if ux < acc {
                    break;
                }
            }
            ux = ((ux - start) / m.w[k]).clamp(0.0, 1.0 - f64::EPSILON);
            let node = &self.nodes[m.idx[k]];
            let n = self.n;
            let i = find_interval(&node.rows, u.y);
            let (r0, r1) = (node.rows[i] as f64, node.rows[i + 1] as f64);
            let v = ((u.y - r0) / (r1 - r0)).clamp(0.0, 1.0);
            let cols = &node.cols[i * (n + 1)..(i + 1) * (n + 1)];
            let j = find_interval(cols, ux);
            let (c0, c1) = (cols[j] as f64, cols[j + 1] as f64);
            let uu = ((ux - c0) / (c1 - c0)).clamp(0.0, 1.0);
            let wl = square_to_hemisphere(DVec2::new(
                (j as f64 + uu) / n as f64,
                (i as f64 + v) / n as f64,
            ));
            (wl, self.pdf_cell(i * n + j, wl.z, &m))
        };
        if wl.z <= 0.0 {
            return None;
        }
        // A rotation about z keeps the (unit) length.
        let wi = DVec3::new(c * wl.x - s * wl.y, s * wl.x + c * wl.y, wl.z);
        if !(pdf > 0.0) || !pdf.is_finite() {
            return None;
        }
        let ch = brdf.channels().len();
        brdf.eval(wi, wo, &mut weight[..ch]);
        let k = wi.z / pdf;
        for w in &mut weight[..ch] {
            *w = (*w as f64 * k) as f32;
        }
        Some(BrdfSample {
            wi,
            pdf,
            delta: false,
        })
    }
}

impl Node {
    fn from_mass(mass: &[f64], n: usize) -> Node {
        let total: f64 = mass.iter().sum();
        let uniform = !(total > 0.0) || !total.is_finite();
        let mut density = vec![0.0f32; n * n];
        let mut rows = vec![0.0f32; n + 1];
        let mut cols = vec![0.0f32; n * (n + 1)];
        let mut acc_rows = 0.0f64;
        for i in 0..n {
            let row = &mass[i * n..(i + 1) * n];
            let row_total: f64 = if uniform { n as f64 } else { row.iter().sum() };
            let cc = &mut cols[i * (n + 1)..(i + 1) * (n + 1)];
            let mut acc = 0.0f64;
            for j in 0..n {
                let m = if uniform { 1.0 } else { row[j] };
                acc += m;
                cc[j + 1] = if row_total > 0.0 {
                    (acc / row_total) as f32
                } else {
                    (j + 1) as f32 / n as f32
                };
                density[i * n + j] = if uniform {
                    1.0
                } else {
                    (m / total * (n * n) as f64) as f32
                };
            }
            cc[n] = 1.0;
            acc_rows += row_total;
            rows[i + 1] = (acc_rows / if uniform { (n * n) as f64 } else { total }) as f32;
        }
        rows[n] = 1.0;
        // The density must be what the CDFs sample: recompute it from the stored f32 CDFs.
        for i in 0..n {
            let pr = rows[i + 1] as f64 - rows[i] as f64;
            for j in 0..n {
                let cc = &cols[i * (n + 1)..];
                let pc = cc[j + 1] as f64 - cc[j] as f64;
                density[i * n + j] = (pr * pc * (n * n) as f64) as f32;
            }
        }
        Node {
            density: density.into(),
            rows: rows.into(),
            cols: cols.into(),
        }
    }
}

#[cfg(test)]
#[path = "sampling_tests.rs"]
mod table_tests;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;

    #[test]
    fn equal_area_map_round_trips() {
        let mut rng = Pcg32::new(3);
        for _ in 0..10_000 {
            let p = rng.next_dvec2();
            let w = square_to_hemisphere(p);
            assert!((w.length() - 1.0).abs() < 1e-12 && w.z >= 0.0);
            let q = hemisphere_to_square(w);
            assert!((p - q).length() < 1e-9, "{p} -> {w} -> {q}");
        }
    }

    #[test]
    fn equal_area_map_has_constant_jacobian() {
        // Solid angle of a small square patch ≈ 2π × its area, anywhere on the square.
        let mut rng = Pcg32::new(4);
        let h = 1e-5;
        for _ in 0..1000 {
            let p = rng.next_dvec2() * (1.0 - 2.0 * h) + DVec2::splat(h);
            let a = square_to_hemisphere(p);
            let bx = square_to_hemisphere(p + DVec2::new(h, 0.0)) - a;
            let by = square_to_hemisphere(p + DVec2::new(0.0, h)) - a;
            let area = bx.cross(by).length() / (h * h);
            assert!((area - TAU).abs() < 1e-3 * TAU, "{p}: {area}");
        }
    }

    #[test]
    fn find_interval_skips_empty_intervals() {
        let cdf = [0.0, 0.0, 0.5, 0.5, 1.0];
        assert_eq!(find_interval(&cdf, 0.0), 1);
        assert_eq!(find_interval(&cdf, 0.49), 1);
        assert_eq!(find_interval(&cdf, 0.5), 3);
        assert_eq!(find_interval(&cdf, 0.999), 3);
    }
}
