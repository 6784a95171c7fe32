//! The smallest adaptive grid that meets an error target (`brdftab bake --target-error E`).
//!
//! How many nodes a measured material needs depends on the material: a matte paint is within
//! 0.2 % of its measurement on 64 θh nodes, a near-mirror film's 0.4°-wide peak needs 128 or
//! more. [`search`] fits the warps once (they do not depend on the node counts), then bakes
//! the grids of a [`LADDER`] of node counts in memory (calibrating each as the final table will
//! be, [`crate::table::calibration`]) and measures each against the source with the fidelity
//! metric — relative RMSE of f_r cos θi cos θo, both directions within 80°, and in the grazing
//! band beyond — and keeps the smallest that meets the target.
//!
//! The metric is measured on a deterministic product rule centred on the mirror direction
//! ([`PairRule`]), not on random pairs: for peaky materials a random estimate is heavy tailed
//! (a single pair on a peak's flank can carry most of a 100 000-pair figure; `cg_sunflower`'s
//! grazing band ranged from 1.0 % to 5.4 % over six seeds), while the rule's figure moves by
//! less than 0.3 points when its nodes are multiplied by 20. The source is evaluated on the
//! rule once; each candidate costs its bake and its lookups.

use crate::analysis::pair_rule::{PairRule, PairRuleOptions, RuleError};
use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::progress::{Progress, Stage};
use crate::table::adaptive::{self, AdaptiveOptions};
use crate::table::calibration::{AlbedoReference, calibrate_with};
use crate::table::symmetry::Symmetry;
use crate::table::{BakeOptions, Grid, TabulatedBrdf, bake};

/// Node counts (θh, θd, stored φd) the search tries, smallest first (45 k to 1.6 M RGB
/// values). θd and φd grow faster than θh: on the RGL films the error falls faster per node
/// in θd and φd (BENCHMARKS.md, "Measured materials"): 80 × 48 × 25 matches the error of
/// 128 × 48 × 25 with 62 % of its values.
pub const LADDER: [[usize; 3]; 8] = [
    [48, 24, 13],
    [64, 32, 17],
    [64, 40, 21],
    [80, 48, 25],
    [96, 56, 29],
    [112, 64, 33],
    [128, 72, 37],
    [160, 80, 41],
];

/// Where the search starts (the middle of the ladder): it goes down from there while the
/// target holds, or up until it does.
const START: usize = 4;

/// How [`search`] measures a candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetOptions {
    /// The error target (relative RMSE, e.g. 0.008 for 0.8 %) within [`TargetOptions::cap_deg`].
    pub target: f64,
    /// When set, the grazing band (a direction beyond the cap) is judged too, against this
    /// multiple of the target: a table meets the target when its error within the cap is at most
    /// `target` and its error in the band at most `grazing_factor · target`. Every bake judges
    /// it so (3: the fidelity bars are 1 % within 80° and 3 % in the band) except one of a
    /// measurement's own f_r, which grows like 1/cos θ at the horizon (its grid stops short of
    /// it).
    pub grazing_factor: Option<f64>,
    /// Directions beyond this angle from the normal do not count in the cap (degrees).
    pub cap_deg: f64,
    /// The product rule the errors are measured on ([`PairRule`]).
    pub rule: PairRuleOptions,
}

impl TargetOptions {
    /// Within 80° only, on the default rule.
    pub fn new(target: f64) -> TargetOptions {
        TargetOptions {
            target,
            grazing_factor: None,
            cap_deg: 80.0,
            rule: PairRuleOptions::default(),
        }
    }

    /// The same, judging the grazing band against `factor` × the target too.
    pub fn with_grazing(mut self, factor: f64) -> TargetOptions {
        self.grazing_factor = Some(factor);
        self
    }

    /// The score of a candidate's errors: at most 1 when it meets the target.
    fn score(&self, e: &RuleError) -> f64 {
        let cap = e.cap / self.target;
        match self.grazing_factor {
            Some(f) => cap.max(e.grazing / (f * self.target)),
            None => cap,
        }
    }
}

