//! The lecture's models ([`LECTURE_MODELS`]) and their plausibility table, what
//! `brdftab demo --plausibility` prints.

use super::{Options, check};

/// The lecture's models, in its order, as (label, spec).
pub const LECTURE_MODELS: &[(&str, &str)] = &[
    ("lambert kd=0.3", r#"{"model": "lambert", "kd": 0.3}"#),
    ("lambert kd=0.5", r#"{"model": "lambert", "kd": 0.5}"#),
    (
        "phong (original) n=20",
        r#"{"model": "phong", "ks": 0.5, "n": 20}"#,
    ),
    (
        "reciprocal phong n=20",
        r#"{"model": "reciprocal_phong", "ks": 0.5, "n": 20}"#,
    ),
    (
        "reciprocal phong n=1000",
        r#"{"model": "reciprocal_phong", "ks": 1, "n": 1000}"#,
    ),
    (
        "max phong n=20",
        r#"{"model": "max_phong", "ks": 0.5, "n": 20}"#,
    ),
    (
        "pumped phong X=mean",
        r#"{"model": "pumped_phong", "ks": 0.5, "n": 20, "x": "mean"}"#,
    ),
    (
        "pumped phong X=product",
        r#"{"model": "pumped_phong", "ks": 0.5, "n": 20, "x": "product"}"#,
    ),
    (
        "pumped phong X=sqrt",
        r#"{"model": "pumped_phong", "ks": 0.5, "n": 20, "x": "sqrt"}"#,
    ),
    (
        "mirror gold",
        r#"{"model": "mirror", "fresnel": {"conductor": "Au"}}"#,
    ),
    (
        "cook-torrance m=0.3 F=1",
        r#"{"model": "cook_torrance", "m": 0.3}"#,
    ),
    (
        "cook-torrance m=0.3 gold",
        r#"{"model": "cook_torrance", "m": 0.3, "fresnel": {"conductor": "Au"}}"#,
    ),
    (
        "ggx alpha=0.3 copper",
        r#"{"model": "ggx", "alpha": 0.3, "fresnel": {"conductor": "Cu"}}"#,
    ),
    (
        "blinn-phong n=100",
        r#"{"model": "blinn_phong", "ks": 0.5, "n": 100}"#,
    ),
    (
        "ward 0.1 x 0.3",
        r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
    ),
    (
        "oren-nayar sigma=0.3",
        r#"{"model": "oren_nayar", "kd": 0.3, "sigma": 0.3}"#,
    ),
];

/// The plausibility table of [`LECTURE_MODELS`] (what `brdftab demo --plausibility` prints):
/// one row per model with positivity, reciprocity (max error) and energy conservation (max
/// albedo and where), and a list of the models this build cannot make.
pub fn lecture_table() -> String {
    let mut text = format!(
        "Physical plausibility of the lecture's BRDF models (RGB; albedo at θ′ = 0..89°, 89.9°, 89.99°)\n\n{:<26} {:<9} {:<22} energy conserving (max albedo @ θ′)\n",
        "model", "positive", "reciprocal (max err)"
    );
    let mut skipped = Vec::new();
    for (label, spec) in LECTURE_MODELS {
        let brdf = match crate::spec::ModelSpec::parse(spec)
            .and_then(|s| s.build(&crate::Channels::Rgb))
        {
            Ok(b) => b,
            Err(e) => {
                skipped.push(format!("{label}: {e}"));
                continue;
            }
        };
        let r = match check(&*brdf, &Options::default()) {
            Ok(r) => r,
            Err(e) => {
                skipped.push(format!("{label}: {e}"));
                continue;
            }
        };
        let yn = |b: bool| if b { "yes" } else { "NO" };
        text += &format!(
            "{:<26} {:<9} {:<22} {} ({:.4} @ {}°)\n",
            label,
            yn(r.positive),
            format!("{} ({:.1e})", yn(r.reciprocal), r.max_reciprocity_error),
            yn(r.energy_conserving),
            r.max_albedo,
            r.max_albedo_theta_deg
        );
    }
    if !skipped.is_empty() {
        text += "\nskipped (not available in this build):\n";
        for s in skipped {
            text += &format!("  {s}\n");
        }
    }
    text
}
