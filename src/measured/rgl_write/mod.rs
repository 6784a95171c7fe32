//! Writing RGL-EPFL `.bsdf` files (Dupuy & Jakob 2018) from any [`Brdf`]: the one measured
//! format pbrt-v4's `measured` material and Mitsuba 3's `measured` plugin load natively.
//!
//! A `.bsdf` file does not store reflectance on a fixed grid: it stores the material's own
//! *adaptive parameterization* and the reflectance sampled through it. Writing one therefore
//! rebuilds that parameterization from the source, in the order the paper acquires it:
//!
//! 1. [`ndf`]: the microfacet distribution D recovered from the source's retro-reflection
//!    f(ω, ω) by power iteration (Dupuy et al. 2015: D is the eigenvector of
//!    D(ω) ∝ f(ω, ω) cos θ σ(ω)), and its projected area σ(ω) = ∫ D(m) max(0, m·ω) dm;
//! 2. [`warps`]: per incident direction (φi, θi), the visible-normal density
//!    D(m) max(0, m·ωi) on the (θ, φ) unit square (with the square's Jacobian 2π² u sin θ), built
//!    into the reader's own marginal-conditional warp;
//! 3. [`values`]: the reflectance sampled on an N × N grid of the warp's *input* square: each grid
//!    point is warped to a half vector m, ωo = reflect(ωi, m), and the file stores
//!    f_r·cos θo · 4σ(ωi) / D(m) (the `jacobian` = 1 convention: readers multiply by
//!    D(m) / (4σ(ωi)), interpolated from the same tables, so at the grid points they return
//!    exactly f_r·cos θo), clipped at 0 as the readers clip;
//! 4. the `luminance` table (Rec. 709 Y of the stored values; for spectra their photometric Y
//!    under D65, [`ndf::luminance_weights`]) that the readers sample by, and [`container`] lays
//!    the fields out as the published files do.
//!
//! [`report()`] measures a written file against its source with brdftab's own reader.
//!
//! The positions in step 3 are found with the reader's warp code itself
//! ([`rgl`](super::rgl)), so writer and reader agree on where every stored value lives.
//!
//! Defaults (measured, see the tests and BENCHMARKS.md "Written files placed where they are
//! wrong"): an isotropic source's incident elevations are placed by [`elevations`] — from 16
//! even in cos θi, split where the file's own reader is farthest from the source over the whole
//! domain, up to 32 within [`PLACED_BYTES`] — at N = 64, or at N = 128 when a figure stays past
//! its bar, 128 does better and 16 elevations of it fit the budget; an anisotropic source's
//! azimuths and elevations are placed together by [`azimuths`] — from 9 φi evenly over [−π, π]
//! (no symmetry reduction assumed) and 16 θi even in cos θi, split where the file is farthest
//! from the source, at N = 64 on 64 × 64 warps ([`GRID_VNDF`]) within [`PLACED_BYTES`] (its
//! error lies mostly in the interpolation over azimuths, which no count that fits brings
//! within the grazing band's bar: BENCHMARKS.md "Anisotropic files placed over azimuths and
//! elevations"); an isotropic source gets φi = 0. Warps are otherwise 128 × 128, NDF and σ on
//! 128 elevations (2 identical azimuth rows when isotropic, 64 rows over [−π, π] otherwise). One fixed spacing served no source over the whole domain:
//! 16 elevations even in cos θi left a Lambertian's grazing band 6.3 % off and Cook-Torrance
//! gold's albedo 4.5 % off at 89°; even in θi, a Cook-Torrance's grazing band 10 %. A given
//! count of elevations (`theta_i`) is even in cos θi as before. The published files' layout
//! (N = 32, the database's 8 non-uniform elevations, asked for with 8) serves measurements,
//! whose parameterization follows the material, but it interpolates analytic lobes poorly over
//! θi: Cook-Torrance m = 0.3 gold measured 3.6% with it, 1.3% with 16 elevations at N = 32,
//! 0.35% at N = 64 (the metric of [`report()`]). `.bsdf` sources are instead resampled into
//! their own parameterization ([`Options::reuse_source_file`]): same elevations, NDF, warps and N, and
//! the stored values at below-horizon grid points kept; where the source evaluates to the
//! file's own values at every grid point (it is the file), they are copied as stored, so a
//! re-encoded file is the original's table exactly (it used to evaluate them clipped at 0,
//! which brightened dark channels by up to 13 % in albedo).
//!
//! Renderers: Mitsuba 3's `measured` plugin loads RGB files in its RGB variants and spectral files
//! in its spectral variants (checked by `bindings/python/tests/test_rgl_writer_mitsuba.py`).
//! pbrt-v4's `measured` material reads only `spectra` + `wavelengths` (write spectral sources,
//! e.g. specs evaluated at wavelengths), supports no φ reduction (these files have none) and
//! conditions the tensor on its own `wo` (the camera side): for non-reciprocal sources the two
//! renderers therefore see the file with the directions swapped.
//!
//! Choices where the source has no measurement to offer:
//! - the θi = 90° slice evaluates the source at θi = 89.5° (f_r·cos θo at exact grazing incidence
//!   is 0 by the [`Brdf`] conventions; readers interpolate towards this slice above 78.5°);
//! - grid points whose ωo falls below the horizon continue their valid neighbours linearly (they
//!   are corners of cells readers interpolate in, never evaluated themselves); the `valid` field
//!   marks them 0 (a bit per sample, packed most significant bit first over φi × θi × N × N —
//!   the published files' `valid` has exactly that many bytes, φi·θi·N²/8, though what their bits
//!   mean is not documented; no reader uses the field);
//! - D is floored at 10⁻⁵ of its maximum so that every warp covers the whole hemisphere, and
//!   for isotropic sources raised to a tenth of what any incidence up to 80° needs
//!   ([`ndf::COVERAGE`]): a lobe that the retro-reflection misses (Phong's, about the mirror
//!   direction) otherwise gets a few cells for the whole lobe;
//! - a luminance slice that is zero everywhere (a source black for that incidence) is stored
//!   uniform, which keeps the file loadable.
//!
//! Errors: a source that is zero everywhere (no retro-reflection to recover D from), or returns
//! NaN or infinite values, is an [`Error::InvalidArgument`]; invalid cells of MERL files evaluate
//! as 0 in the source and are written as 0.

