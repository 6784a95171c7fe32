//! The materials a viewer answers for, fixed when it starts.
//!
//! Each SOURCE of the command line becomes one material, and a database becomes one material
//! per table. Every material is opened here, once (tables decoded eagerly, so a slider never
//! waits on a chunk and a corrupt table fails the start), and gets an index: the page names
//! materials by that index only, never by path. A table whose provenance names a source that
//! opens — a model spec, or a measured file of that name and SHA-256 beside the database — is
//! paired with it, so the page can show the difference and the error figures. A file of that
//! name whose hash differs is another measurement: it is not paired, and the list says why.

use std::collections::HashMap;
use std::ffi::{OsStr, OsString};
use std::path::Path;
use std::sync::{Arc, Mutex, OnceLock};

use brdftab::measured::merl::sha256_file;
use brdftab::source::{OpenOptions, SourceKind, classify};
use brdftab::store::{db, info, tables};
use brdftab::{Brdf, Channels, Error, Result};
use serde_json::{Value, json};

/// An opened BRDF shared between the server's threads.
pub type Shared = Arc<dyn Brdf + Send + Sync>;

/// One material: what the list shows of it, its BRDF, and its source if it has one that opens.
pub struct Material {
    /// What `/api/materials` says of it (name, kind, channels, grid, bytes, ratio, codec, ...).
    pub info: Value,
    /// The material itself.
    pub brdf: Shared,
    /// The source a table was baked from, when its provenance names one that opens.
    pub source: Option<Shared>,
    /// True for measured data (compared within 80° of the normal, as the demo does).
    pub measured_source: bool,
}

/// Every material, by index, and a cache of the slow figures (error figures, plausibility).
pub struct Registry {
    /// The materials in command-line order (a database's tables in file order).
    pub materials: Vec<Material>,
    /// One cell per key, made under the lock and filled outside it: requests for a figure
    /// still being computed wait for that computation instead of starting their own.
    cache: Mutex<HashMap<String, Arc<OnceLock<Arc<String>>>>>,
}

impl Registry {
    /// Opens every SOURCE (a database lists its tables); fails on the first that does not open.
    /// A SOURCE need not be UTF-8 (a `String`, `OsString` or `PathBuf`: a file name is bytes).
    pub fn open<S: AsRef<OsStr>>(sources: &[S]) -> Result<Registry> {
        let mut materials = Vec::new();
        for s in sources {
            for (name, source, summary, at) in entries(s.as_ref())? {
                materials.push(material(&name, &source, summary, at.as_ref())?);
            }
        }
        if materials.is_empty() {
            return Err(Error::arg("SOURCE", "no materials to show"));
        }
        for (i, m) in materials.iter_mut().enumerate() {
            m.info["id"] = json!(i);
        }
        Ok(Registry {
            materials,
            cache: Mutex::new(HashMap::new()),
        })
    }

    /// The material of index `id`, if there is one.
    pub fn get(&self, id: usize) -> Option<&Material> {
        self.materials.get(id)
    }

    /// The value cached under `key`, computing it with `f` the first time. Concurrent
    /// requests for one key compute it once: the others wait for that value (the page asks for
    /// a material's albedo and error figures again on every click, each taking seconds). Other
    /// keys are computed meanwhile; a computation that panics leaves the key empty.
    pub fn cached(&self, key: String, f: impl FnOnce() -> String) -> Arc<String> {
        let cell = match self.cache.lock() {
            Ok(mut c) => c.entry(key).or_default().clone(),
            Err(_) => Arc::new(OnceLock::new()),
        };
        cell.get_or_init(|| Arc::new(f())).clone()
    }
}

/// The (name, SOURCE, store summary, (file, table) of a store's entry) of every material
/// SOURCE `s` holds.
type Entry = (String, OsString, Option<Value>, Option<(OsString, String)>);

/// The materials SOURCE `s` holds (a database: each of its tables, or the one it names).
fn entries(s: &OsStr) -> Result<Vec<Entry>> {
    let (path, name) = db::split_source(s)?;
    if classify(s) != SourceKind::Table || !tables::is_store_file(path) {
        return Ok(vec![(display_name(s), s.to_owned(), None, None)]);
    }
    let rows = match name {
        Some(n) => vec![info::table_info(path, n)?],
        None => info::list(path)?,
    };
    Ok(rows
        .into_iter()
        .map(|r| {
            let n = r["name"].as_str().unwrap_or_default().to_owned();
            let at = (path.as_os_str().to_owned(), n.clone());
            let mut source = at.0.clone();
            source.push(format!("#{n}"));
            (n.clone(), source, Some(r), Some(at))
        })
        .collect())
}

