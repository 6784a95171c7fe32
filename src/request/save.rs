//! [`SaveSettings`], [`save_table`] and [`import_npy`]: tables whose values were made outside
//! the library — smoothed, rescaled, fitted or optimized in numpy or a renderer — written as
//! brdftab tables.
//!
//! Why a module: a bake writes the tables it makes; these write the tables a host hands back,
//! with a bake's codec settings and its output rule (a `.btdb` file replaced atomically, or
//! `DB#NAME`), so `brdftab import`, Python's `Table.save` and any later host store them alike.

use std::ffi::OsStr;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::bake::{self, BakeTarget};
use crate::codec::Codec;
use crate::error::{Error, Result, excerpt};
use crate::source::{self, OpenOptions, SourceKind};
use crate::store::npy::NpyReader;
use crate::store::{self, tables};
use crate::table::{Grid, Table};

/// How a table is stored (`brdftab import`'s flags, Python's `Table.save` keywords): the
/// fields of [`BakeSettings`](super::BakeSettings) that say so, with the same names, meanings
/// and defaults.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct SaveSettings {
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
    /// Table name inside the file (default: the output file's stem; `DB#NAME` names it
    /// itself, and another name beside it is an error).
    #[cfg_attr(feature = "clap", arg(long))]
    pub name: Option<String>,
    /// Replace an existing table of that name (database outputs).
    #[cfg_attr(feature = "clap", arg(long))]
    pub replace: bool,
}

impl SaveSettings {
    /// The codec these settings describe (default log16 ≤ 1e-3, [`bake::default_codec`]);
    /// also checks the name.
    ///
    /// # Errors
    /// [`Error::InvalidArgument`] naming the field (`codec`, `codec_tolerance`, `floor`,
    /// `level`, `name`).
    pub fn codec(&self) -> Result<Codec> {
        if let Some(n) = &self.name {
            store::name::check("name", n)?;
        }
        bake::codec(
            self.codec.as_deref().unwrap_or("log16"),
            self.codec_tolerance,
            self.floor,
            self.level,
            self.exhaustive,
        )
    }
}

/// Writes `table` to `output` as `settings` say, with `source` as its provenance: `DB#NAME` is
/// a table of a database (created if absent; an existing name is an error unless `replace`),
/// any other name a single-table brdftab file (`.btdb`), replaced atomically — the outputs of
/// [`bake()`](super::bake()). Returns what `brdftab info --json OUTPUT` reports of the table
/// written ([`store::info::file_info`]).
///
/// # Errors
/// Invalid settings or output ([`Error::InvalidArgument`] naming the field; `name` for a name
/// setting beside a `DB#NAME` output that is not NAME, as in a bake), an existing
/// table of that name without `replace` ([`Error::Duplicate`]), values the codec cannot encode
/// ([`Error::Encode`]: f16 beyond ±65504), and whatever writing fails with.
pub fn save_table(
    table: &Table,
    output: impl AsRef<OsStr>,
    source: store::Source,
    settings: &SaveSettings,
) -> Result<serde_json::Value> {
    let codec = settings.codec()?;
    let (path, name) = match target(&output, settings.replace)? {
        BakeTarget::Db {
            path,
            name,
            replace,
        } => {
            bake::refuse_name_conflict(settings.name.as_deref(), &name)?;
            tables::save(&path, &name, source, table, codec, replace)?;
            (path, name)
        }
        t => {
            let path = t.path().to_owned();
            store::db::refuse_dropping_tables(&path)?;
            let name = settings.name.clone().unwrap_or_else(|| bake::stem(&path));
            tables::save_file(&path, &name, source, table, codec)?;
            (path, name)
        }
    };
    // By the path written: a `DB#NAME` string is looked up whole first (store::name).
    store::info::file_info_at(&path, Some(&name))
}

