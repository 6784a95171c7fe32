//! Opening any SOURCE string as a [`Brdf`]: the one place that knows the source kinds.
//!
//! Every host — the `brdftab` CLI, the Python package, the C ABI, the Mitsuba 3 plugin — names
//! what it wants to evaluate with one string, and this module turns that string into a `Brdf`.
//! Keeping the dispatch here (and nowhere else) means a new kind, or a fix to an old one, reaches
//! every host at once.
//!
//! | SOURCE | [`SourceKind`] | opened as |
//! |---|---|---|
//! | inline JSON (`{"model": ...}`) or a `.json` file | `Spec` | the analytic model ([`ModelSpec`]) |
//! | a MERL `.binary` file | `Merl` | [`MerlBrdf`](crate::measured::MerlBrdf) (nearest cell, as the MERL reader) |
//! | an RGL-EPFL `.bsdf` file | `Rgl` | [`RglBrdf`](crate::measured::RglBrdf) (the native adaptive evaluation) |
//! | a brdftab file, `DB#NAME` for one table of a database, or a raw table | `Table` | [`TabulatedBrdf`] |
//!
//! Classification looks at the string ([`classify`]; for a string with a `#`, also whether a
//! file of that whole name exists, as opening does); opening reads the file and reports a typed
//! [`Error`] (missing file, bad magic, unknown model, ...) with the path in it.
//!
//! A SOURCE is an [`OsStr`] (`impl AsRef<OsStr>`: a `&str`, a `String`, a `Path`, an
//! `OsString`): on Linux a file name is bytes, and a file whose name is not UTF-8 opens as any
//! other (its `DB#NAME` too: the name after `#` is UTF-8, as every table name). Inline JSON is
//! text. Errors show such a name lossily (U+FFFD for the bytes that are not UTF-8).

use std::ffi::OsStr;
use std::path::Path;

use crate::brdf::Brdf;
use crate::error::{Error, Result, excerpt};
use crate::spec::ModelSpec;
use crate::spectrum::Channels;
use crate::store::name::is_inline;
use crate::table::{Interp, Table, TabulatedBrdf};

/// What a SOURCE string names, judged from the string alone (see the module table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SourceKind {
    /// An analytic model: inline JSON or a `.json` spec file.
    Spec,
    /// A MERL `.binary` file.
    Merl,
    /// An RGL-EPFL `.bsdf` tensor file.
    Rgl,
    /// A brdftab table file, a database entry `DB#NAME`, or a raw table file.
    Table,
}

impl SourceKind {
    /// The kind's name as hosts print it: `spec`, `merl`, `rgl` or `table`.
    pub fn name(self) -> &'static str {
        match self {
            SourceKind::Spec => "spec",
            SourceKind::Merl => "merl",
            SourceKind::Rgl => "rgl",
            SourceKind::Table => "table",
        }
    }

    /// True for measured files (MERL and RGL).
    pub fn is_measured(self) -> bool {
        matches!(self, SourceKind::Merl | SourceKind::Rgl)
    }
}

/// Classifies a SOURCE that is read: inline JSON is a spec; `DB#NAME` is a table of a database
/// whatever NAME ends in (`materials.btdb#paper.bsdf` too); otherwise the file name's extension
/// decides. The file system is looked at only for a string with a `#`, as opening does
/// ([`crate::store::name::parse_input`]: a file of the whole name, `a#b.bsdf`, is that file).
///
/// ```
/// use brdftab::source::{classify, SourceKind};
/// assert_eq!(classify(r#"{"model": "lambert", "kd": 0.5}"#), SourceKind::Spec);
/// assert_eq!(classify("paint.json"), SourceKind::Spec);
/// assert_eq!(classify("gold-metallic-paint.binary"), SourceKind::Merl);
/// assert_eq!(classify("paper_white_rgb.bsdf"), SourceKind::Rgl);
/// assert_eq!(classify("materials.btdb#gold"), SourceKind::Table);
/// ```
pub fn classify(source: impl AsRef<OsStr>) -> SourceKind {
    let source = source.as_ref();
    if is_inline(source) {
        return SourceKind::Spec;
    }
    match crate::store::name::parse_input_os("source", source) {
        Ok((_, Some(_))) => SourceKind::Table,
        _ => classify_name(source.as_encoded_bytes()),
    }
}

