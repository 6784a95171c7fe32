//! Baking: evaluating any [`Brdf`] on a [`Grid`], chunk by chunk.
//!
//! [`bake_chunks`] produces the stored values one chunk (slab of stored axis 0, see
//! [`Layout`](super::Layout)) at a time, in order, and hands each to a sink — a streaming writer
//! never needs the whole table in memory. Consecutive chunks are grouped up to
//! [`BakeOptions::memory_budget`] bytes and the group is evaluated in parallel (rayon) row by row
//! (a row = one (axis 1, axis 2) node with every axis-3 node and channel, λ innermost), so peak
//! memory is about one group. [`bake`] collects everything into an in-memory [`Table`].
//!
//! Before a reduced grid is baked its symmetries are verified on the source
//! ([`symmetry::verify`]); a violation is an error unless [`BakeOptions::force`] is set.
//!
//! A node's value is f at the node's representative pair ([`pair_of`]) — or, on
//! a `halfdiff` grid whose nodes the source itself stores ([`BakeSource::stored_node`](crate::brdf::BakeSource::stored_node): a MERL file
//! on [`Grid::merl`], a table on its own grid), the stored value verbatim, including cells whose
//! centre lies below the horizon and negative markers of unmeasured cells; with
//! `supersample = k > 1` it is the mean of k^d stratified, jittered samples over the node's cell
//! (d = stored angular axes of size > 1, cell = ±½ node spacing, which on a
//! [`Nodes::CellStart`](super::Nodes) axis is the node's own cell [i/n, (i+1)/n) of u) — a box
//! prefilter for lobes narrower than a cell.

use rayon::prelude::*;
use std::time::Instant;

use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::geometry::HalfDiff;
use crate::rng::Pcg32;
use crate::spectrum::MAX_CHANNELS;
use crate::table::grid::{Grid, Nodes, Param, Quantity, StoredAxis};
use crate::table::horizon::HorizonFill;
use crate::table::symmetry::{self, Symmetry};
use crate::table::{Table, pair_of};

/// Progress callback: (values done, values total).
pub type Progress<'a> = &'a (dyn Fn(u64, u64) + Sync);

/// The largest `supersample` of a bake: 64^d samples per node is already far past what any
/// lobe needs.
pub const MAX_SUPERSAMPLE: usize = 64;

/// Options of [`bake_chunks`] and [`bake`].
#[derive(Clone, Copy)]
pub struct BakeOptions<'a> {
    /// Samples per stored axis and cell (1 = the node value only).
    pub supersample: usize,
    /// Bake even when the source breaks the grid's declared symmetry.
    pub force: bool,
    /// Relative tolerance of the symmetry verification.
    pub tolerance: f64,
    /// Bytes of values evaluated together in parallel (at least one chunk).
    pub memory_budget: usize,
    /// Called after every chunk.
    pub progress: Option<Progress<'a>>,
    /// Asked before every row of values: true stops the bake with [`Error::Cancelled`].
    pub cancel: Option<&'a (dyn Fn() -> bool + Sync)>,
}

impl Default for BakeOptions<'_> {
    fn default() -> Self {
        BakeOptions {
            supersample: 1,
            force: false,
            tolerance: symmetry::DEFAULT_TOLERANCE,
            memory_budget: 64 << 20,
            progress: None,
            cancel: None,
        }
    }
}

/// What a bake did.
#[derive(Debug, Clone, Default)]
pub struct BakeStats {
    /// Stored values produced.
    pub values: u64,
    /// Wall-clock seconds (excluding the symmetry check).
    pub seconds: f64,
    /// The symmetry violation that `force` overrode, if any.
    pub forced: Option<String>,
}

/// Checks the source against the grid: channel count and declared symmetry.
/// Refuses a source whose channels are not a valid set
/// ([`Channels::validate`](crate::spectrum::Channels::validate)), and one with a delta lobe — a
/// mirror or refractor, alone or as a term of a sum:
/// a table (or an RGL or MERL file) holds f_r values, which a Dirac delta has none of, so its
/// table would silently lack the lobe (a sum's smooth terms alone, or zeros). Every bake and
/// conversion checks this before any work.
pub fn tabulable(brdf: &dyn Brdf) -> Result<()> {
    // A `Brdf` of a caller's own may declare channels no table can hold (none, NaN nm).
    brdf.channels().validate()?;
    let f = brdf.flags();
    match (f.delta, f.lobes.delta) {
        (true, _) => Err(Error::Unsupported(
            "a delta (mirror/refractor) BRDF cannot be tabulated".into(),
        )),
        (false, true) => Err(Error::Unsupported(
            "a sum with a delta term (mirror/refractor) cannot be tabulated: a table holds \
             f_r values, which the delta has none of; tabulate the other terms and add the \
             delta in the renderer"
                .into(),
        )),
        _ => Ok(()),
    }
}

