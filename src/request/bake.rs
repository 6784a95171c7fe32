//! [`BakeSettings`]: the settings of a bake, as every host names them.

use serde::{Deserialize, Serialize};

use super::save::{SaveSettings, target};
use super::values::{ErrorTarget, Wavelengths};
use crate::bake::{BakeReport, BakeRequest, GridChoice, SymmetryChoice};
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::table::{Param, fill};

/// The settings of a bake (`brdftab bake`, `convert` to a table, `db add`; Python's `bake` and
/// `convert` keywords; the C ABI's JSON): every field optional, `None` meaning the library's
/// default. [`BakeSettings::request`] validates them and makes the [`BakeRequest`].
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct BakeSettings {
    /// Grid size preset: small, medium or large (default: a MERL file's own cells for MERL
    /// sources, for RGL files the smallest adaptive grid within the default error target,
    /// 0.7 %, medium otherwise — unless a model's medium table misses its albedo by over 1 %, then
    /// the adaptive grid of a 0.2 % target or the medium table calibrated).
    #[cfg_attr(feature = "clap", arg(long))]
    pub preset: Option<String>,
    /// Full grid sizes θ1xφ1xθ2xφ2 (e.g. 90x360x90x360), `merl`, or `adaptive[:NHxNDxNP]`
    /// (halfdiff θh, θd and stored φd nodes placed by the source's own variation; isotropic
    /// bilateral sources; default 128x48x25, or what an error target picks); overrides preset.
    #[cfg_attr(feature = "clap", arg(long))]
    pub grid: Option<String>,
    /// Parameterization: halfdiff (default) or inout.
    #[cfg_attr(feature = "clap", arg(long))]
    pub param: Option<String>,
    /// Wavelengths in nm (`400,500,600`) instead of the source's channels (model specs and RGL
    /// files).
    #[cfg_attr(feature = "clap", arg(long))]
    pub wavelengths: Option<Wavelengths>,
    /// Symmetry reduction: auto (detect; default), declared (what the source says, unverified),
    /// none, all, or a list of isotropic,reciprocal,bilateral.
    #[cfg_attr(feature = "clap", arg(long))]
    pub symmetry: Option<String>,
    /// Relative tolerance of symmetry detection and verification (default 1e-3).
    #[cfg_attr(feature = "clap", arg(long, alias = "tolerance"))]
    pub symmetry_tolerance: Option<f64>,
    /// Bake even if the source breaks the chosen symmetry beyond the tolerance.
    #[cfg_attr(feature = "clap", arg(long))]
    pub force: bool,
    /// Codec: f32 (lossless), f16 (fails above ±65504), or log16 (default; a relative error
    /// bound at any magnitude, `log16:1e-2` sets it): analytic lobes such as Cook-Torrance reach
    /// 1e5 at grazing angles, beyond f16.
    #[cfg_attr(feature = "clap", arg(long))]
    pub codec: Option<String>,
    /// log16 relative tolerance (default 1e-3).
    #[cfg_attr(feature = "clap", arg(long))]
    pub codec_tolerance: Option<f64>,
    /// log16 absolute floor (default: 1e-7 of each chunk's largest value).
    #[cfg_attr(feature = "clap", arg(long))]
    pub floor: Option<f64>,
    /// zstd level (1..=22; default 3 for f32/f16, 6 for log16).
    #[cfg_attr(feature = "clap", arg(long))]
    pub level: Option<i32>,
    /// Try every filter through zstd per chunk and keep the smallest (slower).
    #[cfg_attr(feature = "clap", arg(long))]
    pub exhaustive: bool,
    /// Table name inside the file (default: the output file's stem, or the input's for
    /// `convert`; `DB#NAME` names it itself).
    #[cfg_attr(feature = "clap", arg(long))]
    pub name: Option<String>,
    /// Samples per axis and cell, 1..=64 (box prefilter for very sharp lobes; default 1).
    #[cfg_attr(feature = "clap", arg(long))]
    pub supersample: Option<usize>,
    /// Pick the smallest adaptive grid whose table meets this error: relative RMSE of
    /// f_r cos θi cos θo, both directions within 80°, on a mirror-centred product rule (`0.5%`
    /// or `0.005`), and within 3× it in the grazing band beyond 80° (every table but one of a
    /// measurement's own f_r, which grows without bound at the horizon).
    /// Isotropic bilateral sources; not with given node counts.
    #[cfg_attr(feature = "clap", arg(long))]
    pub target_error: Option<ErrorTarget>,
    /// Pin the table's directional albedo to the source's (default true; tables of measured
    /// sources that store f_r cos θo, adaptive tables of models, and a model's default medium
    /// table where it misses the albedo by over 1 %).
    #[cfg_attr(feature = "clap", arg(long))]
    pub calibrate: Option<bool>,
    /// Replace an existing table of that name (database outputs).
    #[cfg_attr(feature = "clap", arg(long))]
    pub replace: bool,
}

