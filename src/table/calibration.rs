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
//! A [`Calibration`] is a per-channel factor k(θi) on a fine axis of incidence angles: the table's
//! value is multiplied by it, so that at every node of that axis the table's albedo equals the
//! source's (computed on one quadrature for both, [`calibrate`]). Linear interpolation between
//! nodes 0.2–0.45° apart follows a kink to a fraction of a percent. The factor depends on wi only,
//! so it leaves the shape of every lobe alone and costs a square root and a blend per lookup; it
//! is not reciprocal, which is why only tables that cannot fold by reciprocity anyway (the
//! projected quantities of measured sources, [`super::Quantity::FrCosOut`]) carry one.
//!
//! The axis is uniform in t = √(1 − cos θi) = √2 sin(θi/2): nearly uniform in θi (node spacing
//! 0.32° at the normal, 0.45° at the horizon for 257 nodes) and computed from cos θi with one
//! square root — no `acos` in the lookup.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::analysis::fidelity::mirror_albedo;
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::spectrum::MAX_CHANNELS;
use crate::table::{Table, TabulatedBrdf};

/// The largest factor a calibration may hold, and the inverse of the smallest: a table whose
/// albedo is off by more than this is broken, not biased.
pub const MAX_FACTOR: f32 = 4.0;

/// Per-channel albedo factors k(θi) over a uniform axis in t = √(1 − cos θi) (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CalibrationRepr", into = "CalibrationRepr")]
pub struct Calibration {
    /// Nodes × channels, channels innermost; node i at t = i/(nodes − 1).
    factors: Box<[f32]>,
    channels: usize,
    /// nodes − 1, as f32 (the lookup's scale).
    scale: f32,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CalibrationRepr {
    /// Values per node.
    channels: usize,
    /// Nodes × channels, channels innermost.
    factors: Vec<f32>,
}

impl TryFrom<CalibrationRepr> for Calibration {
    type Error = Error;
    fn try_from(r: CalibrationRepr) -> Result<Calibration> {
        Calibration::new(r.factors, r.channels)
    }
}

impl From<Calibration> for CalibrationRepr {
    fn from(c: Calibration) -> CalibrationRepr {
        CalibrationRepr {
            channels: c.channels,
            factors: c.factors.into_vec(),
        }
    }
}

impl Calibration {
    /// A calibration from `factors` (nodes × `channels`, channels innermost). Checked: at least
    /// two nodes, a whole number of them, every factor finite within [1/[`MAX_FACTOR`],
    /// [`MAX_FACTOR`]].
    pub fn new(factors: Vec<f32>, channels: usize) -> Result<Calibration> {
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
        if let Some(x) = factors
            .iter()
            .find(|x| !(x.is_finite() && **x >= 1.0 / MAX_FACTOR && **x <= MAX_FACTOR))
        {
            return Err(Error::arg(
                "calibration",
                format!("factor {x} is outside [1/{MAX_FACTOR}, {MAX_FACTOR}]"),
            ));
        }
        Ok(Calibration {
            factors: factors.into(),
            channels,
            scale: (nodes - 1) as f32,
        })
    }

    /// Number of nodes of the θi axis.
    pub fn nodes(&self) -> usize {
        self.factors.len() / self.channels
    }

    /// Values per node.
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// The factors of node `i` (one per channel).
    pub fn node_factors(&self, i: usize) -> &[f32] {
        &self.factors[i * self.channels..(i + 1) * self.channels]
    }

    /// The incidence angle of node `i` of `nodes` (radians): cos θ = 1 − t², t = i/(nodes − 1).
    pub fn node_theta(i: usize, nodes: usize) -> f64 {
        let t = i as f64 / (nodes.max(2) - 1) as f64;
        (1.0 - t * t).clamp(-1.0, 1.0).acos()
    }

    /// The smallest and largest factor.
    pub fn range(&self) -> (f32, f32) {
        self.factors
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            })
    }

    /// Multiplies `out[..channels]` by k(θi) for a unit wi with z = `cos_i` (clamped to the
    /// axis). The plain form of the lookup: t = √(1 − cos θi), s = t·(nodes − 1), linear
    /// between the nodes ⌊s⌋ and ⌊s⌋ + 1.
    #[inline(always)]
    pub fn apply(&self, cos_i: f32, out: &mut [f32]) {
        let t = (1.0 - cos_i).max(0.0).sqrt();
        let s = (t * self.scale).min(self.scale);
        // s ≥ 0 (NaN becomes 0 in the cast); the last cell ends at node `scale`.
        let j = (s as usize).min(self.factors.len() / self.channels - 2);
        let f = s - j as f32;
        let c = self.channels;
        let (a, b) = (&self.factors[j * c..], &self.factors[(j + 1) * c..]);
        for (k, x) in out.iter_mut().take(c).enumerate() {
            *x *= a[k] + f * (b[k] - a[k]);
        }
    }
}

/// How [`calibrate`] integrates.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationOptions {
    /// Nodes of the θi axis.
    pub nodes: usize,
    /// Azimuths of the albedo rule ([`mirror_albedo`]).
    pub nphi: usize,
    /// Gauss-Legendre nodes per segment of the albedo rule.
    pub order: usize,
    /// The last node's albedo is taken this far above the horizon (radians): at θi = 90° the
    /// incident direction lies in the surface, where measured data have no value.
    pub horizon_margin: f64,
}

