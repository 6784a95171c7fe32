//! [`TabulatedBrdf`]: a table behind the [`Brdf`](crate::Brdf) trait.
//!
//! Values live in chunks (slabs of stored axis 0, see [`Layout`](super::Layout)), each in a
//! `OnceLock<Arc<[f32]>>`. A table built from an in-memory [`Table`] has every chunk set; one
//! built with [`TabulatedBrdf::lazy`] asks a [`ChunkLoader`] (e.g. the file store's decoder) for
//! a chunk the first time a lookup touches it. After that first touch a read is one atomic load
//! — no lock, no allocation.
//!
//! **Load failures.** `eval` cannot return an error. When a chunk fails to load (I/O error,
//! checksum, wrong length) the chunk is marked empty, its corners contribute 0 to every lookup
//! (so a lookup whose corners all lie in a failed chunk writes 0; a table with a kernel, whose
//! lookups read one packed array of every chunk, writes 0 for every lookup), and the table
//! enters a sticky
//! *failed* state that keeps the first error: [`Brdf::health`] (one atomic load while the table
//! is healthy) returns it from then on, for the life of the table. A renderer that calls `eval`
//! pair by pair checks `health()` after each batch (or frame); every host does so after each
//! batch (the CLI's `eval`/`pdf`/`sample`, the C ABI's `brdftab_eval`/`_pdf`/`_sample`, the
//! Python methods), and every writer (bake, convert, export) before it commits a file, so a
//! corrupt table is an error wherever it is read. [`TabulatedBrdf::load_all`] (or an eager
//! open) gets the error up front, with the loader's own variant (a checksum failure stays
//! [`Error::Checksum`]). Lookups do not retry failed chunks.
//!
//! **Negative stored values** mark unmeasured data (a MERL file's −1 cells, kept by
//! [`MerlBrdf::to_table`](crate::measured::MerlBrdf::to_table) and by bakes of such a file on
//! its own grid). A BRDF is never negative, so when a chunk is loaded they are set aside and
//! the lookup sees 0 there: a *nearest* lookup of an unmeasured cell gives 0, and a *linear*
//! lookup next to one blends towards 0 over the half cell between the nodes (measured values
//! near the unmeasured region are darkened, none is made up). The set-aside values stay with
//! the table: [`BakeSource::stored_node`] and [`TabulatedBrdf::to_table`] give them back, so a table
//! converts back to the MERL file it came from. Below the horizon `eval` is 0 as for every
//! `Brdf`; a node whose centre pair has a direction below the horizon still holds its stored
//! value and is interpolated with its neighbours for pairs above it.
//!
//! [`Brdf::health`]: crate::Brdf::health
//! [`BakeSource::stored_node`]: crate::brdf::BakeSource::stored_node

use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex, OnceLock};

use crate::error::{Error, Result};
use crate::table::Table;
use crate::table::grid::{Grid, Quantity};
use crate::table::kernel::{Kernel, Packed};
use crate::table::lookup::{Interp, Lookup};
use crate::table::sampling::{SamplingResolution, TableSampler};

mod chunks;
mod eval;
mod stored;

/// Supplies the values of a chunk on demand (decoding, reading from disk, ...).
pub trait ChunkLoader: Send + Sync {
    /// The values of chunk `chunk`: exactly `grid.layout().chunk_len(chunk)` of them.
    fn load(&self, chunk: usize) -> Result<Vec<f32>>;
}

impl<T: ChunkLoader + ?Sized> ChunkLoader for Arc<T> {
    fn load(&self, chunk: usize) -> Result<Vec<f32>> {
        (**self).load(chunk)
    }
}

impl<T: ChunkLoader + ?Sized> ChunkLoader for Box<T> {
    fn load(&self, chunk: usize) -> Result<Vec<f32>> {
        (**self).load(chunk)
    }
}

/// The negative values of a chunk, (offset in the chunk, value), in order.
type Unmeasured = Box<[(u32, f32)]>;