/// Classifies an output string by its characters alone, as writing splits it
/// ([`crate::store::name::parse_source`]): `DB#NAME` is a table of a database, otherwise the
/// extension decides (`.binary`: a MERL file, `.bsdf`: an RGL file, other names: a table). An
/// output that is not UTF-8 is split on its bytes ([`crate::store::name::parse_output_os`]).
pub fn classify_output(output: impl AsRef<OsStr>) -> SourceKind {
    let output = output.as_ref();
    match crate::store::name::parse_output_os("output", output) {
        Ok((_, Some(_))) => SourceKind::Table,
        _ => classify_name(output.as_encoded_bytes()),
    }
}

/// Refuses `path` as the name of a brdftab table file written by a bake or a save when its
/// name reads as another kind of source: `.bsdf` (an RGL file), `.binary` (a MERL file) or
/// `.json` (a model spec). Sources
/// are told apart by their extension ([`classify`]), so such a table would not open again as
/// what it is (`m.bsdf` read as an RGL tensor file, `m.binary` as a truncated MERL file).
///
/// # Errors
/// [`Error::InvalidArgument`] naming `output`.
pub fn check_table_output(path: &std::path::Path) -> crate::Result<()> {
    let what = match classify_name(path.as_os_str().as_encoded_bytes()) {
        SourceKind::Rgl => "an RGL file",
        SourceKind::Merl => "a MERL file",
        SourceKind::Spec => "a model spec",
        SourceKind::Table => return Ok(()),
    };
    Err(crate::Error::arg(
        "output",
        format!(
            "{}: the name reads as {what}, but a brdftab table is written: give it a .btdb \
             name (a conversion writes RGL .bsdf and MERL .binary files)",
            path.display()
        ),
    ))
}

/// By the name's form and extension only (its bytes: the extensions are ASCII).
fn classify_name(source: &[u8]) -> SourceKind {
    let s = source.trim_ascii_start();
    let ends =
        |ext: &[u8]| s.len() >= ext.len() && s[s.len() - ext.len()..].eq_ignore_ascii_case(ext);
    if s.starts_with(b"{") || ends(b".json") {
        SourceKind::Spec
    } else if ends(b".binary") {
        SourceKind::Merl
    } else if ends(b".bsdf") {
        SourceKind::Rgl
    } else {
        SourceKind::Table
    }
}

/// How [`open_with`] opens a SOURCE. Builder-style: start from `OpenOptions::new()`.
///
/// ```
/// use brdftab::source::OpenOptions;
/// use brdftab::table::Interp;
/// let opts = OpenOptions::new().interp(Interp::Nearest).wavelengths(&[450.0, 550.0, 650.0])?;
/// let brdf = brdftab::open_with(r#"{"model": "lambert", "kd": 0.5}"#, &opts)?;
/// assert_eq!(brdf.channels().names(), ["450nm", "550nm", "650nm"]);
/// # Ok::<(), brdftab::Error>(())
/// ```
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OpenOptions {
    /// Interpolation of tables; `None` (the default) chooses per table
    /// ([`TabulatedBrdf::default_interp`]: nearest on tables of MERL cells, linear otherwise).
    /// A MERL file is a table of cells: linear opens it as its table on the MERL grid
    /// ([`crate::measured::MerlBrdf::to_table`]) with linear lookups. RGL files and analytic
    /// sources ignore it.
    pub interp: Option<Interp>,
    /// Channels to evaluate: `None` keeps the source's own (RGB for model specs, the file's for
    /// RGL files). Model specs evaluate their spectral data at these wavelengths; RGL files
    /// resample their spectra. Tables and MERL files have fixed channels: asking them for other
    /// channels is an error.
    pub channels: Option<Channels>,
    /// Decode every chunk of a table now (in parallel, checking each checksum) instead of on the
    /// first lookup that touches it: the open fails on a corrupt table, and lookups never wait
    /// on decoding.
    pub eager: bool,
}