/// Reads the `.npy` array at `array` and writes it to `output` ([`save_table`]) as a table on
/// the grid of the table SOURCE `like` (a table file or `DB#NAME`): its stored layout,
/// symmetry, quantity and albedo calibration. The array is what the `.npy` export of such a
/// table writes — shaped by the stored axes and the channels, float32 or float64, C order; for
/// a packed layout (an `inout` reciprocal table) the whole rectangle, whose unstored nodes
/// (NaN in the export) are ignored. The values are the stored quantity, before the
/// calibration's factors, as the export gives them; negative values keep their meaning
/// ([`Table::with_values`]). With `calibration` false the values are another material's and
/// the like table's albedo calibration is dropped ([`Grid::without_calibration`]): its factors
/// were measured for the like table's values. The provenance reads "values from FILE on the
/// grid of LIKE".
///
/// # Errors
/// [`Error::InvalidArgument`] naming `like` for a SOURCE that is not a stored table, `output`
/// for an output that is the array's own file, or a settings field; [`Error::Format`] naming
/// the array's file, field and byte offset for an array the reader refuses
/// ([`NpyReader::new`]), another shape than the table's, or a NaN or infinite value at a
/// stored node; and what [`save_table`] fails with.
pub fn import_npy(
    array: &Path,
    like: impl AsRef<OsStr>,
    output: impl AsRef<OsStr>,
    settings: &SaveSettings,
    calibration: bool,
) -> Result<serde_json::Value> {
    // Settings and output before any file is read.
    settings.codec()?;
    let like = like.as_ref();
    let out_path = target(&output, settings.replace)?.path().to_owned();
    if crate::files::same_file(&out_path, array) {
        return Err(Error::arg(
            "output",
            format!(
                "{} is the array being imported: writing the table there would replace \
                 it (write to another file)",
                out_path.display()
            ),
        ));
    }
    let grid = match like_grid(like)? {
        g if calibration => g,
        g => g.without_calibration(),
    };
    let file = array.display().to_string();
    let reader = NpyReader::open(array)?;
    let h = reader.header().clone();
    let l = grid.layout();
    let shape: Vec<usize> = l.shape.iter().copied().chain([l.channels]).collect();
    if h.shape != shape {
        return Err(Error::format(
            &file,
            Some("shape"),
            None,
            format!(
                "an array of shape {:?}; the table {} holds an array of shape {shape:?} (its \
                 stored axes and channels, as its .npy export writes them)",
                h.shape,
                excerpt(&like.to_string_lossy())
            ),
        ));
    }
    let data = reader.read_f32()?;
    if let Some((i, at)) = crate::table::first_nonfinite_at(&grid, &shape, &data)? {
        let only = if l.packed {
            " (only the nodes a packed table does not store may be NaN)"
        } else {
            ""
        };
        return Err(Error::format(
            &file,
            Some("data"),
            Some(h.data_offset + (i * h.dtype.size()) as u64),
            format!(
                "{} at index {at}, a node the table stores: every stored value must be \
                 finite{only}",
                data[i]
            ),
        ));
    }
    let name = array
        .file_name()
        .map_or_else(|| file.clone(), |n| n.to_string_lossy().into_owned());
    let description = format!(
        "values from {name} on the grid of {}",
        like.to_string_lossy()
    );
    let table = Table::from_array(grid, &shape, data, description.clone())?;
    save_table(
        &table,
        output,
        store::Source::Other { description },
        settings,
    )
}

/// Where [`bake()`](super::bake()) and [`save_table`] write `output`; a `DB#NAME` with an empty or invalid name is an argument
/// error naming `output` ([`crate::store::name`]). The output need not be UTF-8: `DB#NAME` is
/// split on its bytes ([`crate::store::name::parse_output_os`]).
pub fn target(output: impl AsRef<OsStr>, replace: bool) -> Result<BakeTarget> {
    Ok(
        match crate::store::name::parse_output_os("output", output.as_ref())? {
            (path, Some(name)) => BakeTarget::Db {
                path: path.into(),
                name: name.into(),
                replace,
            },
            (path, None) => BakeTarget::File(path.into()),
        },
    )
}

