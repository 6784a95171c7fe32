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
    save_table_with(table, output, source, settings, &crate::progress::Silent)
}

/// [`save_table`] for a host that may ask it to stop: into `DB#NAME`, while it waits for
/// another writer's lock and copies the database's other tables
/// ([`store::db::put_with`]).
///
/// # Errors
/// Those of [`save_table`], and [`Error::Cancelled`]: the output as
/// it was.
pub fn save_table_with(
    table: &Table,
    output: impl AsRef<OsStr>,
    source: store::Source,
    settings: &SaveSettings,
    progress: &dyn crate::progress::Progress,
) -> Result<serde_json::Value> {
    let codec = settings.codec()?;
    let (path, name) = match target(&output, settings.replace)? {
        BakeTarget::Db {
            path,
            name,
            replace,
        } => {
            bake::refuse_name_conflict(settings.name.as_deref(), &name)?;
            tables::save_with(&path, &name, source, table, codec, replace, progress)?;
            (path, name)
        }
        t => {
            let path = t.path().to_owned();
            crate::source::check_table_output(&path)?;
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
mod tests;