impl OpenOptions {
    /// The defaults: interpolation chosen per table, the source's own channels, lazy decoding.
    pub fn new() -> OpenOptions {
        OpenOptions::default()
    }

    /// Sets the interpolation of tables.
    pub fn interp(mut self, interp: Interp) -> OpenOptions {
        self.interp = Some(interp);
        self
    }

    /// Sets the channels.
    pub fn channels(mut self, channels: Channels) -> OpenOptions {
        self.channels = Some(channels);
        self
    }

    /// Sets the channels to wavelengths in nm (strictly increasing, positive).
    pub fn wavelengths(self, nm: &[f64]) -> Result<OpenOptions> {
        Ok(self.channels(Channels::wavelengths(nm.to_vec())?))
    }

    /// Decode every chunk of a table when it is opened.
    pub fn eager(mut self, eager: bool) -> OpenOptions {
        self.eager = eager;
        self
    }
}

/// Opens SOURCE with the default [`OpenOptions`] (interpolation chosen per table, the
/// source's own channels).
///
/// `DB#NAME` is split at the last `#`, unless the whole string names an existing file: then it is
/// that file (`a#b.btdb` opens as itself; [`crate::store::name`]).
///
/// An analytic model, inline:
/// ```
/// use glam::DVec3;
/// let brdf = brdftab::open(r#"{"model": "lambert", "kd": [0.1, 0.2, 0.3]}"#)?;
/// let mut f = [0.0f32; 3];
/// brdf.eval(DVec3::Z, DVec3::Z, &mut f);
/// assert_eq!(f, [0.1, 0.2, 0.3]);
/// # Ok::<(), brdftab::Error>(())
/// ```
/// A table file, and one table of a database (`DB#NAME`):
/// ```
/// # let dir = std::env::temp_dir().join(format!("brdftab-open-doc-{}", std::process::id()));
/// # std::fs::create_dir_all(&dir)?;
/// # let db = dir.join("doc.btdb");
/// # let db = db.to_str().unwrap();
/// use brdftab::bake::{BakeRequest, BakeTarget};
/// use brdftab::table::presets::Preset;
/// let spec = r#"{"model": "lambert", "kd": 0.25}"#;
/// BakeRequest::new(spec).preset(Preset::Small).run(&BakeTarget::db(db, "matte"))?;
/// let table = brdftab::open(&format!("{db}#matte"))?;
/// assert_eq!(table.channels().len(), 3);
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
/// An RGL-EPFL measurement (the shipped `data/rgl` files):
/// ```
/// let dir = brdftab::measured::data::rgl_dir().expect("data/rgl ships with brdftab");
/// let rgl = brdftab::open(dir.join("paper_white_rgb.bsdf").to_str().unwrap())?;
/// assert_eq!(rgl.channels().names(), ["R", "G", "B"]);
/// # Ok::<(), brdftab::Error>(())
/// ```
/// A MERL `.binary` file (here one written from a model; the 100 published files open alike):
/// ```
/// # let dir = std::env::temp_dir().join(format!("brdftab-merl-doc-{}", std::process::id()));
/// # std::fs::create_dir_all(&dir)?;
/// let path = dir.join("matte.binary");
/// let model = brdftab::open(r#"{"model": "lambert", "kd": 0.5}"#)?;
/// brdftab::measured::MerlBrdf::from_brdf(model.as_ref()).write(&path)?;
/// let merl = brdftab::open(path.to_str().unwrap())?;
/// let mut f = [0.0f32; 3];
/// merl.eval(glam::DVec3::new(0.3, 0.0, 0.9), glam::DVec3::Z, &mut f);
/// assert!((f[0] - 0.5).abs() < 1e-3);
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
/// A missing file is an error that names it:
/// ```
/// let e = brdftab::open("no-such-material.binary").unwrap_err();
/// assert!(e.to_string().contains("no-such-material.binary"));
/// ```
/// To share one opened source between threads or materials, make the box an `Arc` of the same
/// type (`From<Box<T>>`), which then coerces to `Arc<dyn Brdf>`:
/// ```
/// use std::sync::Arc;
/// let shared: Arc<dyn brdftab::Brdf + Send + Sync> = brdftab::open(r#"{"model": "lambert", "kd": 0.2}"#)?.into();
/// let material: Arc<dyn brdftab::Brdf> = shared.clone();
/// # Ok::<(), brdftab::Error>(())
/// ```
pub fn open(source: impl AsRef<OsStr>) -> Result<Box<dyn Brdf + Send + Sync>> {
    open_with(source, &OpenOptions::default())
}