pub mod azimuths;
pub mod container;
pub mod elevations;
pub mod ndf;
pub mod report;
pub mod values;
pub mod warps;

use std::path::Path;

use crate::brdf::Brdf;
use crate::error::{Error, Result};

pub use container::Fields;
pub use report::{Report, report, report_with};

/// The incident elevations (radians) of the published isotropic files (0°, 27.7°, 39.9°, 49.9°,
/// 59.3°, 68.6°, 78.5°, 90°), used when 8 are asked for.
pub const DATABASE_THETA_I: [f32; 8] = [
    0.0,
    0.482_896_83,
    0.695_710_7,
    0.871_582_87,
    1.034_542_9,
    1.196_715_5,
    1.369_449,
    std::f32::consts::FRAC_PI_2,
];

/// Default reflectance table resolution N for sources without a parameterization of their own.
pub const DEFAULT_RESOLUTION: usize = 64;

/// The resolution N a source gets by default when at [`DEFAULT_RESOLUTION`] a figure stays past
/// its bar ([`elevations::Placement::past_bar`]).
pub const FINE_RESOLUTION: usize = 128;

/// The most bytes placement lets a file grow to (the values, luminance and VNDF of every
/// elevation): more elevations or the finer table only while they fit. 16 elevations always
/// fit (the count written before placement); a spectral file of 48 wavelengths stays at
/// N = 64 (at N = 128 and 32 elevations it took 105 MB and 12 s). An anisotropic source's
/// grid starts from 9 azimuths × 16 elevations whether they fit or not (48 wavelengths: 118 MB,
/// where the even 17 × 16 on 128² warps took 236 MB) and grows only while it fits.
pub const PLACED_BYTES: usize = 32 << 20;

