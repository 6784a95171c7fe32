//! [`TabulatedBrdf`]: a table behind the [`Brdf`] trait.
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

use glam::{DVec2, DVec3};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

use crate::brdf::{BakeSource, Brdf, BrdfSample, Flags};
use crate::error::{Error, Result};
use crate::geometry::HalfDiff;
use crate::spectrum::Channels;
use crate::table::Table;
use crate::table::grid::{Grid, Param, Quantity};
use crate::table::kernel::{Kernel, LANES, Packed, project_out};
use crate::table::lookup::{Interp, Lookup, Prepared};
use crate::table::sampling::{SamplingResolution, TableSampler};

mod chunks;

/// Lookups per group in [`TabulatedBrdf::eval_batch`]'s two-phase loop.
const GROUP: usize = 8;

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

/// A dense table as a [`Brdf`]: nearest or multilinear lookup, chunks loaded lazily.
pub struct TabulatedBrdf {
    grid: Grid,
    lookup: Lookup,
    /// The fast linear lookup ([`super::kernel`]) of adaptive grids and of small MERL-style
    /// fixed grids, when it applies. Its lookups read `packed`, all chunks in one array loaded
    /// at first use: f16 codes for adaptive grids, whose `chunks` are then loaded only for other
    /// readers (nearest lookups, [`TabulatedBrdf::to_table`], [`BakeSource::stored_node`]), or the
    /// exact values, which `chunk` then serves instead of `chunks`.
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