/// Opens SOURCE as `opts` say (see [`open`] for the kinds).
pub fn open_with(
    source: impl AsRef<OsStr>,
    opts: &OpenOptions,
) -> Result<Box<dyn Brdf + Send + Sync>> {
    let source = source.as_ref();
    let shown = source.to_string_lossy();
    // An empty SOURCE (or an empty path before `#NAME`) names nothing: it was "not found: : no
    // such file".
    if shown.trim().is_empty() || (shown.starts_with('#') && !Path::new(source).exists()) {
        return Err(Error::arg(
            "source",
            format!("{shown:?}: an empty SOURCE or path (expected a spec, a file or DB#NAME)"),
        ));
    }
    if let Some(c) = &opts.channels {
        c.validate()?;
    }
    // Stat before any open: a FIFO, socket, device or directory is refused at once.
    // `x.btdb#` or a control character in NAME is an argument error, not a path to stat.
    if !is_inline(source) {
        let (f, _) = crate::store::name::parse_input_os("source", source)?;
        crate::files::require_regular(f)?;
    }
    let fixed_channels = |brdf: Box<dyn Brdf + Send + Sync>| match &opts.channels {
        Some(c) if c != brdf.channels() => Err(Error::Unsupported(format!(
            "{}: stored with channels {}; it cannot be evaluated at {}",
            excerpt(&shown),
            brdf.channels().names().join(" "),
            c.names().join(" ")
        ))),
        _ => Ok(brdf),
    };
    match classify(source) {
        SourceKind::Spec => {
            let channels = opts.channels.clone().unwrap_or(Channels::Rgb);
            spec(source)?.build(&channels)
        }
        SourceKind::Merl => {
            let merl = crate::measured::MerlBrdf::open(source)?;
            // The file is a table of cells: a linear lookup asked for is the one its table on
            // the MERL grid gives (auto and nearest: the reader's cell, as `MerlBrdf` reads it).
            fixed_channels(if opts.interp == Some(Interp::Linear) {
                Box::new(TabulatedBrdf::from_table(merl.to_table()).with_interp(Interp::Linear))
            } else {
                Box::new(merl)
            })
        }
        SourceKind::Rgl => match &opts.channels {
            Some(c) => Ok(Box::new(crate::measured::RglBrdf::open_with_channels(
                source, c,
            )?)),
            None => Ok(Box::new(crate::measured::RglBrdf::open(source)?)),
        },
        SourceKind::Table => fixed_channels(Box::new(open_table(source, opts)?)),
    }
}