/// The most elevations placement may give `layout` with `nch` channels: as many as fit
/// [`PLACED_BYTES`], at least [`elevations::START`], at most [`elevations::MAX`].
fn most_elevations(layout: &Layout, nch: usize) -> usize {
    (PLACED_BYTES / elevation_bytes(layout, nch)).clamp(elevations::START, elevations::MAX)
}

/// The most slices (incident directions) an anisotropic file of `layout` with `nch` channels
/// may have within [`PLACED_BYTES`].
fn most_slices(layout: &Layout, nch: usize) -> usize {
    PLACED_BYTES / (elevation_bytes(layout, nch) / layout.phi_i.len())
}

/// Bytes of one incident elevation of `layout` (every azimuth) for `nch` channels.
fn elevation_bytes(layout: &Layout, nch: usize) -> usize {
    4 * layout.phi_i.len() * ((nch + 1) * layout.n * layout.n + layout.vndf[0] * layout.vndf[1])
}

/// The number of incident elevations of an anisotropic source given its count of azimuths
/// (even in cos θi); otherwise elevations are placed ([`elevations`], [`azimuths`]).
pub const DEFAULT_THETA_I: usize = 16;

/// Rows and columns of an anisotropic file's VNDF slices when its azimuths and elevations are
/// placed ([`azimuths::place`]): 64 × 64 leaves [`PLACED_BYTES`] room for 409 RGB slices at
/// N = 64, against 256 at 128 × 128, and the interpolation over azimuths is where such a file's
/// error is (the NDF and σ keep 128 columns).
pub const GRID_VNDF: usize = 64;

/// The most f32 values a written file may hold (1 GiB), so that no option allocates without bound.
pub const MAX_FLOATS: usize = 1 << 28;

/// What to write.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Options {
    /// Reflectance table resolution N (N × N per incident direction), 2..=1024; `None`:
    /// [`DEFAULT_RESOLUTION`] ([`FINE_RESOLUTION`] when elevations are placed, a figure stays
    /// past its bar at N = 64, N = 128 does better and fits [`PLACED_BYTES`]), or the
    /// parameterization's own.
    pub resolution: Option<usize>,
    /// Number of incident elevations θi (from 0 to 90°), 2..=256; `None`: placed per source
    /// ([`elevations::place`], 16 to 32, when it is isotropic; [`azimuths::place`] with its
    /// azimuths when it is not and `phi_i` is `None`), else [`DEFAULT_THETA_I`]. 8 gives
    /// the database's spacing, other counts are even in cos θi. Must be `None` with a
    /// parameterization (which fixes them).
    pub theta_i: Option<usize>,
    /// Number of incident azimuths: `None` = 1 for isotropic sources; for anisotropic ones
    /// placed with the elevations ([`azimuths::place`]) when `theta_i` is `None`, else 17. 1 writes an
    /// isotropic file (φi = 0), and is the only value an isotropic source takes; 3 or more an
    /// anisotropic one (evenly over [−π, π]), for anisotropic sources. 2 is not allowed
    /// (readers take ≤ 2 azimuths as isotropic).
    pub phi_i: Option<usize>,
    /// Resolution of the NDF, σ and VNDF warp grids along each axis, 4..=1024; `None`: 128
    /// (the VNDF warps [`GRID_VNDF`] when an anisotropic source's azimuths are placed).
    pub ndf_resolution: Option<usize>,
    /// The `description` field (default: the source's description).
    pub description: Option<String>,
    /// Resample into this existing parameterization (incident directions, NDF, σ, VNDF) instead
    /// of recovering one from the source — what re-encoding an RGL file uses, so that its values
    /// are resampled at the very positions they were stored at.
    pub parameterization: Option<Parameterization>,
}