/// What [`search`] found.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TargetSearch {
    /// The target.
    pub target: f64,
    /// The grazing band's target, when it was judged.
    pub grazing_target: Option<f64>,
    /// The chosen node counts (θh, θd, stored φd).
    pub nodes: [usize; 3],
    /// The chosen grid's error within the cap.
    pub error: f64,
    /// The chosen grid's error in the grazing band.
    pub grazing: f64,
    /// Whether it meets the target (otherwise it is the largest grid of the ladder).
    pub met: bool,
    /// Every candidate measured: node counts, error within the cap and in the band, in the
    /// order tried.
    pub tried: Vec<([usize; 3], f64, f64)>,
    /// Pairs of the product rule the errors were measured on.
    pub pairs: usize,
}

impl TargetSearch {
    /// One line for a bake's report.
    pub fn summary(&self) -> String {
        let [h, d, p] = self.nodes;
        let tried: Vec<String> = self
            .tried
            .iter()
            .map(|([h, d, p], e, _)| format!("{h}x{d}x{p} {:.2}%", e * 100.0))
            .collect();
        let band = match self.grazing_target {
            Some(g) => format!(
                " and {:.2}% in the grazing band ({:.2}% there)",
                g * 100.0,
                self.grazing * 100.0
            ),
            None => String::new(),
        };
        format!(
            "target error {:.2}%{band}: {} {h}x{d}x{p} nodes ({:.2}% on a rule of {} pairs; tried {})",
            self.target * 100.0,
            if self.met {
                "met by"
            } else {
                "NOT met; largest grid"
            },
            self.error * 100.0,
            self.pairs,
            tried.join(", ")
        )
    }
}