/// Opens a table SOURCE (`FILE`, `DB#NAME` or a raw table) as a [`TabulatedBrdf`].
pub fn open_table(source: impl AsRef<OsStr>, opts: &OpenOptions) -> Result<TabulatedBrdf> {
    let source = source.as_ref();
    let (path, name) = crate::store::name::parse_input_os("source", source)?;
    crate::files::require_regular(path)?;
    let shown = path.to_string_lossy();
    let brdf = if crate::store::tables::is_store_file(path) {
        crate::store::tables::open_brdf_at(path, name, opts.eager)?
    } else if Table::is_raw(source) {
        TabulatedBrdf::from_table(Table::open_raw(source)?)
    } else if !path.exists() {
        return Err(Error::NotFound(format!(
            "{}: no such file",
            excerpt(&shown)
        )));
    } else if crate::measured::tensor::has_magic(path) {
        // Sources are told apart by name (`classify`); an RGL file under another name would
        // otherwise be "no RGL signature", which it has.
        return Err(Error::Unsupported(format!(
            "{}: an RGL tensor file (its signature) without the .bsdf name that RGL files are \
             opened by: give it a .bsdf name",
            excerpt(&shown)
        )));
    } else {
        return Err(Error::Unsupported(format!(
            "{}: not a file brdftab can read (no brdftab, MERL or RGL signature, and not a \
             .json spec)",
            excerpt(&shown)
        )));
    };
    let interp = opts.interp.unwrap_or_else(|| brdf.default_interp());
    Ok(brdf.with_interp(interp))
}

/// Parses a spec SOURCE: inline JSON (starting with `{`) or a `.json` file.
pub fn spec(source: impl AsRef<OsStr>) -> Result<ModelSpec> {
    let source = source.as_ref();
    match source.to_str() {
        Some(s) if is_inline(source) => ModelSpec::parse(s),
        None if is_inline(source) => Err(Error::arg(
            "source",
            format!(
                "{}: inline JSON that is not UTF-8",
                excerpt(&source.to_string_lossy())
            ),
        )),
        _ => ModelSpec::from_file(source),
    }
}

/// Parses a comma-separated list of wavelengths in nm (`"450, 550, 650"`).
pub fn parse_wavelengths(list: &str) -> Result<Channels> {
    if list.trim().eq_ignore_ascii_case("rgb") {
        // `Channels`'s parse takes "rgb" too; a list of wavelengths does not.
        return Err(Error::arg(
            "wavelengths",
            "`rgb` is not a list of wavelengths",
        ));
    }
    list.parse()
}