/// The parameterization of an existing `.bsdf` file: its incident directions, NDF, σ and VNDF
/// slices, and its reflectance resolution.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameterization {
    /// Incident azimuths.
    pub phi_i: Vec<f32>,
    /// Incident elevations.
    pub theta_i: Vec<f32>,
    /// NDF/σ shape [rows, columns].
    pub ndf_shape: [usize; 2],
    /// The NDF.
    pub ndf: Vec<f32>,
    /// The projected area.
    pub sigma: Vec<f32>,
    /// VNDF slice shape [rows, columns].
    pub vndf_shape: [usize; 2],
    /// The VNDF slices, φi × θi × rows × columns.
    pub vndf: Vec<f32>,
    /// The file's reflectance resolution.
    pub resolution: usize,
    /// The file's channels (`None`: RGB, else its wavelengths) and stored values
    /// (φi × θi × channels × N × N): kept as they are at the grid points whose ωo is below the
    /// horizon, where no source can be evaluated (they matter only as corners of cells readers
    /// interpolate in), when the source has the same channels and N.
    pub values: (Option<Vec<f32>>, Vec<f32>),
}

impl Parameterization {
    /// Reads the parameterization of a `.bsdf` file.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self> {
        Self::from_tensor(&crate::measured::tensor::TensorFile::open(path)?)
    }

    /// Reads the parameterization of a parsed tensor file (the shapes are checked as the
    /// reader checks them).
    pub fn from_tensor(tf: &crate::measured::tensor::TensorFile) -> Result<Self> {
        // The reader validates every shape and value range; reuse it as the check.
        crate::measured::RglBrdf::from_tensor(tf, None)?;
        let get = |name: &str| -> Result<(Vec<usize>, Vec<f32>)> {
            let f = tf.field(name)?;
            Ok((f.shape.clone(), tf.to_f32(f)?))
        };
        let (_, phi_i) = get("phi_i")?;
        let (_, theta_i) = get("theta_i")?;
        let (ns, ndf) = get("ndf")?;
        let (_, sigma) = get("sigma")?;
        let (vs, vndf) = get("vndf")?;
        let table = tf
            .get("rgb")
            .or_else(|| tf.get("spectra"))
            .ok_or_else(|| Error::format(tf.file_name(), Some("rgb"), None, "missing"))?;
        let resolution = table.shape[3];
        let square = table.shape[3] == table.shape[4];
        let wavelengths = match tf.get("wavelengths") {
            Some(w) if table.name == "spectra" => Some(tf.to_f32(w)?),
            _ => None,
        };
        let values = (wavelengths, tf.to_f32(table)?);
        if !square || vs.len() != 4 || ns.len() != 2 {
            return Err(Error::Unsupported(format!(
                "{}: only square reflectance tables can be re-encoded",
                tf.file_name()
            )));
        }
        Ok(Parameterization {
            phi_i,
            theta_i,
            ndf_shape: [ns[0], ns[1]],
            ndf,
            sigma,
            vndf_shape: [vs[2], vs[3]],
            vndf,
            resolution,
            values,
        })
    }
}

pub use crate::progress::Progress;

/// The stored values and their validity bits.
#[derive(Debug, Clone)]
pub struct Values {
    /// φi × θi × channels × N × N.
    pub data: Vec<f32>,
    /// One bit per (φi, θi, j, i), packed.
    pub valid: Vec<u8>,
}

/// Checked layout of a file to write.
#[derive(Debug, Clone)]
pub struct Layout {
    /// Reflectance table resolution N.
    pub n: usize,
    /// Incident elevations.
    pub theta_i: Vec<f32>,
    /// Incident azimuths.
    pub phi_i: Vec<f32>,
    /// At most 2 φi (an isotropic file, azimuths relative to φi).
    pub isotropic: bool,
    /// NDF/σ columns (θ).
    pub ndf_nx: usize,
    /// NDF/σ rows (φ).
    pub ndf_ny: usize,
    /// VNDF slice shape [rows (φ), columns (θ)].
    pub vndf: [usize; 2],
}