fn check(brdf: &dyn Brdf, grid: &Grid, opts: &BakeOptions) -> Result<Option<String>> {
    if brdf.channels().len() != grid.channels().len() {
        return Err(Error::arg(
            "grid",
            format!(
                "the source has {} channels, the grid {}",
                brdf.channels().len(),
                grid.channels().len()
            ),
        ));
    }
    tabulable(brdf)?;
    if !(1..=MAX_SUPERSAMPLE).contains(&opts.supersample) {
        return Err(Error::arg(
            "supersample",
            format!("{}: must be in 1..={MAX_SUPERSAMPLE}", opts.supersample),
        ));
    }
    if grid.symmetry() == Symmetry::NONE {
        return Ok(None);
    }
    match symmetry::verify(brdf, grid.symmetry(), opts.tolerance) {
        Ok(()) => Ok(None),
        Err(e) if opts.force => Ok(Some(e.to_string())),
        Err(e) => Err(e),
    }
}

/// Bakes `brdf` on `grid`, calling `sink(chunk_index, values)` for every chunk in order
/// (`values.len() == grid.layout().chunk_len(chunk_index)`). An error from the sink stops the
/// bake and is returned.
pub fn bake_chunks(
    brdf: &dyn Brdf,
    grid: &Grid,
    opts: &BakeOptions,
    mut sink: impl FnMut(usize, &[f32]) -> Result<()>,
) -> Result<BakeStats> {
    let forced = check(brdf, grid, opts)?;
    let start = Instant::now();
    let layout = grid.layout();
    let total = layout.len() as u64;
    let c = layout.channels;
    let s3 = layout.shape[3];
    let row_len = s3 * c;
    let axes = grid.stored_axes().clone();
    // A source that stores this grid's first node stores them all (it is on the same grid):
    // its nodes are copied, not evaluated. Asked once, so other sources pay nothing.
    let native = grid.param() == Param::HalfDiff
        && grid.quantity() == Quantity::Fr
        && opts.supersample <= 1
        && !layout.is_empty()
        && brdf
            .bake_source()
            .is_some_and(|b| b.stored_node(half_diff(grid.node_angles([0; 4])), &mut vec![0.0; c]));
    // Nodes beyond the horizon of f_r cos θi cos θo tables are extrapolated (`horizon`).
    let mut horizon = HorizonFill::new(grid);
    let budget = (opts.memory_budget / 4).max(1);
    let mut buf: Vec<f32> = Vec::new();
    let mut a = 0;
    let n0 = layout.chunk_count();
    let cancelled = || opts.cancel.is_some_and(|c| c());
    while a < n0 {
        // Group chunks a..e up to the budget.
        let mut e = a + 1;
        let mut len = layout.chunk_len(a);
        while e < n0 && len + layout.chunk_len(e) <= budget {
            len += layout.chunk_len(e);
            e += 1;
        }
        buf.clear();
        buf.resize(len, 0.0);
        // Row r of the group → (chunk, row within chunk).
        let mut row_starts = Vec::with_capacity(e - a + 1);
        let mut acc = 0;
        for k in a..e {
            row_starts.push(acc);
            acc += layout.rows_in_chunk(k);
        }
        row_starts.push(acc);
        if row_len > 0 {
            crate::par::install(|| {
                buf.par_chunks_mut(row_len)
                    .with_min_len(8)
                    .enumerate()
                    .for_each(|(gr, row)| {
                        // A cancelled bake skips its remaining rows (one per thread finishes).
                        if cancelled() {
                            return;
                        }
                        let k = row_starts.partition_point(|&s| s <= gr) - 1;
                        let chunk = a + k;
                        let (p, b) = layout.row_node(chunk, gr - row_starts[k]);
                        for q in 0..s3 {
                            let out = &mut row[q * c..(q + 1) * c];
                            let idx = [chunk, p, b, q];
                            if native
                                && brdf.bake_source().is_some_and(|b| {
                                    b.stored_node(half_diff(grid.node_angles(idx)), out)
                                })
                            {
                                for v in out.iter_mut() {
                                    if !v.is_finite() {
                                        *v = 0.0;
                                    }
                                }
                                continue;
                            }
                            eval_node(brdf, grid, &axes, idx, opts.supersample, out);
                        }
                    })
            });
        }
        if cancelled() {
            return Err(Error::Cancelled);
        }
        let mut off = 0;
        let mut done = layout.chunk_range(a).start as u64;
        for k in a..e {
            let l = layout.chunk_len(k);
            if let Some(h) = horizon.as_mut() {
                h.fill(k, &mut buf[off..off + l]);
            }
            if cancelled() {
                return Err(Error::Cancelled);
            }
            sink(k, &buf[off..off + l])?;
            off += l;
            done += l as u64;
            if let Some(p) = opts.progress {
                p(done, total);
            }
        }
        a = e;
    }
    Ok(BakeStats {
        values: total,
        seconds: start.elapsed().as_secs_f64(),
        forced,
    })
}

