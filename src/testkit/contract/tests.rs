//! Tests of the contract checker itself: each flaw planted in a test BRDF is caught by its
//! check, and Lambert passes.

use super::*;
use crate::brdf::{BrdfSample, Flags};
use crate::spectrum::Channels;
use glam::DVec2;

/// Lambert (kd = 0.3) with one flaw.
struct Flawed(&'static str);

impl Brdf for Flawed {
    fn channels(&self) -> &Channels {
        &Channels::Rgb
    }
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let ok = |v: DVec3| v.is_finite() && v.z > 0.0;
        let v = if !(ok(wi) && ok(wo)) && self.0 != "horizon" {
            0.0
        } else {
            match self.0 {
                "negative" if wi.x > 0.5 => -0.1,
                "reciprocal" => 0.3 + 0.1 * wi.z as f32,
                "isotropic" => 0.3 + 0.1 * wi.x as f32,
                _ => 0.3,
            }
        };
        out.fill(v);
    }
    fn eval_batch(&self, wi: &[DVec3], wo: &[DVec3], out: &mut [f32]) {
        for ((a, b), o) in wi.iter().zip(wo).zip(out.chunks_exact_mut(3)) {
            self.eval(*a, *b, o);
            if self.0 == "batch" {
                o[0] *= 1.001;
            }
        }
    }
    fn flags(&self) -> Flags {
        Flags::SMOOTH_SYMMETRIC
    }
    fn describe(&self) -> String {
        self.0.into()
    }
    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let p = match (geometry::unit(wi), geometry::unit(wo)) {
            (Some(i), Some(o)) if i.z > 0.0 && o.z > 0.0 => i.z / std::f64::consts::PI,
            _ => 0.0,
        };
        if self.0 == "pdf" { p * 1.01 } else { p }
    }
    fn sample(&self, wo: DVec3, u: DVec2, w: &mut [f32]) -> Option<BrdfSample> {
        let o = geometry::unit(wo)?;
        // "square": draws from any finite u, as the Phong family once did.
        let drawable = match self.0 {
            "square" => u.is_finite(),
            _ => geometry::in_unit_square(u),
        };
        if o.z <= 0.0 || !drawable {
            return None;
        }
        let wi = geometry::cosine_hemisphere(u);
        let pdf = wi.z / std::f64::consts::PI;
        let k = if self.0 == "weight" { 1.1 } else { 1.0 };
        w.fill((0.3 * std::f64::consts::PI * k) as f32);
        Some(BrdfSample {
            wi,
            pdf,
            delta: false,
        })
    }
}

#[test]
fn each_flaw_is_caught_by_its_check_and_lambert_passes() {
    let quick = Contract {
        pairs: 300,
        samples: 50,
        ..Contract::default()
    };
    assert_eq!(check_contract(&Flawed("none"), &quick), Ok(()));
    for flaw in [
        "negative",
        "reciprocal",
        "isotropic",
        "batch",
        "horizon",
        "pdf",
        "weight",
        "square",
    ] {
        let v = check_contract(&Flawed(flaw), &quick).expect_err(flaw);
        let check = match flaw {
            "negative" => "positive",
            "batch" => "eval_batch",
            "square" => "horizon",
            f => f,
        };
        assert!(v.iter().any(|m| m.starts_with(check)), "{flaw}: {v:?}");
    }
}