impl Options {
    /// When `source` names a `.bsdf` file and no incident-direction or NDF-grid option is set,
    /// resample into the file's own parameterization (re-encoding: values land where they were
    /// stored); otherwise the options as they are.
    pub fn reuse_source_file(mut self, source: impl AsRef<std::ffi::OsStr>) -> Result<Self> {
        let source = source.as_ref();
        let fixed = self.theta_i.is_none() && self.phi_i.is_none() && self.ndf_resolution.is_none();
        if fixed
            && self.parameterization.is_none()
            && source
                .as_encoded_bytes()
                .to_ascii_lowercase()
                .ends_with(b".bsdf")
        {
            self.parameterization = Some(Parameterization::from_file(source)?);
        }
        Ok(self)
    }

    /// Checks the options and computes the file's layout for a source (isotropic or not).
    pub fn layout(&self, source_isotropic: bool) -> Result<Layout> {
        let n = self.resolution.unwrap_or(
            self.parameterization
                .as_ref()
                .map_or(DEFAULT_RESOLUTION, |p| p.resolution),
        );
        if !(2..=1024).contains(&n) {
            return Err(Error::arg("resolution", format!("{n} is not in 2..=1024")));
        }
        if let Some(p) = &self.parameterization {
            if self.theta_i.is_some() || self.phi_i.is_some() || self.ndf_resolution.is_some() {
                return Err(Error::arg(
                    "theta_i",
                    "the incident directions and NDF grid are fixed by the given parameterization",
                ));
            }
            return Ok(Layout {
                n,
                theta_i: p.theta_i.clone(),
                phi_i: p.phi_i.clone(),
                isotropic: p.phi_i.len() <= 2,
                ndf_nx: p.ndf_shape[1],
                ndf_ny: p.ndf_shape[0],
                vndf: p.vndf_shape,
            });
        }
        let n_theta = self.theta_i.unwrap_or(DEFAULT_THETA_I);
        if !(2..=256).contains(&n_theta) {
            return Err(Error::arg(
                "theta_i",
                format!("{n_theta} incident elevations: 2..=256 are allowed"),
            ));
        }
        let nv = self.ndf_resolution.unwrap_or(128);
        if !(4..=1024).contains(&nv) {
            return Err(Error::arg(
                "ndf_resolution",
                format!("{nv} is not in 4..=1024"),
            ));
        }
        let n_phi = self.phi_i.unwrap_or(if source_isotropic { 1 } else { 17 });
        if n_phi == 2 || n_phi == 0 || n_phi > 360 {
            return Err(Error::arg(
                "phi_i",
                format!(
                    "{n_phi} incident azimuths: 1 (isotropic) or 3..=360 (anisotropic) are allowed"
                ),
            ));
        }
        // More azimuths for an isotropic source only repeat it: n_phi times the bytes, and the
        // anisotropic layout's even elevations in place of the placed ones (a GGX α = 0.3 file
        // with 4 φi: 4× the bytes, whole-hemisphere error 7.3 % against 0.41 % with 1).
        if n_phi > 1 && source_isotropic {
            return Err(Error::arg(
                "phi_i",
                format!(
                    "the source is isotropic: {n_phi} incident azimuths would repeat it {n_phi} \
                     times and lose the elevations placed for it (leave it unset, or 1)"
                ),
            ));
        }
        if n_phi == 1 && !source_isotropic {
            return Err(Error::arg(
                "phi_i",
                "the source is anisotropic: one incident azimuth would lose its azimuthal dependence (use 3 or more)",
            ));
        }
        let theta_i: Vec<f32> = if n_theta == DATABASE_THETA_I.len() {
            DATABASE_THETA_I.to_vec()
        } else {
            let m = (n_theta - 1) as f64;
            (0..n_theta)
                .map(|k| (1.0 - k as f64 / m).clamp(0.0, 1.0).acos() as f32)
                .collect()
        };
        let isotropic = n_phi == 1;
        let phi_i: Vec<f32> = if isotropic {
            vec![0.0]
        } else {
            let pi = std::f64::consts::PI;
            (0..n_phi)
                .map(|k| (-pi + 2.0 * pi * k as f64 / (n_phi - 1) as f64) as f32)
                .collect()
        };
        Ok(Layout {
            n,
            theta_i,
            phi_i,
            isotropic,
            ndf_nx: nv,
            ndf_ny: if isotropic { 2 } else { (nv / 2).max(4) },
            vndf: [nv, nv],
        })
    }
}