    /// Evaluates `out.len() / channels` pairs. Linear lookups run in groups of [`GROUP`] in
    /// two phases — coordinates and corners for the whole group, with a prefetch of each
    /// lookup's cache lines, then the gathers — so that the group's memory accesses overlap
    /// instead of each lookup waiting for its own.
    fn eval_block(&self, wi: &[DVec3], wo: &[DVec3], out: &mut [f32]) {
        let c = self.lookup.channels();
        if let Some(k) = &self.kernel
            && self.interp == Interp::Linear
            && k.has_x8()
        {
            // Eight pairs per group in AVX2 lanes; the pairs the lanes leave, and the last
            // ones, one at a time (the same values).
            let values = self.packed();
            let n = out.len() / c;
            let whole = n - n % LANES;
            for s in (0..whole).step_by(LANES) {
                let og = &mut out[s * c..(s + LANES) * c];
                let left = k.eval_x8(&wi[s..], &wo[s..], og, values);
                if left != 0 {
                    for (j, oc) in og.chunks_exact_mut(c).enumerate() {
                        if left & (1 << j) != 0 {
                            self.eval(wi[s + j], wo[s + j], oc);
                        }
                    }
                }
            }
            for (j, oc) in out[whole * c..].chunks_exact_mut(c).enumerate() {
                self.eval(wi[whole + j], wo[whole + j], oc);
            }
            return;
        }
        if self.interp != Interp::Linear || self.kernel.is_some() {
            // Nearest lookups, and the kernel (its tables are cache resident: nothing to
            // prefetch), go one pair at a time.
            for (k, oc) in out.chunks_exact_mut(c).enumerate() {
                self.eval(wi[k], wo[k], oc);
            }
            return;
        }
        for (g, og) in out.chunks_mut(GROUP * c).enumerate() {
            let s = g * GROUP;
            let m = og.len() / c;
            let mut prep = [Prepared::Zero; GROUP];
            for k in 0..m {
                prep[k] = self.lookup.prepare(wi[s + k], wo[s + k], |a| self.chunk(a));
                prep[k].prefetch();
            }
            for (k, oc) in og.chunks_exact_mut(c).enumerate() {
                if !prep[k].gather(c, oc) {
                    self.eval(wi[s + k], wo[s + k], oc);
                } else if self.finish {
                    project_out(
                        self.grid.quantity(),
                        self.grid.calibration(),
                        wi[s + k],
                        wo[s + k],
                        oc,
                    );
                }
            }
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

    /// The node of stored coordinates `x` when `x` is one (to 1e-6 of a node spacing on every
    /// axis of size > 1).
    fn node_at(&self, x: [f64; 4]) -> Option<[usize; 4]> {
        let mut idx = [0usize; 4];
        for (d, ax) in self.grid.stored_axes().iter().enumerate() {
            if ax.size <= 1 {
                continue;
            }
            let s = ax.continuous(x[d]);
            let i = s.round();
            if !((s - i).abs() <= 1e-6) {
                return None;
            }
            let n = ax.size as f64;
            let i = if ax.periodic { i.rem_euclid(n) } else { i };
            if !(0.0..n).contains(&i) {
                return None;
            }
            idx[d] = i as usize;
        }
        Some(idx)
    }
}

impl Brdf for TabulatedBrdf {
    fn bake_source(&self) -> Option<&dyn BakeSource> {
        Some(self)
    }

    fn channels(&self) -> &Channels {
        self.grid.channels()
    }

    #[inline]
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        if let Some(k) = &self.kernel
            && self.interp == Interp::Linear
            && k.eval(wi, wo, out, self.packed())
        {
            return;
        }
        // Not a kernel table, a nearest lookup, or a pair beyond a resampled axis's cut.
        self.lookup
            .eval(self.interp, wi, wo, out, |a| self.chunk(a));
        if self.finish {
            project_out(
                self.grid.quantity(),
                self.grid.calibration(),
                wi,
                wo,
                &mut out[..self.lookup.channels()],
            );
        }
    }

    /// The first chunk-load error any lookup met (sticky, see the module docs); one atomic load
    /// while the table is healthy.
    #[inline]
    fn health(&self) -> Result<()> {
        if !self.failed.load(Ordering::Acquire) {
            return Ok(());
        }
        match self.error.lock() {
            Ok(e) => e.as_ref().map_or(Ok(()), |e| Err(e.replicate())),
            Err(_) => Err(Error::Unsupported(format!(
                "{}: a chunk failed to load",
                self.description
            ))),
        }
    }

    /// Only the symmetries the table stores are declared (a reduced table has them exactly).
    /// By quadrature to [`crate::analysis::albedo::Options::DATA`] (see [`Brdf::albedo`]).
    fn albedo(&self, wi: DVec3, out: &mut [f64]) {
        crate::brdf::albedo_with(self, wi, &crate::quadrature::Options::DATA, out)
    }

    fn flags(&self) -> Flags {
        let s = self.grid.symmetry();
        Flags {
            delta: false,
            reciprocal: s.reciprocal,
            isotropic: s.isotropic,
            bilateral: s.bilateral,
            transmission: false,
            lobes: crate::brdf::Lobes::GLOSSY,
        }
    }

    fn describe(&self) -> String {
        format!(
            "table [{}] {:?} of: {}",
            self.grid.summary(),
            self.interp,
            self.description
        )
    }

    /// Tabulated importance sampling of f_r·cos θi ([`TableSampler`]).
    fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
        self.sampler().sample(self, wo, u, weight)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.sampler().pdf(wi, wo)
    }

    /// A table's f_r at a wavelength interpolates its channels: one lookup for every
    /// wavelength.
    fn eval_at_wavelengths(&self, wi: DVec3, wo: DVec3, nm: &[f64], out: &mut [f32]) {
        crate::brdf::channels_at_wavelengths(self, wi, wo, nm, out)
    }

    /// A table's f_r at a wavelength interpolates its channels, so the weights do too: one
    /// draw and one lookup, whatever the number of wavelengths.
    fn sample_wavelengths(
        &self,
        wo: DVec3,
        u: DVec2,
        nm: &[f64],
        weight: &mut [f32],
    ) -> Option<BrdfSample> {
        let mut buf = [0.0f32; crate::spectrum::MAX_CHANNELS];
        let c = self.lookup.channels().min(buf.len());
        let s = self.sample(wo, u, &mut buf[..c])?;
        crate::brdf::mix_channels(self.channels(), &buf[..c], nm, weight);
        Some(s)
    }

