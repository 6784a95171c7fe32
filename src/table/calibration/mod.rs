//! Albedo calibration: a measured table's directional albedo pinned to its source's.
//!
//! A table interpolates its source between nodes in half/difference coordinates, and the
//! directional albedo a(θ′) = ∫ f_r cos θo dωo — what a renderer's diffuse lighting sees — carries
//! the interpolation's bias. For smooth sources that bias is a fraction of a percent; measured
//! data are not smooth in θ′: the RGL reader interpolates linearly between its eight measured
//! incidence slices, so its albedo has a kink at every slice (`cc_iris_purple_gem`, red: slope
//! 0.0014 per degree below its 30.1° slice, 0.0051 above), which no half/difference grid
//! follows — a table is 3.6 % bright there on a grid 20× finer in θ′ than the slices. Near the
//! horizon, where a direction's cell holds little of the hemisphere, a few percent of bias
//! remain too (`vch_golden_yellow` 3.9 % at 84°).
//!
//! A [`Calibration`] is a pair of per-channel factors on a fine axis of polar angles,
//! k_in(θi) · k_out(θo), that the table's value is multiplied by, so that at every node of that
//! axis the table's directional albedo equals the source's both ways: the light's
//! a(θi) = ∫ f_r cos θo dωo (the energy a light at θi deposits) and the viewer's
//! ∫ f_r cos θi dωi (what a view at θo sees in a white furnace). For a measured, non-reciprocal
//! material the two differ, and a renderer meets both. [`calibrate`] fits them by alternating
//! the two (each changes the other's integrals by the average of a factor within a percent or two
//! of 1, so three rounds settle to 1e-4), every albedo on one quadrature for table and source.
//! Linear interpolation between nodes 0.32–0.45° apart follows a kink to a fraction of a percent.
//! The factors leave the shape of every lobe alone and cost two square roots and two blends per
//! lookup. Two k's are not reciprocal: tables that cannot fold by reciprocity anyway (the
//! projected quantities of measured sources, [`super::Quantity::FrCosOut`]) carry them. A table
//! that folds by reciprocity — a model's adaptive table, whose error target judges f_r's RMSE
//! and lets the albedo of the last degrees above the horizon drift (GGX copper α = 0.1 at a
//! 0.2 % target: 1.6 % at 88°), or a model's default medium table that misses the albedo
//! (Ward's f_r cos θi cos θo, whose √cos θi edge at the horizon no grid follows: 4.8 % at
//! 89°) — gets one factor for both directions, k(θi) k(θo), fitted by the symmetric scaling
//! k ← √(k · a / (M k)); the table stays reciprocal.
//!
//! The axis is uniform in t = √(1 − cos θ) = √2 sin(θ/2): nearly uniform in θ (node spacing
//! 0.32° at the normal, 0.45° at the horizon for 257 nodes) and computed from cos θ with one
//! square root — no `acos` in the lookup.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::simd::F4;
use crate::spectrum::MAX_CHANNELS;

mod fit;
#[cfg(test)]
mod tests;

pub use fit::{
    ANISOTROPIC_AZIMUTHS, AlbedoReference, CalibrationOptions, FIT_LIMIT, calibrate, calibrate_with,
};

/// The largest factor a calibration may hold, and the inverse of the smallest: a table whose
/// albedo is off by more than this is broken, not biased.
pub const MAX_FACTOR: f32 = 4.0;