/// The smallest grid of [`LADDER`] whose table meets `opts` against `src` (see the module
/// docs), with what was measured. `symmetry` must be isotropic and bilateral; `force` bakes
/// without verifying it (an assumed symmetry). With `albedo`, every candidate is calibrated to
/// it ([`calibrate_with`]) before it is judged, as the final table will be. When no grid meets the
/// target, the largest is returned with `met: false`. Reports a stage `"searching grid"` on
/// `progress` (of unknown length), noting each grid as it is tried.
pub fn search(
    src: &dyn Brdf,
    symmetry: Symmetry,
    adaptive_opts: &AdaptiveOptions,
    opts: &TargetOptions,
    albedo: Option<&AlbedoReference>,
    force: bool,
    progress: &dyn Progress,
) -> Result<(Grid, TargetSearch)> {
    if !(opts.target > 0.0 && opts.target.is_finite()) {
        return Err(Error::arg(
            "target_error",
            format!("{} is not a positive error", opts.target),
        ));
    }
    if opts
        .grazing_factor
        .is_some_and(|f| !(f > 0.0 && f.is_finite()))
    {
        return Err(Error::arg("grazing_factor", "needs a positive factor"));
    }
    let _stage = Stage::begin(progress, "searching grid", 0);
    progress.note("fitting warps");
    let warps = adaptive::fit_warps_with(src, adaptive::phi_hi(symmetry), adaptive_opts, progress)?;
    progress.note("evaluating the source on the rule");
    let rule = PairRule::new_with(src, opts.cap_deg.to_radians(), &opts.rule, progress)?;
    let grid_of = |nodes| {
        adaptive::grid_with_warps(src.channels().clone(), symmetry, nodes, warps.clone())
            .and_then(|g| g.with_quantity(adaptive_opts.quantity))
    };
    let cancel = || progress.cancelled();
    let bake_opts = BakeOptions {
        force,
        cancel: Some(&cancel),
        ..BakeOptions::default()
    };
    let mut tried = Vec::new();
    let mut score_of = |k: usize| -> Result<f64> {
        let [h, d, p] = LADDER[k];
        crate::progress::check(progress)?;
        progress.note(&format!("{h}x{d}x{p}"));
        let (mut t, _) = bake(src, &grid_of(LADDER[k])?, &bake_opts)?;
        if let Some(a) = albedo {
            t = calibrate_with(t, a, progress)?;
        }
        let e = rule.error_with(&TabulatedBrdf::from_table(t), progress)?;
        tried.push((LADDER[k], e.cap, e.grazing));
        progress.set(tried.len() as u64);
        Ok(opts.score(&e))
    };
    let start = START;
    let (chosen, met) = if score_of(start)? <= 1.0 {
        let mut k = start;
        while k > 0 && score_of(k - 1)? <= 1.0 {
            k -= 1;
        }
        (k, true)
    } else {
        let mut found = None;
        for k in start + 1..LADDER.len() {
            if score_of(k)? <= 1.0 {
                found = Some(k);
                break;
            }
        }
        match found {
            Some(k) => (k, true),
            None => (LADDER.len() - 1, false),
        }
    };
    let &(_, error, grazing) = tried
        .iter()
        .find(|t| t.0 == LADDER[chosen])
        .ok_or_else(|| Error::Unsupported("the search measured no grid".into()))?;
    let search = TargetSearch {
        target: opts.target,
        grazing_target: opts.grazing_factor.map(|f| f * opts.target),
        nodes: LADDER[chosen],
        error,
        grazing,
        met,
        tried,
        pairs: rule.len(),
    };
    Ok((grid_of(LADDER[chosen])?, search))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;
    use crate::spec::ModelSpec;
    use crate::spectrum::Channels;

    fn model(spec: &str) -> Box<dyn Brdf + Send + Sync> {
        ModelSpec::parse(spec)
            .unwrap()
            .build(&Channels::Rgb)
            .unwrap()
    }

    const SYM: Symmetry = Symmetry {
        isotropic: true,
        reciprocal: true,
        bilateral: true,
    };

    fn quick(target: f64) -> TargetOptions {
        TargetOptions {
            rule: PairRuleOptions {
                theta_segments: [8, 2],
                nphi: 32,
                ..Default::default()
            },
            ..TargetOptions::new(target)
        }
    }

    #[test]
    fn a_smooth_source_gets_the_smallest_grid_and_a_sharp_one_a_larger_one() {
        let fine = AdaptiveOptions {
            fine: [96, 48, 32],
            ..Default::default()
        };
        // Oren-Nayar is smooth: the smallest grid of the ladder meets 1 %.
        let on = model(r#"{"model": "oren_nayar", "sigma": 0.3, "kd": 0.5}"#);
        let (g, s) = search(on.as_ref(), SYM, &fine, &quick(0.01), None, false, &Silent).unwrap();
        assert!(s.met && s.nodes == LADDER[0], "{}", s.summary());
        assert_eq!(g.stored_shape()[0], LADDER[0][0]);
        // The measured errors decide: every candidate tried below the chosen one failed, the
        // chosen one passed (or is the largest).
        let ggx = model(r#"{"model": "ggx", "alpha": 0.03}"#);
        let (_, s) = search(
            ggx.as_ref(),
            SYM,
            &fine,
            &quick(0.004),
            None,
            false,
            &Silent,
        )
        .unwrap();
        let k = LADDER.iter().position(|&n| n == s.nodes).unwrap();
        assert!(k > 0, "{}", s.summary());
        for (n, e, _) in &s.tried {
            let j = LADDER.iter().position(|x| x == n).unwrap();
            if j < k {
                assert!(*e > 0.004, "{}", s.summary());
            }
            if j == k {
                assert!(*e <= 0.004 || !s.met, "{}", s.summary());
            }
        }
        assert!(s.summary().contains("target error 0.40%"));
    }

    #[test]
    fn an_unreachable_target_returns_the_largest_grid_unmet() {
        let ggx = model(r#"{"model": "ggx", "alpha": 0.02}"#);
        let fine = AdaptiveOptions {
            fine: [64, 32, 16],
            ..Default::default()
        };
        let o = quick(1e-7);
        let (g, s) = search(ggx.as_ref(), SYM, &fine, &o, None, false, &Silent).unwrap();
        assert!(!s.met && s.nodes == LADDER[LADDER.len() - 1]);
        assert_eq!(g.stored_shape()[0], LADDER[LADDER.len() - 1][0]);
        assert!(s.summary().contains("NOT met"));
        assert!(
            search(
                ggx.as_ref(),
                SYM,
                &fine,
                &TargetOptions::new(0.0),
                None,
                false,
                &Silent
            )
            .is_err()
        );
    }
}
