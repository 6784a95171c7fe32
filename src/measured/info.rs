//! What `brdftab info` says of a measured file (MERL `.binary`, RGL `.bsdf`), as text every host
//! can show ([`describe`]) and as JSON (`info --json`, Python `brdftab.info`: [`info`]):
//! description, dimensions, channels, sha256.

use std::fmt::Write as _;
use std::path::Path;

use serde_json::{Value, json};

use super::{MerlBrdf, RglBrdf, merl, tensor::TensorFile};
use crate::brdf::Brdf;
use crate::error::{Error, Result};

/// The description of the measured file at `path`, one `key: value` line each (a path that is
/// not UTF-8 is shown lossily).
pub fn describe(path: impl AsRef<Path>) -> Result<String> {
    let path = path.as_ref();
    if ends_with(path, ".binary") {
        describe_merl(path)
    } else if ends_with(path, ".bsdf") {
        describe_rgl(path)
    } else {
        Err(Error::Unsupported(format!(
            "{}: not a measured file (.binary, .bsdf)",
            path.display()
        )))
    }
}

/// Whether `path` ends in `ext` in any case (on its bytes: a name need not be UTF-8).
fn ends_with(path: &Path, ext: &str) -> bool {
    let b = path.as_os_str().as_encoded_bytes();
    b.len() >= ext.len() && b[b.len() - ext.len()..].eq_ignore_ascii_case(ext.as_bytes())
}

/// [`describe`] as JSON: `file`, `format` (`merl` or `rgl`), `bytes`, `channels`, `sha256`,
/// and per format: MERL `material` (the published name, or null), `dims` (θh, θd, φd),
/// `unmeasured` and `cells`; RGL `description`, `kind`, `isotropic`, `reduction`, `phi_i`,
/// `theta_i`, `resolution`, `vndf_resolution` and `fields` (name, type, offset).
pub fn info(path: impl AsRef<Path>) -> Result<Value> {
    let path = path.as_ref();
    let file = path.display().to_string();
    if ends_with(path, ".binary") {
        let sha = merl::sha256_file(path)?;
        let m = MerlBrdf::open(path)?;
        Ok(json!({
            "file": file,
            "format": "merl",
            "bytes": merl::FILE_SIZE,
            "material": merl::material_of(&sha),
            "dims": [merl::RES_THETA_H, merl::RES_THETA_D, merl::RES_PHI_D],
            "channels": m.channels().names(),
            "unmeasured": m.invalid_cells(),
            "cells": merl::SAMPLES,
            "sha256": sha,
        }))
    } else if ends_with(path, ".bsdf") {
        let t = TensorFile::open(path)?;
        let b = RglBrdf::from_tensor(&t, None)?;
        let s = b.summary();
        let fields: Vec<Value> = t
            .fields()
            .iter()
            .map(|f| json!({"name": f.name, "type": f.describe(), "offset": f.offset}))
            .collect();
        Ok(json!({
            "file": file,
            "format": "rgl",
            "bytes": t.size(),
            "description": s.description,
            "kind": s.kind,
            "isotropic": s.isotropic,
            "reduction": s.reduction,
            "phi_i": s.phi_i,
            "theta_i": s.theta_i,
            "resolution": [s.resolution.0, s.resolution.1],
            "vndf_resolution": [s.vndf_resolution.0, s.vndf_resolution.1],
            "channels": b.channels().names(),
            "fields": fields,
            "sha256": b.sha256(),
        }))
    } else {
        describe(path).map(|_| Value::Null)
    }
}

fn describe_merl(path: &Path) -> Result<String> {
    let sha = merl::sha256_file(path)?;
    let m = MerlBrdf::open(path)?;
    let mut o = String::new();
    let _ = writeln!(o, "file:        {}", path.display());
    let _ = writeln!(
        o,
        "format:      MERL BRDF database (.binary, Matusik et al. 2003)"
    );
    let _ = match merl::material_of(&sha) {
        Some(name) => writeln!(o, "material:    {name} (sha256 matches the published file)"),
        None => writeln!(
            o,
            "material:    unknown (sha256 matches none of the 100 published files)"
        ),
    };
    let _ = writeln!(
        o,
        "dims:        θh {} × θd {} × φd {} (sqrt θh axis), {} bytes",
        merl::RES_THETA_H,
        merl::RES_THETA_D,
        merl::RES_PHI_D,
        merl::FILE_SIZE
    );
    let _ = writeln!(
        o,
        "channels:    R G B (scales 1/1500, 1.15/1500, 1.66/1500)"
    );
    let _ = writeln!(
        o,
        "unmeasured:  {} of {} cells (negative, evaluated as 0)",
        m.invalid_cells(),
        merl::SAMPLES
    );
    let _ = writeln!(o, "sha256:      {sha}");
    Ok(o)
}

fn describe_rgl(path: &Path) -> Result<String> {
    let t = TensorFile::open(path)?;
    let b = RglBrdf::from_tensor(&t, None)?;
    let s = b.summary();
    let mut o = String::new();
    let _ = writeln!(o, "file:        {}", path.display());
    let _ = writeln!(
        o,
        "format:      RGL-EPFL tensor file (.bsdf, Dupuy & Jakob 2018), {} bytes",
        t.size()
    );
    let _ = writeln!(o, "description: {}", s.description);
    let _ = writeln!(o, "kind:        {}", s.kind);
    let symmetry = if s.isotropic {
        "isotropic".to_string()
    } else {
        format!("anisotropic, reduction {}", s.reduction)
    };
    let _ = writeln!(
        o,
        "dims:        φi {} × θi {}, table {}×{}, vndf {}×{}, {symmetry}",
        s.phi_i,
        s.theta_i,
        s.resolution.0,
        s.resolution.1,
        s.vndf_resolution.0,
        s.vndf_resolution.1,
    );
    let _ = writeln!(o, "channels:    {}", b.channels().names().join(" "));
    let _ = writeln!(o, "fields:");
    for f in t.fields() {
        let _ = writeln!(o, "  {:<12} {:<22} @ {}", f.name, f.describe(), f.offset);
    }
    let _ = writeln!(o, "sha256:      {}", b.sha256());
    Ok(o)
}