impl Default for CalibrationOptions {
    /// 257 nodes (0.32–0.45° apart), 64 azimuths, 6 nodes per segment: the two albedos share
    /// every node, so their ratio is far more accurate than either (about 4 000 evaluations of
    /// each per node).
    fn default() -> Self {
        CalibrationOptions {
            nodes: 257,
            nphi: 64,
            order: 6,
            horizon_margin: 0.1f64.to_radians(),
        }
    }
}

/// The source's directional albedo at the nodes of a calibration axis, computed once and used
/// to calibrate any number of tables of that source ([`calibrate`]; the error-target search
/// calibrates every candidate grid).
#[derive(Debug, Clone, PartialEq)]
pub struct AlbedoReference {
    opts: CalibrationOptions,
    channels: usize,
    /// Nodes × channels.
    albedo: Vec<f64>,
}

impl AlbedoReference {
    /// The albedo of `reference` at the nodes of `opts`.
    pub fn new(reference: &dyn Brdf, opts: &CalibrationOptions) -> Result<AlbedoReference> {
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
            albedo: node_albedos(reference, opts),
            channels: c,
            opts: opts.clone(),
        })
    }
}

/// Per node of `opts`, the albedo of `brdf` per channel (nodes × channels).
fn node_albedos(brdf: &dyn Brdf, opts: &CalibrationOptions) -> Vec<f64> {
    let c = brdf.channels().len();
    let max_theta = std::f64::consts::FRAC_PI_2 - opts.horizon_margin;
    let rows: Vec<Vec<f64>> = crate::par::install(|| {
        (0..opts.nodes)
            .into_par_iter()
            .map(|i| {
                let theta = Calibration::node_theta(i, opts.nodes).min(max_theta);
                mirror_albedo(brdf, theta, opts.nphi, opts.order)[..c].to_vec()
            })
            .collect()
    });
    rows.into_iter().flatten().collect()
}

/// `table` with a [`Calibration`] that pins its directional albedo to the albedo of
/// `reference` at every node (module docs). A channel whose albedo is 0 in either keeps the
/// factor 1 there; a ratio outside [1/[`MAX_FACTOR`], [`MAX_FACTOR`]] is an error (the table
/// does not approximate its reference). Any calibration the table had is replaced.
pub fn calibrate(table: Table, reference: &AlbedoReference) -> Result<Table> {
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
    let (grid, values, description) = table.into_parts();
    let grid = grid.without_calibration();
    let plain = TabulatedBrdf::from_table(Table::new(grid.clone(), values.clone(), "")?);
    let own = node_albedos(&plain, &reference.opts);
    let factors: Vec<f32> = own
        .iter()
        .zip(&reference.albedo)
        .map(|(&a, &r)| {
            if a > 0.0 && r > 0.0 {
                (r / a) as f32
            } else {
                1.0
            }
        })
        .collect();
    let cal = Calibration::new(factors, c).map_err(|e| {
        Error::arg(
            "calibration",
            format!("the table is too far from its reference to calibrate: {e}"),
        )
    })?;
    Table::new(grid.with_calibration(cal)?, values, description)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_lookup_interpolates_linearly_in_t_and_clamps() {
        // Two channels, three nodes at t = 0, ½, 1 (θ = 0°, 41.4°, 90°).
        let c = Calibration::new(vec![1.0, 2.0, 1.5, 1.0, 0.5, 3.0], 2).unwrap();
        assert_eq!(c.nodes(), 3);
        let at = |cos_i: f32| {
            let mut v = [1.0f32, 1.0];
            c.apply(cos_i, &mut v);
            v
        };
        assert_eq!(at(1.0), [1.0, 2.0]);
        assert_eq!(at(0.75), [1.5, 1.0]); // t = ½
        assert_eq!(at(0.0), [0.5, 3.0]);
        // Beyond the axis: clamped (below the horizon, NaN).
        assert_eq!(at(-0.5), [0.5, 3.0]);
        assert_eq!(at(f32::NAN), [1.0, 2.0]);
        // t = ¼: halfway between nodes 0 and 1.
        let v = at(1.0 - 0.0625);
        assert!(
            (v[0] - 1.25).abs() < 1e-6 && (v[1] - 1.5).abs() < 1e-6,
            "{v:?}"
        );
        assert!((Calibration::node_theta(1, 3).to_degrees() - 41.409622).abs() < 1e-5);
    }

    #[test]
    fn malformed_calibrations_are_refused() {
        for (f, c) in [
            (vec![1.0, 1.0, 1.0], 2),
            (vec![1.0], 1),
            (vec![1.0, f32::NAN], 1),
            (vec![1.0, 5.0], 1),
            (vec![1.0, 0.2], 1),
            (vec![1.0, 1.0], 0),
        ] {
            assert!(Calibration::new(f.clone(), c).is_err(), "{f:?} {c}");
        }
        // Through the serialized form too.
        let e = serde_json::from_str::<Calibration>(r#"{"channels": 1, "factors": [1.0, -1.0]}"#);
        assert!(e.is_err());
        let ok: Calibration =
            serde_json::from_str(r#"{"channels": 1, "factors": [1.0, 1.5]}"#).unwrap();
        assert_eq!(ok.range(), (1.0, 1.5));
    }
}