/// Per-channel albedo factors k_in(θi) · k_out(θo) over a uniform axis in t = √(1 − cos θ)
/// (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CalibrationRepr", into = "CalibrationRepr")]
pub struct Calibration {
    /// k_in: nodes × channels, channels innermost; node i at t = i/(nodes − 1).
    factors: Box<[f32]>,
    /// k_out on the same nodes (1 where absent).
    out_factors: Option<Box<[f32]>>,
    channels: usize,
    /// The axis's end t_end = √(1 − cos θ_end): node i at t = t_end · i/(nodes − 1).
    t_end: f32,
    /// (nodes − 1)/t_end, the lookup's scale from t to the fractional node.
    scale: f32,
    /// nodes − 1, as f32.
    last: f32,
    /// For three channels, per node k_in RGB, 1, k_out RGB, 1 (k_out 1 where absent): the
    /// four-lane form [`Calibration::apply_rgb`] loads.
    lanes: Option<Box<[f32]>>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CalibrationRepr {
    /// Values per node.
    channels: usize,
    /// The axis's end, √(1 − cos θ_end).
    t_end: f32,
    /// k_in: nodes × channels, channels innermost.
    factors: Vec<f32>,
    /// k_out, as `factors`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    out_factors: Option<Vec<f32>>,
}

impl TryFrom<CalibrationRepr> for Calibration {
    type Error = Error;
    fn try_from(r: CalibrationRepr) -> Result<Calibration> {
        Calibration::new(r.factors, r.out_factors, r.channels, r.t_end)
    }
}

impl From<Calibration> for CalibrationRepr {
    fn from(c: Calibration) -> CalibrationRepr {
        CalibrationRepr {
            channels: c.channels,
            t_end: c.t_end,
            factors: c.factors.into_vec(),
            out_factors: c.out_factors.map(|f| f.into_vec()),
        }
    }
}

impl Calibration {
    /// A calibration from `factors` k_in and optionally `out_factors` k_out (each nodes ×
    /// `channels`, channels innermost) on an axis ending at `t_end` = √(1 − cos θ_end).
    /// Checked: at least two nodes, a whole number of them, as many of k_out as of k_in, every
    /// factor finite within [1/[`MAX_FACTOR`], [`MAX_FACTOR`]], t_end in (0, 1].
    pub fn new(
        factors: Vec<f32>,
        out_factors: Option<Vec<f32>>,
        channels: usize,
        t_end: f32,
    ) -> Result<Calibration> {
        if !(t_end > 0.0 && t_end <= 1.0) {
            return Err(Error::arg(
                "calibration",
                format!("axis end {t_end} is not in (0, 1]"),
            ));
        }
        if channels == 0 || channels > MAX_CHANNELS || !factors.len().is_multiple_of(channels) {
            return Err(Error::arg(
                "calibration",
                format!(
                    "{} factors are not a whole number of nodes of {channels} channels",
                    factors.len()
                ),
            ));
        }
        let nodes = factors.len() / channels;
        if nodes < 2 {
            return Err(Error::arg("calibration", "needs at least two nodes"));
        }
        if out_factors
            .as_ref()
            .is_some_and(|o| o.len() != factors.len())
        {
            return Err(Error::arg(
                "calibration",
                "as many outgoing factors as incident ones",
            ));
        }
        if let Some(x) = factors
            .iter()
            .chain(out_factors.iter().flatten())
            .find(|x| !(x.is_finite() && **x >= 1.0 / MAX_FACTOR && **x <= MAX_FACTOR))
        {
            return Err(Error::arg(
                "calibration",
                format!("factor {x} is outside [1/{MAX_FACTOR}, {MAX_FACTOR}]"),
            ));
        }
        let lanes = (channels == 3).then(|| {
            (0..nodes)
                .flat_map(|i| {
                    let kin = &factors[i * 3..i * 3 + 3];
                    let kout = out_factors
                        .as_ref()
                        .map_or([1.0; 3], |o| [o[i * 3], o[i * 3 + 1], o[i * 3 + 2]]);
                    [kin[0], kin[1], kin[2], 1.0, kout[0], kout[1], kout[2], 1.0]
                })
                .collect()
        });
        Ok(Calibration {
            factors: factors.into(),
            out_factors: out_factors.map(Into::into),
            channels,
            t_end,
            scale: (nodes - 1) as f32 / t_end,
            last: (nodes - 1) as f32,
            lanes,
        })
    }

    /// Number of nodes of the axis.
    pub fn nodes(&self) -> usize {
        self.factors.len() / self.channels
    }

    /// Values per node.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// The polar angle of node `i` of `nodes` on an axis ending at `t_end` (radians):
    /// cos θ = 1 − t², t = t_end · i/(nodes − 1).
    pub fn node_theta(i: usize, nodes: usize, t_end: f64) -> f64 {
        let t = t_end * i as f64 / (nodes.max(2) - 1) as f64;
        (1.0 - t * t).clamp(-1.0, 1.0).acos()
    }

    /// The axis end t_end = √(1 − cos θ) of an axis ending at polar angle `theta`.
    pub fn t_end_of(theta: f64) -> f32 {
        (1.0 - theta.cos()).max(0.0).sqrt() as f32
    }