/// Builds every field of the `.bsdf` file for `brdf` (see the module docs), reporting the
/// incident directions done to `progress` ([`Silent`](crate::progress::Silent) for none).
pub fn encode(brdf: &dyn Brdf, opts: &Options, progress: &dyn Progress) -> Result<Fields> {
    let mut layout = opts.layout(brdf.flags().isotropic)?;
    // An anisotropic source's azimuths and elevations are placed together unless either is
    // given, on GRID_VNDF² warps unless those are given.
    let gridding = opts.parameterization.is_none()
        && opts.theta_i.is_none()
        && opts.phi_i.is_none()
        && !layout.isotropic;
    if gridding && opts.ndf_resolution.is_none() {
        layout.vndf = [GRID_VNDF; 2];
    }
    let nch = brdf.channels().len();
    if nch == 0 {
        return Err(Error::arg("source", "the source has no channels"));
    }
    // Placement adds elevations (and tries the finer table) only within PLACED_BYTES, far
    // below the limit, so the largest file it may build has the layout's own count or fits
    // the budget.
    let placing = opts.parameterization.is_none() && opts.theta_i.is_none() && layout.isotropic;
    let nt = if placing {
        most_elevations(&layout, nch)
    } else {
        layout.theta_i.len()
    };
    let slices = if gridding {
        // The grid placement starts from, whether it fits the budget or not.
        most_slices(&layout, nch).max(azimuths::START_PHI * elevations::START)
    } else {
        layout.phi_i.len() * nt
    };
    let floats = slices * ((nch + 1) * layout.n * layout.n + layout.vndf[0] * layout.vndf[1]);
    if floats > MAX_FLOATS {
        return Err(Error::arg(
            "resolution",
            format!(
                "the file would hold {floats} values ({} MB); at most {MAX_FLOATS} are written",
                floats * 4 / 1_000_000
            ),
        ));
    }
    let (ndf, warps, placed) = match &opts.parameterization {
        Some(p) => {
            let ndf = ndf::Ndf::given(p, layout.isotropic);
            let warps = warps::given(p, &layout)?;
            (ndf, warps, None)
        }
        None => {
            let ndf = ndf::recover(brdf, &layout)?;
            if placing {
                let max = most_elevations(&layout, nch);
                let mut placed = elevations::place(brdf, &ndf, &layout, max, progress)?;
                let fine = Layout {
                    n: FINE_RESOLUTION,
                    ..layout.clone()
                };
                if placed.past_bar()
                    && opts.resolution.is_none()
                    && PLACED_BYTES / elevation_bytes(&fine, nch) >= elevations::START
                {
                    // Still past a bar at the most elevations or at the slices' own limit: a
                    // finer table, placed again, kept when its worst figure is lower (Ward's
                    // albedo at 89°, which grows like 1/√cos θ, is not).
                    let max = most_elevations(&fine, nch);
                    let finer = elevations::place(brdf, &ndf, &fine, max, progress)?;
                    if finer.worst() < placed.worst() {
                        placed = finer;
                        layout.n = FINE_RESOLUTION;
                    }
                }
                layout.theta_i = placed.theta_i;
            }
            // Anisotropic files interpolate over azimuths as well, and that is where most of
            // their error is: placing elevations alone changed none of their figures (Lambert +
            // GGX α = (0.2, 0.5): grazing band 4.0 → 3.8 % on the pair rule) for 2.3× the bytes.
            if gridding {
                let (placed, phi_i, slices) =
                    azimuths::place(brdf, &ndf, &layout, most_slices(&layout, nch), progress)?;
                layout.theta_i = placed.theta_i;
                layout.phi_i = phi_i;
                // The file is the grid placement encoded last, slice by slice (encoding it
                // again took 0.27 s of a 5.3 s write).
                let warps = warps::with_warps(slices.vndf, &layout)?;
                (ndf, warps, Some(slices.values))
            } else {
                let warps = warps::vndf(&ndf, &layout)?;
                (ndf, warps, None)
            }
        }
    };
    let keep = opts
        .parameterization
        .as_ref()
        .filter(|p| p.resolution == layout.n && same_channels(&p.values.0, brdf.channels()))
        .map(|p| p.values.1.as_slice());
    let values = match placed {
        Some(v) => v,
        None => values::sample(brdf, &ndf, &warps, &layout, keep, progress)?,
    };
    if values.data.iter().all(|&v| v == 0.0) {
        return Err(Error::arg(
            "source",
            "the source is zero at every sampled direction pair: nothing to write",
        ));
    }
    let description = opts
        .description
        .clone()
        .unwrap_or_else(|| format!("brdftab: {}", brdf.describe()));
    let fields = fields_of(
        description,
        &layout,
        &ndf,
        warps.data,
        values,
        brdf.channels(),
    );
    // The luminance must be a density the readers can build their warp of: values near f32's
    // largest, each finite, summed to inf (session 40's fuzzing: a file the reader accepts,
    // re-encoded, was written and then refused by the reader).
    let planes = crate::table::warp2d::Planes {
        nx: layout.n,
        ny: layout.n,
        data: fields.luminance.clone(),
    };
    if let Err((s, total)) = crate::table::warp2d::Warp::build(planes) {
        return Err(Error::arg(
            "source",
            format!(
                "the luminance of slice {s} integrates to {total}: the source's values are too \
                 large for a .bsdf file"
            ),
        ));
    }
    Ok(fields)
}