/// The provenance a table baked from SOURCE records: the spec for models, the file's name and
/// sha256 for measurements, the source's own description otherwise.
pub fn provenance(source: impl AsRef<OsStr>, brdf: &dyn Brdf) -> Result<crate::store::Source> {
    let source = source.as_ref();
    Ok(match classify(source) {
        SourceKind::Spec => crate::store::Source::model(&spec(source)?),
        SourceKind::Merl | SourceKind::Rgl => crate::store::Source::measured(source)?,
        SourceKind::Table => crate::store::Source::Other {
            description: format!("{}: {}", source.to_string_lossy(), brdf.describe()),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn a_file_under_the_wrong_name_is_named_by_its_signature() {
        let d = crate::testkit::TempDir::new("source-misnamed");
        let rgl = crate::measured::data::rgl_file("paper_white_rgb.bsdf").unwrap();
        let as_dat = d.join("paper.dat");
        std::fs::copy(&rgl, &as_dat).unwrap();
        let e = open(as_dat.to_str().unwrap()).unwrap_err().to_string();
        assert!(
            e.contains("an RGL tensor file") && e.contains(".bsdf name"),
            "{e}"
        );
        let table = d.join("t.btdb");
        crate::bake::BakeRequest::new(r#"{"model":"lambert","kd":0.5}"#)
            .preset(crate::table::presets::Preset::Small)
            .run(&crate::bake::BakeTarget::file(table.to_str().unwrap()))
            .unwrap();
        let as_bsdf = d.join("t.bsdf");
        std::fs::copy(&table, &as_bsdf).unwrap();
        let e = open(as_bsdf.to_str().unwrap()).unwrap_err().to_string();
        assert!(
            e.contains("brdftab table") && e.contains(".btdb name"),
            "{e}"
        );
        // Neither signature: the message says so.
        let junk = d.join("junk.dat");
        std::fs::write(&junk, b"0123456789abcdef").unwrap();
        let e = open(junk.to_str().unwrap()).unwrap_err().to_string();
        assert!(e.contains("no brdftab, MERL or RGL signature"), "{e}");
    }

    #[test]
    fn channels_and_quantities_parse_from_strings() {
        use crate::table::Quantity;
        assert_eq!("RGB".parse::<Channels>().unwrap(), Channels::Rgb);
        assert_eq!(
            " 450, 550 ".parse::<Channels>().unwrap(),
            Channels::wavelengths(vec![450.0, 550.0]).unwrap()
        );
        for bad in ["", "450,x", "550,450", "-1"] {
            assert!(bad.parse::<Channels>().is_err(), "{bad}");
        }
        assert!(parse_wavelengths("rgb").is_err());
        assert_eq!(parse_wavelengths("450").unwrap().len(), 1);
        assert_eq!(
            "fr_cos_out".parse::<Quantity>().unwrap(),
            Quantity::FrCosOut
        );
        match "cos".parse::<Quantity>() {
            Err(Error::InvalidArgument { name, .. }) => assert_eq!(name, "quantity"),
            r => panic!("{r:?}"),
        }
    }

    #[test]
    fn empty_source_is_an_argument_error() {
        for s in ["", "  ", "#name"] {
            match open(s) {
                Err(Error::InvalidArgument { name, msg }) => {
                    assert_eq!(name, "source", "{s:?}: {msg}")
                }
                r => panic!("{s:?}: {:?}", r.map(|b| b.describe())),
            }
        }
    }

    #[test]
    fn classify_is_by_string_only() {
        assert_eq!(classify("  {\"model\": \"x\"}"), SourceKind::Spec);
        assert_eq!(classify("A.JSON"), SourceKind::Spec);
        assert_eq!(classify("x.BINARY"), SourceKind::Merl);
        assert_eq!(classify("x.Bsdf"), SourceKind::Rgl);
        assert_eq!(classify("x.btdb"), SourceKind::Table);
        assert_eq!(classify("x.tbl"), SourceKind::Table);
        // A table of a database is a table whatever its name ends in.
        for kind in ["json", "binary", "bsdf"] {
            assert_eq!(classify(format!("db.btdb#t.{kind}")), SourceKind::Table);
            assert_eq!(
                classify_output(format!("db.btdb#t.{kind}")),
                SourceKind::Table
            );
        }
        assert_eq!(classify_output("x.bsdf"), SourceKind::Rgl);
        assert_eq!(classify_output("x.binary"), SourceKind::Merl);
    }

    #[test]
    fn spec_with_wavelengths_evaluates_there() {
        let opts = OpenOptions::new().wavelengths(&[500.0, 600.0]).unwrap();
        let b = open_with(r#"{"model":"lambert","kd":0.5}"#, &opts).unwrap();
        let mut f = [0.0f32; 2];
        b.eval(DVec3::Z, DVec3::Z, &mut f);
        assert_eq!(f, [0.5, 0.5]);
    }

    #[test]
    fn errors_are_typed() {
        assert!(matches!(
            open(r#"{"model":"no_such_model"}"#),
            Err(Error::Spec { .. })
        ));
        assert!(matches!(
            open("/nonexistent/x.btdb"),
            Err(Error::NotFound(_))
        ));
        assert!(matches!(
            open("/nonexistent/x.binary"),
            Err(Error::NotFound(_))
        ));
        assert!(matches!(
            parse_wavelengths("400, x"),
            Err(Error::InvalidArgument { .. })
        ));
        let dir = crate::testkit::TempDir::new("src");
        let junk = dir.join("junk.tbl");
        std::fs::write(&junk, b"not a table at all").unwrap();
        assert!(matches!(
            open(junk.to_str().unwrap()),
            Err(Error::Unsupported(_))
        ));
    }
}