impl BakeSettings {
    /// The settings of this bake that say how its table is stored (codec, name, replace):
    /// one validation of those fields for a bake and a save.
    pub fn save(&self) -> SaveSettings {
        SaveSettings {
            codec: self.codec.clone(),
            codec_tolerance: self.codec_tolerance,
            floor: self.floor,
            level: self.level,
            exhaustive: self.exhaustive,
            name: self.name.clone(),
            replace: self.replace,
        }
    }

    /// The request these settings describe for `source`; every check of a bake's settings is
    /// here or in what it calls.
    ///
    /// # Errors
    /// [`Error::InvalidArgument`] naming the field.
    pub fn request(&self, source: impl AsRef<std::ffi::OsStr>) -> Result<BakeRequest> {
        let grid = match (&self.grid, &self.preset) {
            (Some(g), _) => g.parse::<GridChoice>().map_err(|e| rename(e, "grid")),
            (None, Some(p)) => p.parse::<GridChoice>().map_err(|e| rename(e, "preset")),
            (None, None) => Ok(GridChoice::Default),
        }?;
        let mut r = BakeRequest::new(source).grid(grid);
        r.param = self.param.as_deref().map(str::parse::<Param>).transpose()?;
        if let Some(s) = &self.symmetry {
            r.symmetry = s
                .parse::<SymmetryChoice>()
                .map_err(|e| rename(e, "symmetry"))?;
        }
        if let Some(t) = self.symmetry_tolerance {
            if !(t >= 0.0 && t.is_finite()) {
                return Err(Error::arg(
                    "symmetry_tolerance",
                    format!("{t}: expected a finite tolerance ≥ 0"),
                ));
            }
            r.symmetry_tolerance = t;
        }
        r.force = self.force;
        r.codec = self.save().codec()?;
        r.name = self.name.clone();
        if let Some(k) = self.supersample {
            if !(1..=fill::MAX_SUPERSAMPLE).contains(&k) {
                return Err(Error::arg(
                    "supersample",
                    format!("{k}: must be in 1..={}", fill::MAX_SUPERSAMPLE),
                ));
            }
            r.supersample = k;
        }
        r.channels = self
            .wavelengths
            .as_ref()
            .map(|w| w.channels())
            .transpose()?;
        r.target_error = self.target_error.map(|t| t.0);
        if let Some(c) = self.calibrate {
            r.calibrate = c;
        }
        Ok(r)
    }
}

/// Bakes SOURCE into `output` as `settings` say: `DB#NAME` is a table of a database (created if
/// absent; an existing name is an error unless `replace`), any other name a single-table
/// brdftab file (`.btdb`), replaced atomically. What `brdftab bake`, Python's `bake` and the C
/// ABI's `brdftab_bake` run.
///
/// # Errors
/// Invalid settings ([`Error::InvalidArgument`] naming the field), and whatever opening the
/// source, baking and writing fail with.
pub fn bake(
    source: impl AsRef<std::ffi::OsStr>,
    output: impl AsRef<std::ffi::OsStr>,
    settings: &BakeSettings,
    progress: &dyn Progress,
) -> Result<BakeReport> {
    let req = settings.request(source)?;
    req.run_with(&target(output, settings.replace)?, progress)
}

