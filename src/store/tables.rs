//! Storing [`Table`]s and [`Grid`]s: headers from grids, per-chunk predictor layouts, saving a
//! table (in memory or chunk by chunk), and getting a table's grid back from a file.

use std::path::Path;

use super::format::Source;
use super::{StoredTable, TableHeader, Writer, db};
use crate::codec::{self, Codec};
use crate::error::{Error, Result};
use crate::spec::ModelSpec;
use crate::table::{Grid, Table};

impl Source {
    /// The source of a table baked from a model spec.
    pub fn model(spec: &ModelSpec) -> Source {
        Source::Model {
            spec: serde_json::to_value(spec).unwrap_or(serde_json::Value::Null),
        }
    }

    /// The source of a table read from a measured file: its name and SHA-256.
    pub fn measured(path: impl AsRef<Path>) -> Result<Source> {
        use sha2::Digest;
        let path = path.as_ref();
        crate::files::require_regular(path)?;
        let mut f = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        let mut h = sha2::Sha256::new();
        std::io::copy(&mut f, &mut h).map_err(|e| Error::io(path, e))?;
        let sha: String = h.finalize().iter().map(|b| format!("{b:02x}")).collect();
        Ok(Source::Measured {
            file: path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            ),
            sha256: sha,
        })
    }
}

impl TableHeader {
    /// The header of a table on `grid`.
    pub fn for_grid(
        name: impl Into<String>,
        source: Source,
        grid: &Grid,
        codec: Codec,
    ) -> TableHeader {
        let s = grid.stored_shape();
        let shape = vec![
            s[0] as u64,
            s[1] as u64,
            s[2] as u64,
            s[3] as u64,
            grid.channels().len() as u64,
        ];
        let mut h = TableHeader::new(name, source, shape, grid.channels().clone(), codec);
        h.grid = serde_json::to_value(grid).unwrap_or(serde_json::Value::Null);
        h.parameterization = grid.param().name().into();
        h.symmetry = grid.symmetry().to_string();
        h.values = grid.stored_values() as u64;
        h.layout = chunk_layout(grid, 0);
        h
    }
}

/// The predictor layout of chunk `a` of `grid`: rows of stored axis 3 (× channels) in planes of
/// the stored axis-2 rows of that chunk.
pub fn chunk_layout(grid: &Grid, a: usize) -> codec::Layout {
    let l = grid.layout();
    codec::Layout::new(
        l.channels,
        l.shape[3],
        l.rows2(a.min(l.shape[0].saturating_sub(1))).1,
    )
}

/// Saves an in-memory table as `name` in the database (or single-table file) at `path`, encoding
/// its chunks in parallel. With `replace`, an existing table of that name is replaced.
pub fn save(
    path: impl AsRef<Path>,
    name: &str,
    source: Source,
    table: &Table,
    codec: Codec,
    replace: bool,
) -> Result<()> {
    let grid = table.grid();
    let header = TableHeader::for_grid(name, source, grid, codec);
    db::put(path, header, replace, |w| write_table_chunks(w, table))
}

/// [`save`] into a database, asking `progress` to stop while it waits for another writer's
/// lock and copies the other tables ([`db::put_with`]).
pub(crate) fn save_with(
    path: &Path,
    name: &str,
    source: Source,
    table: &Table,
    codec: Codec,
    replace: bool,
    progress: &dyn crate::progress::Progress,
) -> Result<()> {
    let header = TableHeader::for_grid(name, source, table.grid(), codec);
    db::put_with(path, header, replace, progress, |w| {
        write_table_chunks(w, table)
    })
}

/// Writes `table` as `name`, the one table of a new brdftab file that replaces whatever is at
/// `path` atomically (a failed write leaves the old file as it was), encoding its chunks in
/// parallel.
pub fn save_file(
    path: impl AsRef<Path>,
    name: &str,
    source: Source,
    table: &Table,
    codec: Codec,
) -> Result<()> {
    super::name::check("name", name)?;
    let mut w = Writer::create(path)?;
    w.begin_table(TableHeader::for_grid(name, source, table.grid(), codec))?;
    write_table_chunks(&mut w, table)?;
    w.end_table()?;
    w.finish()
}

/// Appends all chunks of `table` to a writer whose table is begun (encoded in parallel).
pub fn write_table_chunks(w: &mut Writer, table: &Table) -> Result<()> {
    let grid = table.grid();
    let chunks: Vec<(&[f32], codec::Layout)> = (0..grid.layout().chunk_count())
        .map(|a| (table.chunk(a), chunk_layout(grid, a)))
        .collect();
    w.chunks_par(&chunks)
}