    /// True when k_out is k_in: the factor k(θi) k(θo) is symmetric in the two directions,
    /// so a reciprocal table stays reciprocal ([`calibrate`] fits such factors for tables
    /// that fold by reciprocity).
    pub fn is_symmetric(&self) -> bool {
        self.out_factors.as_deref() == Some(&self.factors[..])
    }

    /// The smallest and largest factor (of either kind).
    pub fn range(&self) -> (f32, f32) {
        self.factors
            .iter()
            .chain(self.out_factors.iter().flat_map(|f| f.iter()))
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            })
    }

    /// The node and fraction of a unit direction with z = `cos`: t = √(1 − cos θ),
    /// s = t·(nodes − 1), clamped to the axis (NaN: node 0).
    #[inline(always)]
    fn cell(&self, cos: f32) -> (usize, f32) {
        let t = (1.0 - cos).max(0.0).sqrt();
        let s = (t * self.scale).min(self.last);
        // s ≥ 0 (NaN becomes 0 in the cast); the last cell ends at node `scale`.
        let j = (s as usize).min(self.factors.len() / self.channels - 2);
        (j, s - j as f32)
    }

    /// `x` (RGB in lanes 0..2) times k_in(θi) · k_out(θo) for unit directions with z =
    /// `cos_i`, `cos_o`: [`Calibration::apply`] on four lanes (both axes' t in one square
    /// root, each node's three factors in one load; the same operations lane by lane, tested
    /// equal). `x` unchanged for a calibration of other than three channels.
    #[inline(always)]
    pub fn apply_rgb(&self, cos_i: f32, cos_o: f32, x: F4) -> F4 {
        Self::times(x, self.factors_rgb(cos_i, cos_o))
    }

    /// `x` times the two factors of [`Calibration::factors_rgb`] (k_in first, then k_out), or
    /// `x` itself for `None`.
    #[inline(always)]
    pub(crate) fn times(x: F4, k: Option<(F4, F4)>) -> F4 {
        match k {
            Some((k_in, k_out)) => x * k_in * k_out,
            None => x,
        }
    }

    /// The factors k_in(θi) and k_out(θo) that [`Calibration::apply_rgb`] multiplies by (RGB in
    /// lanes 0..2), `None` without the three-channel form. A lookup asks for them before its
    /// blend: they depend only on the cosines, and computed first they run beside the blend's
    /// dependent chain instead of after it (one `eval` of a measured table 31 → 26 ns).
    #[inline(always)]
    pub(crate) fn factors_rgb(&self, cos_i: f32, cos_o: f32) -> Option<(F4, F4)> {
        let (scale, last, last_cell) = self.rgb_axis()?;
        let zero = F4::splat(0.0);
        let t = (F4::new(1.0 - cos_i, 1.0 - cos_o, 0.0, 0.0).max(zero)).sqrt();
        let s = (t * F4::splat(scale)).min(F4::splat(last));
        let (j, _) = s.trunc();
        // s ≥ 0 and not NaN (max and min above return the other operand for NaN lanes).
        let (ji, jo) = ((j[0] as u32).min(last_cell), (j[1] as u32).min(last_cell));
        let [si, so, _, _] = s.to_array();
        self.factors_rgb_cells([ji, jo], [si - ji as f32, so - jo as f32])
    }

    /// What [`Calibration::apply_rgb`] needs of the axis to find a cosine's cell — the scale
    /// from t to the fractional node, the last node (f32) and the last cell (nodes − 2) —, for
    /// lookups that find cells in lanes of their own; `None` without the three-channel form
    /// (`apply_rgb` then returns its input).
    #[inline(always)]
    pub(crate) fn rgb_axis(&self) -> Option<(f32, f32, u32)> {
        self.lanes.as_ref()?;
        Some((self.scale, self.last, (self.factors.len() / 3 - 2) as u32))
    }

    /// `x` times k_in at cell `cell[0]` with fraction `frac[0]` and k_out at `cell[1]`,
    /// `frac[1]` (cells at most the last; see [`Calibration::rgb_axis`]): the interpolation
    /// of [`Calibration::apply_rgb`].
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(crate) fn apply_rgb_cells(&self, cell: [u32; 2], frac: [f32; 2], x: F4) -> F4 {
        Self::times(x, self.factors_rgb_cells(cell, frac))
    }

    /// The factors of [`Calibration::apply_rgb_cells`] (see [`Calibration::factors_rgb`]).
    #[inline(always)]
    pub(crate) fn factors_rgb_cells(&self, cell: [u32; 2], frac: [f32; 2]) -> Option<(F4, F4)> {
        let q = self.lanes.as_ref()?;
        // Node o's four factors and node o + 1's (eight further on), one bounds check each.
        let lerp =
            |o: usize, f: F4| match q.get(o..o + 12).map(|q| (F4::load(q), F4::load(&q[8..]))) {
                Some((Some(a), Some(b))) => a + f * (b - a),
                _ => F4::splat(1.0),
            };
        let (ji, jo) = (cell[0] as usize, cell[1] as usize);
        Some((
            lerp(ji * 8, F4::splat(frac[0])),
            lerp(jo * 8 + 4, F4::splat(frac[1])),
        ))
    }

    /// [`Calibration::apply`] four channels at a time (the same operations lane by lane, tested
    /// equal): what the kernel's lookups of other than three channels call.
    #[inline(always)]
    pub(crate) fn apply_lanes(&self, cos_i: f32, cos_o: f32, out: &mut [f32]) {
        self.apply_lanes_cells(self.cells(cos_i, cos_o), out)
    }

    /// The cells (node, fraction) of both cosines that [`Calibration::apply_lanes`] reads: a
    /// lookup finds them before its blend, beside the blend's chain.
    #[inline(always)]
    pub(crate) fn cells(&self, cos_i: f32, cos_o: f32) -> [(usize, f32); 2] {
        [self.cell(cos_i), self.cell(cos_o)]
    }

    /// [`Calibration::apply_lanes`] at cells found by [`Calibration::cells`].
    #[inline(always)]
    pub(crate) fn apply_lanes_cells(
        &self,
        [(ji, fi), (jo, fo)]: [(usize, f32); 2],
        out: &mut [f32],
    ) {
        let c = self.channels;
        let n = c.min(out.len());
        let out = &mut out[..n];
        lerp_into(&self.factors, ji, c, fi, out);
        if let Some(o) = &self.out_factors {
            lerp_into(o, jo, c, fo, out);
        }
    }

    /// Multiplies `out[..channels]` by k_in(θi) · k_out(θo) for unit directions with z =
    /// `cos_i`, `cos_o`: on each, linear between the nodes ⌊s⌋ and ⌊s⌋ + 1 (the plain form of
    /// the lookup; the kernel calls it as it is).
    #[inline(always)]
    pub fn apply(&self, cos_i: f32, cos_o: f32, out: &mut [f32]) {
        let c = self.channels;
        let (j, f) = self.cell(cos_i);
        let (a, b) = (&self.factors[j * c..], &self.factors[(j + 1) * c..]);
        for (k, x) in out.iter_mut().take(c).enumerate() {
            *x *= a[k] + f * (b[k] - a[k]);
        }
        if let Some(o) = &self.out_factors {
            let (j, f) = self.cell(cos_o);
            let (a, b) = (&o[j * c..], &o[(j + 1) * c..]);
            for (k, x) in out.iter_mut().take(c).enumerate() {
                *x *= a[k] + f * (b[k] - a[k]);
            }
        }
    }
}

/// `out[k] *= a[k] + f (b[k] − a[k])` with a, b the factors of nodes `j`, `j` + 1 (`c` per
/// node): four at a time, then one at a time (the same operations in each lane).
#[inline(always)]
fn lerp_into(factors: &[f32], j: usize, c: usize, f: f32, out: &mut [f32]) {
    let (Some(a), Some(b)) = (
        factors.get(j * c..(j + 1) * c),
        factors.get((j + 1) * c..(j + 2) * c),
    ) else {
        return;
    };
    let fv = F4::splat(f);
    let mut k = 0;
    while k + 4 <= out.len() {
        if let (Some(x), Some(a4), Some(b4)) =
            (F4::load(&out[k..]), F4::load(&a[k..]), F4::load(&b[k..]))
        {
            out[k..k + 4].copy_from_slice(&(x * (a4 + fv * (b4 - a4))).to_array());
        }
        k += 4;
    }
    for k in k..out.len() {
        out[k] *= a[k] + f * (b[k] - a[k]);
    }
}
