//! Fitting a [`Calibration`]: the source's albedos on one quadrature ([`AlbedoReference`]), the
//! table's on the same rule, and the factors balanced until the two agree ([`calibrate`]).

use rayon::prelude::*;

use super::Calibration;
use crate::analysis::fidelity::{Reversed, Turned, light_azimuths, mirror_albedo};
use crate::analysis::pair_rule::mirror_rule;
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::progress::{Progress, Silent};
use crate::quadrature::gauss_legendre;
use crate::spectrum::MAX_CHANNELS;
use crate::table::{Table, TabulatedBrdf};

/// How [`calibrate`] integrates.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationOptions {
    /// Nodes of the θ axis.
    pub nodes: usize,
    /// Azimuths of the albedo rule ([`mirror_albedo`]).
    pub nphi: usize,
    /// Gauss-Legendre nodes per segment of the albedo rule.
    pub order: usize,
    /// The axis ends this far above the horizon (radians): at θ = 90° a direction lies in the
    /// surface, where measured data have no value; beyond the end the last node's factor holds.
    pub horizon_margin: f64,
    /// Calibrate the viewer's albedo too (k_out); otherwise only the light's (k_in).
    pub two_sided: bool,
    /// Rounds of the alternating fit at most (it stops once no factor moves by 1e-7; a round
    /// costs 2 · nodes² · channels multiply-adds, 0.4 M for the default).
    pub rounds: usize,
}

impl Default for CalibrationOptions {
    /// 257 nodes (0.32–0.45° apart), 64 azimuths, 6 nodes per segment (about 4 000
    /// evaluations per albedo: table and source share every node, so their ratio is far more
    /// accurate than either), both sides, at most 2000 rounds (the balance converges linearly,
    /// slowly where the table's bias differs between the two sides).
    fn default() -> Self {
        CalibrationOptions {
            nodes: 257,
            nphi: 64,
            order: 6,
            horizon_margin: 0.1f64.to_radians(),
            two_sided: true,
            rounds: 2000,
        }
    }
}

impl CalibrationOptions {
    /// The end of the axis, √(1 − cos θ_end) with θ_end = 90° − the horizon margin.
    pub fn t_end(&self) -> f32 {
        Calibration::t_end_of(std::f64::consts::FRAC_PI_2 - self.horizon_margin.max(0.0))
    }
}

/// The source's directional albedos (the light's and, when two-sided, the viewer's) at the
/// nodes of a calibration axis, computed once and used to calibrate any number of tables of that
/// source ([`calibrate`]; the error-target search calibrates every candidate grid).
#[derive(Debug, Clone, PartialEq)]
pub struct AlbedoReference {
    opts: CalibrationOptions,
    channels: usize,
    /// The light's albedo, nodes × channels.
    albedo_in: Vec<f64>,
    /// The viewer's albedo (two-sided options only).
    albedo_out: Vec<f64>,
}

impl AlbedoReference {
    /// The albedos of `reference` at the nodes of `opts`.
    pub fn new(reference: &dyn Brdf, opts: &CalibrationOptions) -> Result<AlbedoReference> {
        Self::new_with(reference, opts, &Silent)
    }

    /// [`new`](Self::new), asking `progress` to stop between nodes
    /// ([`Progress::cancelled`]: [`Error::Cancelled`]).
    pub fn new_with(
        reference: &dyn Brdf,
        opts: &CalibrationOptions,
        progress: &dyn Progress,
    ) -> Result<AlbedoReference> {
        let c = reference.channels().len();
        if c == 0 || c > MAX_CHANNELS {
            return Err(Error::arg(
                "calibration",
                format!("{c} channels (1 to {MAX_CHANNELS})"),
            ));
        }
        if opts.nodes < 2 {
            return Err(Error::arg("calibration", "needs at least two nodes"));
        }
        Ok(AlbedoReference {
            albedo_in: node_albedos(reference, opts, progress)?,
            albedo_out: if opts.two_sided {
                node_albedos(&Reversed(reference), opts, progress)?
            } else {
                Vec::new()
            },
            channels: c,
            opts: opts.clone(),
        })
    }

    /// The albedo a factor k(θ) of both directions is fitted to (a reciprocal table's): the
    /// mean of the light's and the viewer's, equal for a reciprocal source up to quadrature.
    fn mean_albedo(&self) -> Vec<f64> {
        if self.albedo_out.len() != self.albedo_in.len() {
            return self.albedo_in.clone();
        }
        (self.albedo_in.iter().zip(&self.albedo_out))
            .map(|(a, b)| 0.5 * (a + b))
            .collect()
    }
}

/// Azimuths of the light over which an anisotropic BRDF's albedos are averaged: a factor of
/// θ alone cannot follow an albedo that varies with the light's azimuth, so it pins the mean
/// over the azimuths (taken at φ′ = 0 alone, the factors fitted that one azimuth and moved every
/// other: an anisotropic RGL file's table, 3.8 % dark at θ′ = 85°, φ′ = 90°, where the
/// uncalibrated table was 0.7 % bright). Equally spaced, the rule is exact for the azimuthal
/// harmonics below this order (the cos 2φ′ of an elliptical lobe).
pub const ANISOTROPIC_AZIMUTHS: usize = 8;

