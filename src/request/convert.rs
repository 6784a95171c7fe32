//! [`ConvertSettings`] and [`convert`]: any SOURCE into a MERL file, an RGL `.bsdf` file or a
//! table, the output's kind chosen by its name — the one conversion every host runs.

use std::ffi::OsStr;

use serde::{Deserialize, Serialize};

use super::bake::BakeSettings;
use crate::analysis::accuracy::MAX_SAMPLES;
use crate::bake::{self, BakeReport, BakeTarget, Converted};
use crate::error::Result;
use crate::measured::rgl_write;
use crate::progress::Progress;
use crate::source::{SourceKind, classify_output};
use crate::table::Interp;

/// The settings of a conversion: a bake's (for table and MERL outputs; `wavelengths` for every
/// output) plus the accuracy report and the `.bsdf` writer's layout.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct ConvertSettings {
    /// The bake's settings.
    #[serde(flatten)]
    #[cfg_attr(feature = "clap", command(flatten))]
    pub bake: BakeSettings,
    /// Random pairs for the reported accuracy (default 200 000; 0 skips it).
    #[cfg_attr(feature = "clap", arg(long))]
    pub pairs: Option<usize>,
    /// Interpolation for the reported accuracy of a table: auto (default: the table's own, as
    /// every host opens it — nearest on a table of MERL cells, linear otherwise), nearest or
    /// linear.
    #[cfg_attr(feature = "clap", arg(long))]
    pub interp: Option<String>,
    /// .bsdf output: reflectance table resolution N (default 64, or 128 where 64 stays past the
    /// accuracy bars; a .bsdf input's own).
    #[cfg_attr(feature = "clap", arg(long))]
    pub resolution: Option<usize>,
    /// .bsdf output: number of incident elevations θi, even in cos θi (default: 16 to 32 placed
    /// where the written file is farthest from the source; 8 = the RGL database's spacing).
    #[cfg_attr(feature = "clap", arg(long))]
    pub theta_i: Option<usize>,
    /// .bsdf output: number of incident azimuths φi (default 1 if isotropic — the only count an
    /// isotropic source takes —, else placed with the elevations where the written file is
    /// farthest from the source, from 9, within 32 MiB; given: 3 or more, evenly, with 16 θi).
    #[cfg_attr(feature = "clap", arg(long))]
    pub phi_i: Option<usize>,
    /// .bsdf output: NDF, σ and VNDF grid resolution (default 128).
    #[cfg_attr(feature = "clap", arg(long))]
    pub ndf_resolution: Option<usize>,
}

/// The accuracy pairs of a conversion unless told otherwise.
pub const DEFAULT_PAIRS: usize = 200_000;

/// What [`convert`] wrote.
#[derive(Debug, Clone)]
pub enum ConvertOutput {
    /// A MERL `.binary`: the source resampled as MERL cell means
    /// ([`crate::measured::merl_resample`]).
    Merl(BakeReport),
    /// An RGL `.bsdf` file, with the error of the file read back.
    Rgl(Converted),
    /// A table (`DB#NAME`, a `.btdb` file holding one table named after the input, or a raw
    /// table), with its accuracy against the source under `interp`.
    Table {
        /// What the bake did.
        report: BakeReport,
        /// The interpolation of the accuracy report.
        interp: Interp,
    },
}

/// Converts SOURCE into `output`, whose kind its name says: a MERL `.binary`, an RGL `.bsdf`,
/// `DB#NAME`, a `.btdb` file (a table named after the input) or a raw table file.
///
/// # Errors
/// Invalid settings ([`crate::Error::InvalidArgument`] naming the field), and whatever opening
/// the source and writing the output fail with.
pub fn convert(
    source: impl AsRef<std::ffi::OsStr>,
    output: impl AsRef<std::ffi::OsStr>,
    settings: &ConvertSettings,
    progress: &dyn Progress,
) -> Result<ConvertOutput> {
    let (source, output) = (source.as_ref(), output.as_ref());
    let mut req = settings.bake.request(source)?;
    let pairs = settings.pairs.unwrap_or(DEFAULT_PAIRS);
    // Checked before the bake, not after it: the comparison's own check (per channel count)
    // would refuse a count beyond this only once the table is written.
    if pairs > MAX_SAMPLES {
        return Err(crate::Error::arg(
            "pairs",
            format!("{pairs}: at most {MAX_SAMPLES} pairs (fewer with many channels)"),
        ));
    }
    let kind = classify_output(output);
    refuse_unused(settings, kind, output)?;
    match kind {
        SourceKind::Merl => Ok(ConvertOutput::Merl(
            req.run_with(&BakeTarget::Merl(output.into()), progress)?,
        )),
        SourceKind::Rgl => {
            let opts = rgl_write::Options {
                resolution: settings.resolution,
                theta_i: settings.theta_i,
                phi_i: settings.phi_i,
                ndf_resolution: settings.ndf_resolution,
                ..Default::default()
            };
            Ok(ConvertOutput::Rgl(bake::to_rgl(
                source,
                req.channels.clone(),
                output,
                &opts,
                pairs,
                progress,
            )?))
        }
        _ => {
            req.accuracy_pairs = pairs;
            req.accuracy_interp = accuracy_interp(settings.interp.as_deref())?;
            let replace = settings.bake.replace;
            let target = match BakeTarget::parse(output, None, replace)? {
                BakeTarget::File(path) => BakeTarget::Db {
                    path,
                    name: req
                        .name
                        .clone()
                        .unwrap_or_else(|| bake::source_stem(source)),
                    replace,
                },
                t => t,
            };
            let report = req.run_with(&target, progress)?;
            let interp = req
                .accuracy_interp
                .unwrap_or_else(|| Interp::default_for(&report.grid));
            Ok(ConvertOutput::Table { report, interp })
        }
    }
}