/// A short name for a SOURCE that is not a database entry: the model of a spec, else the file
/// name.
fn display_name(s: &OsStr) -> String {
    if s.to_string_lossy().trim_start().starts_with('{') {
        return brdftab::source::spec(s)
            .map(|m| m.name().to_owned())
            .unwrap_or_else(|_| "spec".to_owned());
    }
    Path::new(s)
        .file_name()
        .unwrap_or(s)
        .to_string_lossy()
        .into_owned()
}

/// Opens one material and describes it; a store's entry by its file and table name (`at`), so
/// that a file named like the `FILE#NAME` string beside it is not what opens.
fn material(
    name: &str,
    source: &OsStr,
    summary: Option<Value>,
    at: Option<&(OsString, String)>,
) -> Result<Material> {
    let kind = classify(source);
    let brdf: Shared = match at {
        Some((file, table)) => Arc::new(tables::open_brdf_at(file, Some(table), true)?),
        None => Arc::from(brdftab::open_with(source, &OpenOptions::new().eager(true))?),
    };
    let mut info = json!({
        "name": name,
        "kind": kind.name(),
        "channels": brdf.channels().names(),
        "description": brdf.describe(),
        "delta": super::eval::has_delta(brdf.as_ref()),
    });
    if kind == SourceKind::Spec {
        info["spec"] =
            serde_json::from_str(&brdftab::source::spec(source)?.to_json()).unwrap_or(Value::Null);
    }
    let (mut paired, mut measured_source) = (None, false);
    if let Some(s) = &summary {
        let shape: Vec<String> = s["shape"]
            .as_array()
            .map(|a| a.iter().map(|x| x.to_string()).collect())
            .unwrap_or_default();
        info["grid"] = json!(format!(
            "{} {} {}",
            s["parameterization"].as_str().unwrap_or(""),
            shape.join("×"),
            s["symmetry"].as_str().unwrap_or("")
        ));
        info["bytes"] = s["bytes"].clone();
        info["ratio"] = s["ratio_to_f32"].clone();
        info["codec"] = s["codec"].clone();
        info["provenance"] = s["source"].clone();
        let dir = db::split_source(source).map_or(Path::new(source), |(p, _)| p);
        let dir = dir.parent();
        let note;
        (paired, measured_source, note) = provenance_source(&s["source"], dir, brdf.channels());
        if let Some(n) = note {
            info["source_note"] = json!(n);
        }
    }
    info["has_source"] = json!(paired.is_some());
    Ok(Material {
        info,
        brdf,
        source: paired,
        measured_source,
    })
}

/// The source a table's provenance names, if it opens: a model spec, or a measured file of the
/// recorded name in the table's directory (the provenance keeps the file name only) whose
/// SHA-256 is the recorded one. Whether it is measured rides along, and why a file of that name
/// was not paired.
///
/// The source is opened at the table's `channels`, as it was baked (`--wavelengths`): a spec
/// opened in RGB beside a spectral table compared 3 channels with 7 ("7 vs 3 channels").
fn provenance_source(
    p: &Value,
    dir: Option<&Path>,
    channels: &Channels,
) -> (Option<Shared>, bool, Option<String>) {
    let opts = OpenOptions::new().channels(channels.clone());
    let open = |s: &OsStr| brdftab::open_with(s, &opts).ok().map(Arc::from);
    match p["kind"].as_str() {
        Some("model") => {
            let opened = open(p["spec"].to_string().as_ref());
            (opened, false, None)
        }
        Some("measured") => {
            let Some(file) = p["file"].as_str().filter(|f| !f.contains(['/', '\\'])) else {
                return (None, false, None);
            };
            let path = dir.unwrap_or(Path::new(".")).join(file);
            if !(classify(&path).is_measured() && path.is_file()) {
                return (None, true, None);
            }
            let recorded = p["sha256"].as_str().unwrap_or_default();
            match sha256_file(&path) {
                Ok(sha) if sha.eq_ignore_ascii_case(recorded) => {
                    (open(path.as_os_str()), true, None)
                }
                Ok(_) => (
                    None,
                    true,
                    Some(format!(
                        "{file} beside it is not the file it was baked from (its sha256 differs)"
                    )),
                ),
                Err(_) => (None, true, None),
            }
        }
        _ => (None, false, None),
    }
}
