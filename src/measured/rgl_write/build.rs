//! Building every field of a file from a source ([`encode`]): the layout placed within
//! [`PLACED_BYTES`](super::PLACED_BYTES), the NDF, warps and values computed, the fields laid out.

use super::{
    FINE_RESOLUTION, Fields, GRID_VNDF, Layout, MAX_FLOATS, Options, PLACED_BYTES, Progress,
    Values, azimuths, elevations, ndf, values, warps,
};
use crate::brdf::Brdf;
use crate::error::{Error, Result};

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
pub(super) fn fields_of(
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
pub(super) fn same_channels(file: &Option<Vec<f32>>, channels: &crate::spectrum::Channels) -> bool {
    match (file, channels) {
        (None, crate::spectrum::Channels::Rgb) => true,
        (Some(w), c @ crate::spectrum::Channels::Wavelengths(_)) => {
            w.len() == c.len() && (0..c.len()).all(|i| w[i] == c.wavelength(i) as f32)
        }
        _ => false,
    }
}