    /// Draws a run of pairs, then evaluates their weights together ([`Brdf::eval_batch`]'s
    /// path: eight lookups per AVX2 group on kernel tables), then weighs them: the same values
    /// as [`TabulatedBrdf::sample`] pair by pair, at a batch lookup's cost for the weights.
    fn sample_batch(&self, wo: &[DVec3], u: &[DVec2], out: crate::batch::SampleOut<'_>) {
        use crate::batch::{SampleOut, drawable, no_sample};
        /// Pairs drawn before their weights are evaluated (on the stack: 3 kB of views).
        const RUN: usize = 128;
        let c = self.lookup.channels().max(1);
        let sampler = self.sampler();
        crate::batch::sample_blocks(c, wo, u, out, |wo, u, out| {
            let SampleOut { wi, pdf, weight } = out;
            let mut views = [DVec3::ZERO; RUN];
            for (s, ((wi, pdf), weight)) in wi
                .chunks_mut(RUN)
                .zip(pdf.chunks_mut(RUN))
                .zip(weight.chunks_mut(RUN * c))
                .enumerate()
            {
                let s = s * RUN;
                let m = wi.len();
                for k in 0..m {
                    let d = match drawable(wo[s + k], u[s + k]) {
                        true => sampler.draw(wo[s + k], u[s + k]),
                        false => None,
                    };
                    // A pair without a sample is evaluated at wi = 0 (f_r = 0, cheap) and
                    // zeroed below.
                    (wi[k], pdf[k], views[k]) = match d {
                        Some(d) => (d.wi, d.pdf, d.wo),
                        None => (DVec3::ZERO, 0.0, DVec3::Z),
                    };
                }
                self.eval_block(wi, &views[..m], weight);
                for (k, w) in weight.chunks_exact_mut(c).enumerate() {
                    if pdf[k] > 0.0 {
                        let d = crate::table::Draw {
                            wi: wi[k],
                            wo: views[k],
                            pdf: pdf[k],
                        };
                        d.weigh(w);
                    } else {
                        no_sample(&mut wi[k], &mut pdf[k], w);
                    }
                }
            }
        });
    }

    /// Parallel (rayon) above 16384 pairs, sequential below.
    fn eval_batch(&self, wi: &[DVec3], wo: &[DVec3], out: &mut [f32]) {
        let c = self.lookup.channels();
        let n = crate::brdf::check_batch(wi, wo, out, c.max(1));
        crate::batch::blocks(&mut out[..n * c], c, |s, o| {
            self.eval_block(&wi[s..], &wo[s..], o)
        });
    }
}

impl BakeSource for TabulatedBrdf {
    /// The node at `hd` as stored, negative (unmeasured) values included, on `halfdiff` grids.
    fn stored_node(&self, hd: HalfDiff, out: &mut [f32]) -> bool {
        let c = self.lookup.channels();
        // A stored quantity other than f_r: such nodes are evaluated, not copied.
        if self.grid.param() != Param::HalfDiff || out.len() < c || self.finish {
            return false;
        }
        let x = crate::table::symmetry::canonical_half_diff(self.grid.symmetry(), hd);
        let Some(idx) = self.node_at(x) else {
            return false;
        };
        let Some(off) = self.grid.layout().offset_in_chunk(idx) else {
            return false;
        };
        let Some(v) = self.chunk(idx[0]).get(off..off + c) else {
            return false;
        };
        out[..c].copy_from_slice(v);
        let neg = self.unmeasured_of(idx[0]);
        let first = neg.partition_point(|e| (e.0 as usize) < off);
        for &(k, x) in neg[first..].iter().take_while(|e| (e.0 as usize) < off + c) {
            out[k as usize - off] = x;
        }
        true
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