/// The azimuths at which `brdf`'s albedos are taken: 0 alone for an isotropic BRDF, else
/// [`ANISOTROPIC_AZIMUTHS`] equally spaced.
fn azimuths(brdf: &dyn Brdf) -> Vec<f64> {
    light_azimuths(if brdf.flags().isotropic {
        1
    } else {
        ANISOTROPIC_AZIMUTHS
    })
}

/// Per node of `opts`, the albedo of `brdf` per channel (nodes × channels), the mean over
/// [`azimuths`]. Asks `progress` to stop before each node.
fn node_albedos(
    brdf: &dyn Brdf,
    opts: &CalibrationOptions,
    progress: &dyn Progress,
) -> Result<Vec<f64>> {
    let c = brdf.channels().len();
    let t_end = opts.t_end() as f64;
    let turns = azimuths(brdf);
    let rows: Vec<Vec<f64>> = crate::par::install(|| {
        (0..opts.nodes)
            .into_par_iter()
            .map(|i| {
                crate::progress::check(progress)?;
                let theta = Calibration::node_theta(i, opts.nodes, t_end);
                let mut row = vec![0.0f64; c];
                for &phi in &turns {
                    let a = mirror_albedo(&Turned(brdf, phi), theta, opts.nphi, opts.order);
                    for (r, a) in row.iter_mut().zip(a) {
                        *r += a / turns.len() as f64;
                    }
                }
                Ok(row)
            })
            .collect::<Result<_>>()
    })?;
    Ok(rows.into_iter().flatten().collect())
}

/// The transport of `brdf` from each node's direction onto the axis: `m[(i·nodes + j)·c + k]`
/// = ∫ f_r cos θo · hat_j(t_o) dωo for wi at node i, where hat_j is node j's linear
/// interpolation weight (what a factor on node j multiplies). Summed over j it is node i's
/// albedo; with k_out applied, node i's albedo is `Σ_j m[i][j] k_out[j]`. The mean over
/// [`azimuths`], as the reference's albedos. Asks `progress` to stop before each node.
fn transport(
    brdf: &dyn Brdf,
    opts: &CalibrationOptions,
    progress: &dyn Progress,
) -> Result<Vec<f64>> {
    let c = brdf.channels().len();
    let n = opts.nodes;
    let t_end = opts.t_end() as f64;
    let (gx, gw) = gauss_legendre(opts.order.max(1));
    let (scale, last) = ((n - 1) as f64 / t_end, (n - 1) as f64);
    let turns = azimuths(brdf);
    let share = 1.0 / turns.len() as f64;
    let rows: Vec<Vec<f64>> = crate::par::install(|| {
        (0..n)
            .into_par_iter()
            .map(|i| {
                crate::progress::check(progress)?;
                let theta = Calibration::node_theta(i, n, t_end);
                let mut row = vec![0.0f64; n * c];
                let mut f = [0f32; MAX_CHANNELS];
                for &phi in &turns {
                    let turned = Turned(brdf, phi);
                    mirror_rule(theta, opts.nphi.max(1), &gx, &gw, None, |wi, wo, w| {
                        turned.eval(wi, wo, &mut f[..c]);
                        let s = ((1.0 - wo.z).max(0.0).sqrt() * scale).min(last);
                        let j = (s as usize).min(n - 2);
                        let t = s - j as f64;
                        let w = share * w * wo.z;
                        for k in 0..c {
                            let v = w * f[k] as f64;
                            row[j * c + k] += (1.0 - t) * v;
                            row[(j + 1) * c + k] += t * v;
                        }
                    });
                }
                Ok(row)
            })
            .collect::<Result<_>>()
    })?;
    Ok(rows.into_iter().flatten().collect())
}

/// The range [`calibrate`] keeps each factor in: a correction beyond a factor of 2 is not a bias
/// of the table but a place where the source has no data the table can follow (a MERL file's
/// unmeasured cells near the horizon read as 0), and is left at the limit.
pub const FIT_LIMIT: f32 = 2.0;

/// One half step of the alternating fit: `k[i] = reference[i] / Σ_j m[i][j] other[j]` per
/// channel (kept where either side is 0), within [1/[`FIT_LIMIT`], [`FIT_LIMIT`]]; returns the
/// largest relative change.
fn balance(k: &mut [f32], m: &[f64], other: &[f32], reference: &[f64], c: usize) -> f64 {
    let n = k.len() / c;
    let mut most = 0.0f64;
    for i in 0..n {
        for ch in 0..c {
            let own: f64 = (0..n)
                .map(|j| m[(i * n + j) * c + ch] * other[j * c + ch] as f64)
                .sum();
            let r = reference[i * c + ch];
            if own > 0.0 && r > 0.0 {
                let new = ((r / own) as f32).clamp(1.0 / FIT_LIMIT, FIT_LIMIT);
                let old = &mut k[i * c + ch];
                most = most.max(((new / *old) as f64 - 1.0).abs());
                *old = new;
            }
        }
    }
    most
}