/// The most values a table built whole in memory ([`bake`]: adaptive and calibrated tables,
/// raw files) may have: 2^30, 4 GiB of f32 — 240× the largest default table. Streamed bakes
/// ([`bake_chunks`]) are bounded by the store file's limit instead. A larger grid (an adaptive
/// `10000000×8×8`: 1.9 G values) aborted the process when its allocation failed, or was killed
/// by the system, rather than failing.
pub const MAX_IN_MEMORY_VALUES: usize = 1 << 30;

/// The error of a table too large to build in memory.
pub(crate) fn too_large(n: usize) -> Error {
    Error::arg(
        "grid",
        format!(
            "{n} values ({:.1} GB of f32): more than the {MAX_IN_MEMORY_VALUES} a table built in \
             memory may hold",
            n as f64 * 4e-9
        ),
    )
}

/// Bakes `brdf` on `grid` into an in-memory [`Table`].
pub fn bake(brdf: &dyn Brdf, grid: &Grid, opts: &BakeOptions) -> Result<(Table, BakeStats)> {
    // The whole table in memory: a grid too large for it is an error, not an abort.
    let n = grid.stored_values();
    let mut values = Vec::new();
    if n > MAX_IN_MEMORY_VALUES || values.try_reserve_exact(n).is_err() {
        return Err(too_large(n));
    }
    let report = bake_chunks(brdf, grid, opts, |_, v| {
        values.extend_from_slice(v);
        Ok(())
    })?;
    Ok((Table::new(grid.clone(), values, brdf.describe())?, report))
}

/// Stored `halfdiff` coordinates as [`HalfDiff`] angles.
fn half_diff(c: [f64; 4]) -> HalfDiff {
    HalfDiff {
        theta_h: c[0],
        phi_h: c[1],
        theta_d: c[2],
        phi_d: c[3],
    }
}

/// The value of one stored node (all channels) into `out`.
fn eval_node(
    brdf: &dyn Brdf,
    grid: &Grid,
    axes: &[StoredAxis; 4],
    idx: [usize; 4],
    k: usize,
    out: &mut [f32],
) {
    let param = grid.param();
    // The factor of the stored quantity at a (lifted) pair.
    let weight = |wi: glam::DVec3, wo: glam::DVec3| grid.quantity().factor(wi.z, wo.z);
    if k <= 1 {
        let (wi, wo) = pair_of(param, grid.node_angles(idx));
        brdf.eval(wi, wo, out);
        let w = weight(wi, wo);
        for v in out.iter_mut() {
            *v = if v.is_finite() {
                (*v as f64 * w) as f32
            } else {
                0.0
            };
        }
        return;
    }
    // Stratified jittered samples over the node's cell on every axis of size > 1: ±½ in node
    // index on every placement. (On a `CellStart` axis node i sits at the centre of cell i, so
    // ±½ *is* cell i, [i/n, (i+1)/n) of u: `coord` adds the half; sampling [i, i + 1) had
    // averaged cells i and i + 1, half each, on a MERL grid.)
    let active: Vec<usize> = (0..4).filter(|&d| axes[d].size > 1).collect();
    let cell = |d: usize| -> (f64, f64) {
        let i = idx[d] as f64;
        (i - 0.5, i + 0.5)
    };
    let c = out.len().min(MAX_CHANNELS);
    let mut acc = [0.0f64; MAX_CHANNELS];
    let mut f = [0.0f32; MAX_CHANNELS];
    let seed = idx.iter().fold(0x9E37_79B9_7F4A_7C15u64, |h, &i| {
        (h ^ i as u64).wrapping_mul(0x1000_0000_01b3)
    });
    let mut rng = Pcg32::new(seed);
    let total = k.pow(active.len() as u32);
    for s in 0..total {
        let mut coords = grid.node_angles(idx);
        let mut rest = s;
        for &d in &active {
            let j = rest % k;
            rest /= k;
            let (lo, hi) = cell(d);
            let t = lo + (hi - lo) * ((j as f64 + rng.next_f64()) / k as f64);
            let ax = &axes[d];
            let n = ax.size as f64;
            let t = match (ax.periodic, ax.nodes) {
                (true, _) => t,
                (false, Nodes::Centers | Nodes::CellStart) => t.clamp(-0.5, n - 0.5),
                (false, Nodes::Edges) => t.clamp(0.0, n - 1.0),
            };
            coords[d] = ax.coord(t);
        }
        let (wi, wo) = pair_of(param, coords);
        brdf.eval(wi, wo, &mut f[..c]);
        let w = weight(wi, wo);
        for ch in 0..c {
            if f[ch].is_finite() {
                acc[ch] += f[ch] as f64 * w;
            }
        }
    }
    for ch in 0..c {
        out[ch] = (acc[ch] / total as f64) as f32;
    }
}