/// The same error naming `field` (a parser names what it parses, e.g. `preset` for a grid).
fn rename(e: Error, field: &str) -> Error {
    match e {
        Error::InvalidArgument { msg, .. } => Error::arg(field, msg),
        e => e,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::BakeTarget;

    #[test]
    fn an_output_with_an_empty_or_control_character_name_is_an_output_error() {
        for out in ["x.btdb#", "x.btdb#\0", "x.btdb#a\u{1b}b"] {
            match target(out, false) {
                Err(Error::InvalidArgument { ref name, .. }) => assert_eq!(name, "output"),
                r => panic!("{out:?}: {r:?}"),
            }
        }
        assert_eq!(
            target("x.btdb#m", false).unwrap(),
            BakeTarget::db("x.btdb", "m")
        );
    }

    #[test]
    fn a_name_setting_that_contradicts_db_name_is_refused_before_any_write() {
        // `bake(src, "db.btdb#c", name="d")` wrote table `c` and dropped `d` without a word.
        let d = crate::testkit::TempDir::new("request_bake_name_conflict");
        let db = d.join("db.btdb").to_str().unwrap().to_owned();
        let spec = r#"{"model": "lambert", "kd": 0.5}"#;
        let with_name = |n: &str| BakeSettings {
            name: Some(n.into()),
            preset: Some("small".into()),
            ..Default::default()
        };
        let out = format!("{db}#c");
        let e = bake(spec, &out, &with_name("d"), &crate::progress::Silent).unwrap_err();
        match e {
            Error::InvalidArgument { ref name, ref msg } => {
                assert_eq!(name, "name");
                assert!(msg.contains("\"d\"") && msg.contains("\"c\""), "{msg}");
            }
            e => panic!("{e}"),
        }
        assert!(!d.join("db.btdb").exists(), "nothing is written");
        // The same name twice is no conflict.
        let r = bake(spec, &out, &with_name("c"), &crate::progress::Silent).unwrap();
        assert_eq!(r.name, "c");
    }

    #[test]
    fn defaults_are_the_requests_defaults_and_bad_values_name_their_field() {
        let spec = r#"{"model": "lambert", "kd": 0.5}"#;
        let d = BakeSettings::default().request(spec).unwrap();
        let n = BakeRequest::new(spec);
        assert_eq!(d.codec, n.codec);
        assert_eq!(d.grid, n.grid);
        assert_eq!(d.symmetry_tolerance, n.symmetry_tolerance);
        assert_eq!(d.supersample, n.supersample);
        assert_eq!(d.calibrate, n.calibrate);
        for (json, field) in [
            (r#"{"grid": "huge"}"#, "grid"),
            (r#"{"preset": "huge"}"#, "preset"),
            (r#"{"symmetry": "radial"}"#, "symmetry"),
            (r#"{"symmetry_tolerance": -1}"#, "symmetry_tolerance"),
            (r#"{"supersample": 0}"#, "supersample"),
            (r#"{"supersample": 65}"#, "supersample"),
            (r#"{"level": 30}"#, "level"),
            (r#"{"target_error": "-1%"}"#, "target_error"),
            (r#"{"wavelengths": [500, 400]}"#, "wavelengths"),
            (r#"{"name": ""}"#, "name"),
            (r#"{"name": "\u0000"}"#, "name"),
            (r#"{"name": "a\tb"}"#, "name"),
        ] {
            let e = super::super::from_json::<BakeSettings>(json)
                .and_then(|s| s.request(spec))
                .unwrap_err();
            match e {
                Error::InvalidArgument { ref name, .. } => assert_eq!(name, field, "{json}: {e}"),
                e => panic!("{json}: {e}"),
            }
        }
    }
}