/// One round of the symmetric fit: with the sums `Σ_j m[i][j] k[j]` of the current `k`,
/// `k[i] ← √(k[i] · reference[i] / Σ_j m[i][j] k[j])` per channel (kept where either side is 0),
/// within [1/[`FIT_LIMIT`], [`FIT_LIMIT`]]; returns the largest relative change. Its fixed
/// point is `k[i] Σ_j m[i][j] k[j] = reference[i]`: the albedo of a table multiplied by
/// k(θi) k(θo).
fn balance_symmetric(k: &mut [f32], m: &[f64], reference: &[f64], c: usize) -> f64 {
    let n = k.len() / c;
    let last = k.to_vec();
    let mut most = 0.0f64;
    for i in 0..n {
        for ch in 0..c {
            let own: f64 = (0..n)
                .map(|j| m[(i * n + j) * c + ch] * last[j * c + ch] as f64)
                .sum::<f64>()
                * last[i * c + ch] as f64;
            let r = reference[i * c + ch];
            if own > 0.0 && r > 0.0 {
                let old = last[i * c + ch];
                let new =
                    ((old as f64 * (r / own).sqrt()) as f32).clamp(1.0 / FIT_LIMIT, FIT_LIMIT);
                most = most.max(((new / old) as f64 - 1.0).abs());
                k[i * c + ch] = new;
            }
        }
    }
    most
}

/// `table` with a [`Calibration`] that pins its directional albedos to those of `reference` at
/// every node (module docs). The table is integrated once each way into a transport matrix
/// (what a factor on each node does to each node's albedo), and the factors are
/// fitted on it by alternating k_in and k_out until neither moves by 1e-7 (at most
/// [`CalibrationOptions::rounds`] rounds) — no further lookups. A table folded by reciprocity
/// gets one symmetric factor k_in = k_out (fitted to the mean of the reference's two
/// albedos), so it stays reciprocal. A channel whose albedo is 0
/// in either keeps the factor 1 there; factors stay within [1/[`FIT_LIMIT`], [`FIT_LIMIT`]].
/// Any calibration the table had is replaced.
pub fn calibrate(table: Table, reference: &AlbedoReference) -> Result<Table> {
    calibrate_with(table, reference, &Silent)
}

/// [`calibrate`], asking `progress` to stop between the table's nodes and between rounds of
/// the fit ([`Progress::cancelled`]: [`Error::Cancelled`]).
pub fn calibrate_with(
    table: Table,
    reference: &AlbedoReference,
    progress: &dyn Progress,
) -> Result<Table> {
    let c = table.grid().channels().len();
    if reference.channels != c {
        return Err(Error::arg(
            "calibration",
            format!(
                "the table has {c} channels, its reference {}",
                reference.channels
            ),
        ));
    }
    let opts = &reference.opts;
    let (grid, values, description) = table.into_parts();
    let grid = grid.without_calibration();
    let plain = TabulatedBrdf::from_table(Table::new(grid.clone(), values.clone(), "")?);
    let n = opts.nodes * c;
    let ones = vec![1.0f32; n];
    let mut k_in = ones.clone();
    let m_in = transport(&plain, opts, progress)?;
    let k_out = if grid.symmetry().reciprocal {
        // One factor for both directions, k(θi) k(θo), so the table stays reciprocal: the
        // symmetric scaling k ← √(k · a / (M k)) (the damped form of k = a / (M k), which
        // alone would oscillate between two scalings).
        let reference = reference.mean_albedo();
        for _ in 0..opts.rounds.max(1) {
            crate::progress::check(progress)?;
            if balance_symmetric(&mut k_in, &m_in, &reference, c) < 1e-7 {
                break;
            }
        }
        Some(k_in.clone())
    } else if opts.two_sided {
        let m_out = transport(&Reversed(&plain), opts, progress)?;
        let mut k_out = ones;
        for _ in 0..opts.rounds.max(1) {
            crate::progress::check(progress)?;
            let a = balance(&mut k_in, &m_in, &k_out, &reference.albedo_in, c);
            let b = balance(&mut k_out, &m_out, &k_in, &reference.albedo_out, c);
            if a.max(b) < 1e-7 {
                break;
            }
        }
        Some(k_out)
    } else {
        balance(&mut k_in, &m_in, &ones, &reference.albedo_in, c);
        None
    };
    let cal = Calibration::new(k_in, k_out, c, opts.t_end()).map_err(|e| {
        Error::arg(
            "calibration",
            format!("the table is too far from its reference to calibrate: {e}"),
        )
    })?;
    Table::new(grid.with_calibration(cal)?, values, description)
}
