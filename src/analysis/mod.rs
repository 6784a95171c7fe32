//! Analysis of any `&dyn Brdf`: albedo, physical plausibility, accuracy metrics.

pub mod accuracy;
pub mod albedo;
pub mod chi2;
pub mod fidelity;
pub mod mirror_pairs;
pub mod pair_rule;
pub mod plausibility;
pub mod timing;
pub mod weights;