/// A dense table as a [`Brdf`](crate::Brdf): nearest or multilinear lookup, chunks loaded lazily.
pub struct TabulatedBrdf {
    grid: Grid,
    lookup: Lookup,
    /// The fast linear lookup ([`super::kernel`]) of adaptive grids and of small MERL-style
    /// fixed grids, when it applies. Its lookups read `packed`, all chunks in one array loaded
    /// at first use: f16 codes for adaptive grids, whose `chunks` are then loaded only for other
    /// readers (nearest lookups, [`TabulatedBrdf::to_table`], [`BakeSource::stored_node`]), or the
    /// exact values, which `chunk` then serves instead of `chunks`.
    ///
    /// [`BakeSource::stored_node`]: crate::brdf::BakeSource::stored_node
    kernel: Option<Kernel>,
    /// Every chunk, contiguous and packed (tables with a kernel only), loaded on first use.
    packed: OnceLock<Packed>,
    chunks: Box<[OnceLock<Arc<[f32]>>]>,
    /// Per chunk, the negative stored values (offset in the chunk, value) that `chunks` holds as
    /// 0; set when the chunk is loaded (see the module docs).
    unmeasured: Box<[OnceLock<Unmeasured>]>,
    loader: Option<Box<dyn ChunkLoader>>,
    interp: Interp,
    /// The values are not f_r ([`Quantity`]): general lookups divide by the quantity's factor
    /// (the kernel does so itself).
    project: bool,
    /// The values are not f_r or the grid has an albedo calibration: general lookups finish
    /// with [`project_out`].
    finish: bool,
    description: String,
    error: Mutex<Option<Error>>,
    /// Importance sampling distributions, built on first `sample`/`pdf` (see [`super::sampling`]).
    /// Set (once, never cleared) when `error` is: the cheap test of [`Brdf::health`].
    ///
    /// [`Brdf::health`]: crate::Brdf::health
    failed: AtomicBool,
    sampler: OnceLock<TableSampler>,
}

impl std::fmt::Debug for TabulatedBrdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TabulatedBrdf")
            .field("grid", &self.grid.summary())
            .field("interp", &self.interp)
            .field("description", &self.description)
            .finish()
    }
}

impl TabulatedBrdf {
    /// A tabulated BRDF over an in-memory table (every chunk present), linear interpolation.
    pub fn from_table(table: Table) -> TabulatedBrdf {
        let (grid, mut values, description) = table.into_parts();
        let l = grid.layout();
        let kernel = Kernel::new(&grid);
        let project = grid.quantity() != Quantity::Fr;
        let grid_calibrated = grid.calibration().is_some();
        let mut unmeasured = Vec::with_capacity(l.chunk_count());
        let mut chunks = Vec::with_capacity(l.chunk_count());
        for i in 0..l.chunk_count() {
            let v = &mut values[l.chunk_range(i)];
            unmeasured.push(OnceLock::from(set_aside_negatives(v, project)));
            // An exact kernel's array serves as the chunks (`chunk`).
            chunks.push(match &kernel {
                Some(k) if k.exact_values() => OnceLock::new(),
                _ => OnceLock::from(Arc::<[f32]>::from(&*v)),
            });
        }
        // The table's own array becomes an exact kernel's (no second copy of it).
        let packed = match &kernel {
            Some(k) => OnceLock::from(Packed::for_kernel_owned(k, values)),
            None => OnceLock::new(),
        };
        TabulatedBrdf {
            lookup: Lookup::new(&grid),
            kernel,
            packed,
            grid,
            chunks: chunks.into(),
            unmeasured: unmeasured.into(),
            loader: None,
            interp: Interp::Linear,
            project,
            finish: project || grid_calibrated,
            description,
            error: Mutex::new(None),
            failed: AtomicBool::new(false),
            sampler: OnceLock::new(),
        }
    }