/// The fields of a file of `layout` from its parts (the luminance computed from the values).
fn fields_of(
    description: String,
    layout: &Layout,
    ndf: &ndf::Ndf,
    vndf: Vec<f32>,
    values: Values,
    channels: &crate::spectrum::Channels,
) -> Fields {
    Fields {
        description,
        phi_i: layout.phi_i.clone(),
        theta_i: layout.theta_i.clone(),
        ndf_shape: [layout.ndf_ny, layout.ndf_nx],
        sigma: ndf.sigma.clone(),
        ndf: ndf.ndf.clone(),
        vndf_shape: layout.vndf,
        luminance: warps::luminance(&values, channels, layout),
        vndf,
        n: layout.n,
        values: values.data,
        valid: values.valid,
        wavelengths: wavelengths_of(channels),
    }
}

/// The `wavelengths` field for `channels` (`None`: an RGB file).
fn wavelengths_of(channels: &crate::spectrum::Channels) -> Option<Vec<f32>> {
    match channels {
        crate::spectrum::Channels::Rgb => None,
        c => Some((0..c.len()).map(|i| c.wavelength(i) as f32).collect()),
    }
}

/// Whether a file's channels (`None`: RGB) are `channels`.
fn same_channels(file: &Option<Vec<f32>>, channels: &crate::spectrum::Channels) -> bool {
    match (file, channels) {
        (None, crate::spectrum::Channels::Rgb) => true,
        (Some(w), c @ crate::spectrum::Channels::Wavelengths(_)) => {
            w.len() == c.len() && (0..c.len()).all(|i| w[i] == c.wavelength(i) as f32)
        }
        _ => false,
    }
}

/// What [`write()`] wrote.
#[derive(Debug, Clone)]
pub struct Written {
    /// File size in bytes.
    pub bytes: usize,
    /// The fields written.
    pub fields: Fields,
}

/// Encodes `brdf` and writes the `.bsdf` file at `path` (through a temporary file renamed into
/// place).
pub fn write(
    brdf: &dyn Brdf,
    path: impl AsRef<Path>,
    opts: &Options,
    progress: &dyn Progress,
) -> Result<Written> {
    let path = path.as_ref();
    let fields = encode(brdf, opts, progress)?;
    // A source that failed while it was read (a corrupt table chunk) gave zeros: write nothing.
    brdf.health()?;
    let bytes = fields.to_bytes();
    crate::files::write_atomic(path, &bytes)?;
    Ok(Written {
        bytes: bytes.len(),
        fields,
    })
}

#[cfg(test)]
mod tests;