/// The grid of the table SOURCE `like`; anything that is not a stored table is an error naming
/// `like`.
fn like_grid(like: &OsStr) -> Result<Grid> {
    let kind = source::classify(like);
    if kind != SourceKind::Table {
        return Err(Error::arg(
            "like",
            format!(
                "{} is a {} source, not a stored table (a table file or DB#NAME): its grid is \
                 the table's",
                excerpt(&like.to_string_lossy()),
                kind.name()
            ),
        ));
    }
    match source::open_table(like, &OpenOptions::default()) {
        Ok(t) => Ok(t.grid().clone()),
        Err(
            Error::NotFound(msg) | Error::Unsupported(msg) | Error::InvalidArgument { msg, .. },
        ) => Err(Error::arg("like", msg)),
        Err(e) => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bake::BakeRequest;
    use crate::progress::Silent;
    use crate::spectrum::Channels;
    use crate::store::{Store, export};
    use crate::table::{Mapping, Param, Symmetry};
    use crate::testkit::TempDir;

    fn lossless() -> SaveSettings {
        SaveSettings {
            codec: Some("f32".into()),
            ..SaveSettings::default()
        }
    }

    /// A small Cook-Torrance table (halfdiff, not packed).
    fn ct() -> Table {
        BakeRequest::new(r#"{"model": "cook_torrance", "m": 0.3}"#)
            .grid("16x1x16x32".parse().unwrap())
            .table(&Silent)
            .unwrap()
            .0
    }

    /// A packed table: `inout` reciprocal, the triangle θi ≤ θo.
    fn packed() -> Table {
        let g = Grid::with_sizes(
            Param::InOut,
            [8, 1, 8, 16],
            [Mapping::Uniform, Mapping::Uniform],
            Channels::Rgb,
            Symmetry {
                isotropic: true,
                reciprocal: true,
                bilateral: false,
            },
        )
        .unwrap();
        Table::from_fn(g, "packed", |i, a, out| {
            for (c, o) in out.iter_mut().enumerate() {
                *o = (a[0].cos() * a[2].cos()) as f32 * (1.0 + c as f32) + i[3] as f32 * 1e-3;
            }
        })
    }

    fn other(d: &str) -> store::Source {
        store::Source::Other {
            description: d.into(),
        }
    }

    /// The values of the stored table `source`.
    fn stored(source: &str) -> Vec<f32> {
        source::open_table(source, &OpenOptions::default())
            .unwrap()
            .to_table()
            .unwrap()
            .into_parts()
            .1
    }

    fn bits(v: &[f32]) -> Vec<u32> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    #[test]
    fn a_table_saves_to_a_file_or_a_database_and_reports_its_info() {
        let d = TempDir::new("save-table");
        let t = ct();
        let file = d.file("ct.btdb");
        let info = save_table(&t, &file, other("edited"), &lossless()).unwrap();
        assert_eq!(info, store::info::file_info_at(&file, None).unwrap());
        let e = &info["tables"][0];
        assert_eq!(
            (&e["name"], &e["values"]),
            (&"ct".into(), &t.values().len().into())
        );
        assert_eq!(e["source"]["description"], "edited");
        assert_eq!(e["codec"]["quant"], "f32");
        assert_eq!(bits(&stored(&file)), bits(t.values()));
        // A second save replaces the file: one table, the new values.
        let doubled = t
            .with_values(t.values().iter().map(|x| 2.0 * x).collect())
            .unwrap();
        save_table(&doubled, &file, other("doubled"), &lossless()).unwrap();
        assert_eq!(Store::open(&file).unwrap().tables().len(), 1);
        assert_eq!(bits(&stored(&file)), bits(doubled.values()));

        let db = d.file("lib.btdb");
        let entry = format!("{db}#a");
        let info = save_table(&t, &entry, other("a"), &SaveSettings::default()).unwrap();
        assert_eq!(info["tables"][0]["codec"]["quant"], "log16");
        assert_eq!(info["tables"].as_array().unwrap().len(), 1);
        save_table(&t, format!("{db}#b"), other("b"), &lossless()).unwrap();
        let again = save_table(&doubled, &entry, other("a"), &lossless()).unwrap_err();
        assert!(matches!(again, Error::Duplicate { .. }), "{again}");
        let replace = SaveSettings {
            replace: true,
            ..lossless()
        };
        save_table(&doubled, &entry, other("a"), &replace).unwrap();
        assert_eq!(bits(&stored(&entry)), bits(doubled.values()));
        assert_eq!(Store::open(&db).unwrap().tables().len(), 2);
        let named = SaveSettings {
            name: Some("mine".into()),
            ..lossless()
        };
        let info = save_table(&t, d.file("x.btdb"), other("x"), &named).unwrap();
        assert_eq!(info["tables"][0]["name"], "mine");
        // Beside `DB#NAME`, a name setting may only repeat NAME, as in a bake: `Table.save(
        // "db#c", name="mine")` wrote table `c` and dropped `mine` without a word.
        let err = save_table(&t, format!("{db}#c"), other("c"), &named).unwrap_err();
        match err {
            Error::InvalidArgument { name, .. } => assert_eq!(name, "name"),
            e => panic!("{e}"),
        }
        assert_eq!(
            Store::open(&db).unwrap().tables().len(),
            2,
            "nothing written"
        );
        let same = SaveSettings {
            name: Some("c".into()),
            ..lossless()
        };
        let info = save_table(&t, format!("{db}#c"), other("c"), &same).unwrap();
        assert_eq!(info["tables"][0]["name"], "c");
    }

    #[test]
    fn bad_settings_and_outputs_name_their_field() {
        let d = TempDir::new("save-bad");
        let t = ct();
        let out = d.file("t.btdb");
        for (json, field) in [
            (r#"{"codec": "zip"}"#, "codec"),
            (r#"{"codec": "log16:x"}"#, "codec"),
            (r#"{"level": 30}"#, "level"),
            (r#"{"name": ""}"#, "name"),
            (r#"{"name": "a#b"}"#, "name"),
        ] {
            let s: SaveSettings = super::super::from_json(json).unwrap();
            match save_table(&t, &out, other("x"), &s) {
                Err(Error::InvalidArgument { name, .. }) => assert_eq!(name, field, "{json}"),
                r => panic!("{json}: {r:?}"),
            }
        }
        match save_table(&t, format!("{out}#"), other("x"), &lossless()) {
            Err(Error::InvalidArgument { name, .. }) => assert_eq!(name, "output"),
            r => panic!("{r:?}"),
        }
        assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 0);
        // Values beyond f16 are the codec's error, and the old file stays as it was.
        save_table(&t, &out, other("x"), &lossless()).unwrap();
        let big = t.with_values(vec![1e6; t.values().len()]).unwrap();
        let f16 = SaveSettings {
            codec: Some("f16".into()),
            ..SaveSettings::default()
        };
        let e = save_table(&big, &out, other("x"), &f16).unwrap_err();
        assert!(matches!(e, Error::Encode { .. }), "{e}");
        assert_eq!(bits(&stored(&out)), bits(t.values()));
    }

    /// The `.npy` export of a stored table imported on its own grid is the table, bit for bit:
    /// a plain table, and a packed one whose export fills the unstored nodes with NaN.
    #[test]
    fn an_exported_table_imports_bit_for_bit() {
        let d = TempDir::new("save-import");
        for (k, t) in [ct(), packed()].into_iter().enumerate() {
            let like = d.file(&format!("t{k}.btdb"));
            save_table(&t, &like, other("x"), &lossless()).unwrap();
            let st = Store::open(&like).unwrap().single().unwrap();
            let g = st.grid().unwrap();
            let off = tables::node_offset(&g);
            let npy = d.join(format!("t{k}.npy"));
            export::npy(&st, &npy, Some(&off)).unwrap();
            let (_, exported) = store::npy::read_f32(&npy).unwrap();
            assert_eq!(exported.iter().any(|x| x.is_nan()), g.layout().packed);
            let out = d.file(&format!("back{k}.btdb"));
            let info = import_npy(&npy, &like, &out, &lossless(), true).unwrap();
            let e = &info["tables"][0];
            assert_eq!(
                e["source"]["description"],
                format!("values from t{k}.npy on the grid of {like}")
            );
            assert_eq!(e["symmetry"], st.header().symmetry);
            assert_eq!(bits(&stored(&out)), bits(t.values()), "table {k}");
            let back = Store::open(&out).unwrap().single().unwrap().grid().unwrap();
            assert_eq!(back, g);
        }
    }

    /// A calibrated table's export is its values before the factors, and the import keeps the
    /// grid's calibration: lookups of the imported table are the original's.
    #[test]
    fn an_import_keeps_the_grids_calibration() {
        let d = TempDir::new("save-import-cal");
        let (t, _) = BakeRequest::new(r#"{"model": "ggx", "alpha": 0.3}"#)
            .grid("adaptive:24x12x7".parse().unwrap())
            .table(&Silent)
            .unwrap();
        assert!(t.grid().calibration().is_some());
        let like = d.file("g.btdb");
        save_table(&t, &like, other("x"), &lossless()).unwrap();
        let st = Store::open(&like).unwrap().single().unwrap();
        let npy = d.join("g.npy");
        export::npy(&st, &npy, None).unwrap();
        let out = d.file("back.btdb");
        let info = import_npy(&npy, &like, &out, &lossless(), true).unwrap();
        assert_eq!(info["tables"][0]["calibrated"], true);
        let back = Store::open(&out)
            .unwrap()
            .single()
            .unwrap()
            .to_table()
            .unwrap();
        assert_eq!(back.grid(), t.grid());
        assert_eq!(bits(back.values()), bits(t.values()));
        // Another material's values: without the like table's calibration, the grid is the
        // uncalibrated one and the values are stored as given.
        let other_out = d.file("other.btdb");
        let info = import_npy(&npy, &like, &other_out, &lossless(), false).unwrap();
        assert_eq!(info["tables"][0]["calibrated"], false);
        let back = Store::open(&other_out)
            .unwrap()
            .single()
            .unwrap()
            .to_table()
            .unwrap();
        assert_eq!(back.grid(), &t.grid().clone().without_calibration());
        assert_eq!(bits(back.values()), bits(t.values()));
    }

    fn f32_npy(path: &Path, shape: &[u64], values: &[f32]) {
        let mut b = store::npy::npy_header(shape);
        b.extend(values.iter().flat_map(|x| x.to_le_bytes()));
        std::fs::write(path, b).unwrap();
    }

    #[test]
    fn bad_imports_say_what_and_where() {
        let d = TempDir::new("save-import-bad");
        let t = ct();
        let like = d.file("ct.btdb");
        save_table(&t, &like, other("x"), &lossless()).unwrap();
        let shape: Vec<u64> = t.shape().unwrap().iter().map(|&s| s as u64).collect();
        let npy = d.join("v.npy");
        let out = d.file("out.btdb");
        let arg = |e: Error| match e {
            Error::InvalidArgument { name, msg } => (name, msg),
            e => panic!("{e}"),
        };
        let fmt = |e: Error| match e {
            Error::Format {
                file,
                field,
                offset,
                msg,
            } => (file, field, offset, msg),
            e => panic!("{e}"),
        };
        f32_npy(&npy, &shape, t.values());
        let (none, nope) = (d.file("none.btdb"), format!("{like}#nope"));
        for src in [
            r#"{"model": "lambert", "kd": 0.5}"#,
            "paper.bsdf",
            "m.binary",
            none.as_str(),
            nope.as_str(),
        ] {
            let (name, msg) = arg(import_npy(&npy, src, &out, &lossless(), true).unwrap_err());
            assert_eq!(name, "like", "{src}: {msg}");
        }
        // Not a brdftab file.
        let (name, _) =
            arg(import_npy(&npy, npy.to_str().unwrap(), &out, &lossless(), true).unwrap_err());
        assert_eq!(name, "like");
        let (name, _) =
            arg(import_npy(&npy, &like, npy.to_str().unwrap(), &lossless(), true).unwrap_err());
        assert_eq!(name, "output");

        let mut wrong = shape.clone();
        wrong.swap(0, 3);
        f32_npy(&npy, &wrong, t.values());
        let (file, field, _, msg) =
            fmt(import_npy(&npy, &like, &out, &lossless(), true).unwrap_err());
        assert_eq!(
            (file.as_str(), field.as_deref()),
            (npy.to_str().unwrap(), Some("shape"))
        );
        assert!(msg.contains(&format!("{:?}", t.shape().unwrap())), "{msg}");

        let mut v = t.values().to_vec();
        v[100] = f32::NAN;
        f32_npy(&npy, &shape, &v);
        let (_, field, offset, msg) =
            fmt(import_npy(&npy, &like, &out, &lossless(), true).unwrap_err());
        let h = NpyReader::open(&npy).unwrap().header().clone();
        assert_eq!(
            (field.as_deref(), offset),
            (Some("data"), Some(h.data_offset + 400))
        );
        assert!(msg.contains("NaN"), "{msg}");

        f32_npy(&npy, &shape, t.values());
        let b = std::fs::read(&npy).unwrap();
        std::fs::write(&npy, &b[..b.len() - 3]).unwrap();
        let (_, field, _, msg) = fmt(import_npy(&npy, &like, &out, &lossless(), true).unwrap_err());
        assert!(
            field.as_deref() == Some("data") && msg.contains("truncated"),
            "{msg}"
        );
        // Nothing was written.
        assert!(!Path::new(&out).exists());
    }
}