/// The `interp` setting of a conversion's accuracy report: `None` (auto, the default) for the
/// table's own interpolation.
fn accuracy_interp(s: Option<&str>) -> Result<Option<Interp>> {
    match s.map(|s| s.trim().to_ascii_lowercase()) {
        None => Ok(None),
        Some(s) if s == "auto" => Ok(None),
        Some(s) => s.parse().map(Some).map_err(|_| {
            crate::error::Error::arg("interp", format!("`{s}`: expected auto, nearest or linear"))
        }),
    }
}

/// Refuses a setting the output's kind does not use: it was dropped without a word (a MERL
/// `.binary` asked for `wavelengths` came out RGB; a `.bsdf` asked for a codec or a preset
/// ignored it).
fn refuse_unused(settings: &ConvertSettings, kind: SourceKind, output: &OsStr) -> Result<()> {
    let b = &settings.bake;
    let table = [
        ("preset", b.preset.is_some()),
        ("grid", b.grid.is_some()),
        ("param", b.param.is_some()),
        ("symmetry", b.symmetry.is_some()),
        ("symmetry_tolerance", b.symmetry_tolerance.is_some()),
        ("force", b.force),
        ("codec", b.codec.is_some()),
        ("codec_tolerance", b.codec_tolerance.is_some()),
        ("floor", b.floor.is_some()),
        ("level", b.level.is_some()),
        ("exhaustive", b.exhaustive),
        ("name", b.name.is_some()),
        ("supersample", b.supersample.is_some()),
        ("target_error", b.target_error.is_some()),
        ("calibrate", b.calibrate.is_some()),
        ("interp", settings.interp.is_some()),
    ];
    let rgl = [
        ("resolution", settings.resolution.is_some()),
        ("theta_i", settings.theta_i.is_some()),
        ("phi_i", settings.phi_i.is_some()),
        ("ndf_resolution", settings.ndf_resolution.is_some()),
    ];
    let (what, unused): (&str, Vec<_>) = match kind {
        SourceKind::Merl => (
            "a MERL .binary file (RGB cell means on the MERL grid)",
            [("wavelengths", b.wavelengths.is_some())]
                .into_iter()
                .chain(table)
                .chain(rgl)
                .collect(),
        ),
        SourceKind::Rgl => ("an RGL .bsdf file", table.into_iter().collect()),
        SourceKind::Spec | SourceKind::Table => ("a table", rgl.into_iter().collect()),
    };
    match unused.into_iter().find(|(_, given)| *given) {
        Some((field, _)) => Err(crate::Error::arg(
            field,
            format!("does not apply to {}, {what}", output.to_string_lossy()),
        )),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;

    #[test]
    fn a_setting_the_output_does_not_use_is_refused_before_any_work() {
        let d = crate::testkit::TempDir::new("convert-unused");
        let lambert = r#"{"model":"lambert","kd":[0.1,0.2,0.3]}"#;
        let bake = |b: BakeSettings| ConvertSettings {
            bake: b,
            ..Default::default()
        };
        let wl = bake(BakeSettings {
            wavelengths: Some("450,550".parse().unwrap()),
            ..Default::default()
        });
        let codec = bake(BakeSettings {
            codec: Some("f16".into()),
            ..Default::default()
        });
        let res = ConvertSettings {
            resolution: Some(16),
            ..Default::default()
        };
        for (out, settings, field) in [
            ("a.binary", &wl, "wavelengths"),
            ("a.binary", &codec, "codec"),
            ("a.bsdf", &codec, "codec"),
            ("a.btdb", &res, "resolution"),
            ("a.binary", &res, "resolution"),
        ] {
            let path = d.join(out).to_str().unwrap().to_owned();
            match convert(lambert, &path, settings, &Silent) {
                Err(crate::Error::InvalidArgument { name, .. }) => assert_eq!(name, field, "{out}"),
                r => panic!("{out}: {:?}", r.map(|_| ())),
            }
            assert!(!d.join(out).exists(), "{out} was written");
        }
    }
}