impl StoredTable {
    /// The table's grid, checked against the stored shape and chunk lengths.
    pub fn grid(&self) -> Result<Grid> {
        let h = self.header();
        let bad = |msg: String| {
            Error::format(
                self.file(),
                Some(&format!("table `{}` grid", h.name)),
                None,
                msg,
            )
        };
        // Bound every size in the grid JSON by the (already validated) stored shape before the
        // grid allocates anything from them.
        let max = h
            .shape
            .iter()
            .copied()
            .max()
            .unwrap_or(0)
            .saturating_mul(4)
            .saturating_add(4);
        let sizes = crate::table::grid::json_sizes(&h.grid);
        if let Some(s) = sizes.iter().find(|&&s| s > max) {
            return Err(bad(format!(
                "axis size {s} does not fit the stored shape {:?}",
                h.shape
            )));
        }
        let grid: Grid = serde_json::from_value(h.grid.clone()).map_err(|e| bad(format!("{e}")))?;
        let s = grid.stored_shape();
        let want = [
            s[0] as u64,
            s[1] as u64,
            s[2] as u64,
            s[3] as u64,
            grid.channels().len() as u64,
        ];
        if h.shape != want || grid.layout().chunk_count() != self.chunk_count() {
            return Err(bad(format!(
                "grid stores {want:?}, the header says {:?}",
                h.shape
            )));
        }
        for a in 0..self.chunk_count() {
            if grid.layout().chunk_len(a) != self.chunk_values(a) {
                return Err(bad(format!(
                    "chunk {a} holds {} values, the grid needs {}",
                    self.chunk_values(a),
                    grid.layout().chunk_len(a)
                )));
            }
        }
        Ok(grid)
    }

    /// Decodes the whole table into memory.
    pub fn to_table(&self) -> Result<Table> {
        let grid = self.grid()?;
        Table::new(grid, self.read_all()?, self.header().name.clone())
    }
}

/// The node-offset function of a grid's stored layout, for the exports.
pub fn node_offset(grid: &Grid) -> impl Fn(&[usize]) -> Option<usize> + Sync + '_ {
    move |i: &[usize]| match i {
        [a, b, c, d] => grid.layout().offset([*a, *b, *c, *d]),
        _ => None,
    }
}

impl crate::table::ChunkLoader for StoredTable {
    /// Decodes the chunk (checksum checked) without going through the store's cache: the
    /// `TabulatedBrdf` keeps what it loads.
    fn load(&self, chunk: usize) -> Result<Vec<f32>> {
        self.decode_chunk(chunk)
    }
}

impl StoredTable {
    /// This table as a [`TabulatedBrdf`](crate::table::TabulatedBrdf) whose chunks are decoded
    /// on first touch (linear interpolation).
    pub fn brdf(&self) -> Result<crate::table::TabulatedBrdf> {
        let grid = self.grid()?;
        let desc = format!("table `{}` from {}", self.header().name, self.file());
        Ok(crate::table::TabulatedBrdf::lazy(
            grid,
            Box::new(self.clone()),
            desc,
        ))
    }
}

/// True when `path` starts with the brdftab file magic.
pub fn is_store_file(path: impl AsRef<Path>) -> bool {
    use std::io::Read;
    let mut m = [0u8; 8];
    crate::files::is_regular(path.as_ref())
        && std::fs::File::open(path)
            .and_then(|mut f| f.read_exact(&mut m))
            .is_ok()
        && m == super::format::MAGIC
}

/// Opens `FILE` (a single-table file) or `DB#NAME` (a table of a database) as a lazily decoded
/// [`TabulatedBrdf`](crate::table::TabulatedBrdf). With `eager`, every chunk is decoded now (in
/// parallel) and checked.
pub fn open_brdf(
    source: impl AsRef<std::ffi::OsStr>,
    eager: bool,
) -> Result<crate::table::TabulatedBrdf> {
    let (path, name) = super::name::parse_input_os("source", source.as_ref())?;
    open_brdf_at(path, name, eager)
}

/// [`open_brdf`] of table `name` (`None`: the file's single table) of the brdftab file at
/// `path`, taken as a path: never split at a `#` nor looked up as a `DB#NAME` string. What a
/// writer that knows both (a bake reading back its output) opens, whatever `#` the path holds
/// and whatever files lie beside it.
pub fn open_brdf_at(
    path: impl AsRef<Path>,
    name: Option<&str>,
    eager: bool,
) -> Result<crate::table::TabulatedBrdf> {
    let path = path.as_ref();
    let store = super::Store::open(path)?;
    let t = match name {
        Some(n) => store.table(n)?,
        None => store.single()?,
    };
    if eager {
        // Decoded in parallel into one array, which the table (and an exact kernel) keeps: the
        // chunks decoded apart and then concatenated held the table three times over.
        let grid = t.grid()?;
        let table = Table::new(
            grid,
            t.read_all()?,
            format!("table `{}` from {}", t.header().name, path.display()),
        )?;
        return Ok(crate::table::TabulatedBrdf::from_table(table));
    }
    t.brdf()
}