    /// A tabulated BRDF whose chunks `loader` supplies on first use, linear interpolation.
    pub fn lazy(
        grid: Grid,
        loader: Box<dyn ChunkLoader>,
        description: impl Into<String>,
    ) -> TabulatedBrdf {
        let chunks = (0..grid.layout().chunk_count())
            .map(|_| OnceLock::new())
            .collect();
        let unmeasured = (0..grid.layout().chunk_count())
            .map(|_| OnceLock::new())
            .collect();
        let project = grid.quantity() != Quantity::Fr;
        let grid_calibrated = grid.calibration().is_some();
        TabulatedBrdf {
            lookup: Lookup::new(&grid),
            kernel: Kernel::new(&grid),
            packed: OnceLock::new(),
            grid,
            chunks,
            unmeasured,
            loader: Some(loader),
            interp: Interp::Linear,
            project,
            finish: project || grid_calibrated,
            description: description.into(),
            error: Mutex::new(None),
            failed: AtomicBool::new(false),
            sampler: OnceLock::new(),
        }
    }

    /// The same with interpolation `interp`.
    pub fn with_interp(mut self, interp: Interp) -> Self {
        self.set_interp(interp);
        self
    }

    /// Sets the interpolation.
    pub fn set_interp(&mut self, interp: Interp) {
        self.interp = interp;
        self.sampler = OnceLock::new();
    }

    /// The importance sampler of [`Brdf::sample`]/[`Brdf::pdf`], built on first use by
    /// [`TableSampler::for_source`]: [`SamplingResolution::default`] (isotropic tables),
    /// [`SamplingResolution::binned`] (isotropic tables read with nearest lookups) or
    /// [`SamplingResolution::anisotropic`], with twice the θh nodes for a sharp peak and
    /// finer views for a lobe that changes shape between them.
    ///
    /// [`Brdf::sample`]: crate::Brdf::sample
    /// [`Brdf::pdf`]: crate::Brdf::pdf
    pub fn sampler(&self) -> &TableSampler {
        self.sampler.get_or_init(|| {
            let iso = self.grid.symmetry().isotropic;
            TableSampler::for_source(self, iso, self.interp == Interp::Nearest)
        })
    }

    /// Builds the sampler now with resolution `res` (replacing any built one).
    pub fn set_sampling_resolution(&mut self, res: &SamplingResolution) {
        let s = TableSampler::build(self, self.grid.symmetry().isotropic, res);
        self.sampler = OnceLock::from(s);
    }

    /// The interpolation a table opens with unless told otherwise: nearest when an axis holds
    /// cells rather than nodes ([`Nodes::CellStart`](super::Nodes), the MERL grid: a MERL reader
    /// looks such values up by cell, so nearest reproduces the source), linear otherwise.
    pub fn default_interp(&self) -> Interp {
        Interp::default_for(self.grid())
    }

    /// The interpolation in use.
    pub fn interp(&self) -> Interp {
        self.interp
    }

    /// The grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// The table as a GPU or JIT host evaluates it, for this BRDF's interpolation
    /// ([`super::device::DeviceLayout`]; loads every chunk).
    ///
    /// # Errors
    /// A chunk that does not load, or [`Error::Unsupported`] (see
    /// [`super::device::DeviceLayout::new`]).
    pub fn device_layout(&self) -> Result<super::device::DeviceLayout> {
        super::device::DeviceLayout::from_table(self.to_table()?, self.interp)
    }

    /// The whole table in memory as stored (loads every chunk; negative values included).
    pub fn to_table(&self) -> Result<Table> {
        self.load_all()?;
        let mut v = Vec::with_capacity(self.grid.stored_values());
        for i in 0..self.chunks.len() {
            let start = v.len();
            v.extend_from_slice(self.chunk(i));
            for &(k, x) in self.unmeasured_of(i) {
                v[start + k as usize] = x;
            }
        }
        Table::new(self.grid.clone(), v, self.description.clone())
    }
}

/// Replaces the negative values of `v` by 0 and returns them (offset, value), in order; keeps
/// them (and returns none) for values of another [`Quantity`] than f_r (`projected`), whose negative
/// values are nodes beyond the horizon extrapolated below 0, not unmeasured cells.
fn set_aside_negatives(v: &mut [f32], projected: bool) -> Unmeasured {
    let mut out = Vec::new();
    if projected {
        return out.into();
    }
    for (k, x) in v.iter_mut().enumerate() {
        if *x < 0.0 {
            out.push((k as u32, *x));
            *x = 0.0;
        }
    }
    out.into()
}
