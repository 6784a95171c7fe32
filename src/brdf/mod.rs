//! The [`Brdf`] trait: the one interface every source of reflectance implements.
//!
//! Analytic models, tables baked from them, and measured data all implement `Brdf`, so a renderer
//! or an analysis swaps one for another without changing a line. The interface follows pbrt-v4's
//! `BxDF` (f, Sample_f, PDF, Flags) with the conventions of `DESIGN.md`:
//!
//! - local shading frame, `z` = surface normal; both directions point **away** from the surface;
//! - `wi` is the direction to the light (the lecture's L, ω′, θ′), `wo` to the viewer (V, ω, θ);
//! - [`Brdf::eval`] returns f_r in 1/sr, **not** multiplied by a cosine;
//! - either direction at or below the horizon gives 0; directions need not be normalized; NaN or
//!   zero vectors give 0, never a panic.
//!
//! Directions are `f64` ([`DVec3`]) so that sharp lobes (Phong n = 1000) are evaluated to full
//! accuracy; values are written as `f32` into a caller's buffer, one per channel, so evaluation
//! never allocates.

use glam::{DVec2, DVec3};

use crate::geometry;
use crate::spectrum::{Channels, MAX_CHANNELS};

mod flagged;
mod flags;
mod forward;
mod spectral;
#[cfg(test)]
mod tests;

pub use flagged::{sample_flagged, sample_flagged_at};
pub use flags::{Flags, Lobes};
pub use spectral::{channels_at_wavelengths, eval_wavelengths, mix_channels};

/// A direction drawn by [`Brdf::sample`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrdfSample {
    /// The sampled incident direction (towards the light), unit length. For a refractor it lies
    /// on the other side of the surface from `wo`.
    pub wi: DVec3,
    /// The solid-angle density of `wi` given `wo`. For delta samples this is 1 by convention
    /// (a discrete choice probability when a delta sampler picks among several lobes).
    pub pdf: f64,
    /// True when `wi` is a delta direction (the weight is then the lobe's reflectance, e.g. k_r).
    pub delta: bool,
}

/// `{:?}` of a boxed or borrowed `Brdf` (what [`crate::open`] returns) is its
/// [`describe`](Brdf::describe), so `Result`s holding one can be unwrapped and structs holding
/// one can derive `Debug`.
impl std::fmt::Debug for dyn Brdf + Send + Sync {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Brdf({})", self.describe())
    }
}

/// As for `dyn Brdf + Send + Sync`.
impl std::fmt::Debug for dyn Brdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Brdf({})", self.describe())
    }
}

/// A bidirectional reflectance distribution function.
///
/// Object safe and `Send + Sync`, so `Box<dyn Brdf + Send + Sync>` and `&dyn Brdf` work everywhere.
///
/// # Example
/// ```
/// use brdftab::{Brdf, models::lambert::Lambert, spectrum::{Channels, Value}};
/// use glam::DVec3;
///
/// let brdf = Lambert::new(Value::Grey(0.25), &Channels::Rgb).unwrap();
/// let mut f = [0.0f32; 3];
/// brdf.eval(DVec3::new(0.3, 0.1, 1.0), DVec3::Z, &mut f);
/// assert_eq!(f, [0.25; 3]);
/// ```
pub trait Brdf: Send + Sync {
    /// The channels this BRDF returns (RGB or wavelengths).
    fn channels(&self) -> &Channels;

    /// Writes f_r(wi, wo) for every channel into `out[..channels().len()]`, in 1/sr.
    ///
    /// Below the horizon, for NaN or zero directions, and for delta models, writes 0.
    /// `out` must hold at least `channels().len()` values.
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]);

    /// What the model declares about itself.
    fn flags(&self) -> Flags;

    /// A short human-readable description (model name and parameters, or table and source).
    fn describe(&self) -> String;

    /// Whether f_r grows without bound as one direction nears the horizon — Ward's
    /// 1/√(cos θi cos θo), the original Phong's 1/cos θi. Bounded f_r cos θi cos θo is then
    /// what a table of this BRDF should store (the bake's default for such sources): a table of
    /// f_r itself blends a node near the horizon, where f_r is huge, over a whole cell, which
    /// costs accuracy at grazing angles and gives its sampler a spike to follow. False by
    /// default, and for growth confined to the grazing mirror (the max- and mean-Phong's
    /// 1/cos θ, Cook-Torrance's 1/cos² θ): a lookup of f_r cos θi cos θo divides by cos θo
    /// wherever the view grazes, which amplifies the table's residual there for every light
    /// direction, and their tables of f_r do better (BENCHMARKS.md, session 26).
    fn grows_at_horizon(&self) -> bool {
        false
    }

    /// f_r at one wavelength in nm. The default reads the channels as [`Channels::mix_at`] says:
    /// interpolated linearly between wavelength channels (constant outside them), RGB through the
    /// colour-preserving basis of [`crate::colour`]; analytic models with spectral parameters
    /// override it to use their spectral data directly.
    ///
    /// `nm` must be a wavelength ([`crate::spectrum::is_wavelength`]: finite, > 0): at anything
    /// else every source returns NaN, whatever the directions (this method and
    /// [`Brdf::eval_at_wavelengths`] cannot fail; the Python and C hosts refuse such wavelengths
    /// with an error), rather than an end channel's value, which passed NaN or 0 nm off as data.
    fn eval_wavelength(&self, wi: DVec3, wo: DVec3, nm: f64) -> f64 {
        let mut buf = [0.0f32; MAX_CHANNELS];
        let n = self.channels().len().min(MAX_CHANNELS);
        self.eval(wi, wo, &mut buf[..n]);
        self.channels().mix_at(nm).apply(|i| buf[i] as f64)
    }

    /// f_r at each of the wavelengths `nm` into `out[..nm.len()]`: [`Brdf::eval_wavelength`]
    /// of each, as f32. What a spectral renderer asks per path vertex (pbrt-v4: four
    /// wavelengths). The default calls `eval_wavelength` once per wavelength; sources whose
    /// wavelengths are read from their channels (tables, MERL and RGL files) override it with
    /// one lookup for all of them ([`channels_at_wavelengths`]), the same values bit for bit.
    fn eval_at_wavelengths(&self, wi: DVec3, wo: DVec3, nm: &[f64], out: &mut [f32]) {
        for (o, &x) in out.iter_mut().zip(nm) {
            *o = self.eval_wavelength(wi, wo, x) as f32;
        }
    }

    /// Evaluates many pairs: `out[k * c .. (k + 1) * c]` receives `f_r(wi[k], wo[k])` where `c` is
    /// the channel count. Batches of [`crate::batch::PARALLEL`] (16 384) pairs or more run on
    /// the library's pool ([`crate::par`]); tables override this for throughput.
    ///
    /// # Panics
    ///
    /// If `wi.len() != wo.len()` or `out.len() != wi.len() * c`: a mismatch is a caller's bug,
    /// and silently evaluating fewer pairs would hide it. Every implementation (overrides
    /// included) checks this with [`check_batch`]; hosts that take user arrays (the Python and
    /// C bindings) check the lengths before calling.
    fn eval_batch(&self, wi: &[DVec3], wo: &[DVec3], out: &mut [f32]) {
        let c = self.channels().len().max(1);
        let n = check_batch(wi, wo, out, c);
        crate::batch::blocks(&mut out[..n * c], c, |s, o| {
            for ((a, b), o) in wi[s..].iter().zip(&wo[s..]).zip(o.chunks_exact_mut(c)) {
                self.eval(*a, *b, o);
            }
        });
    }

    /// Densities of many pairs: `out[k] = pdf(wi[k], wo[k])`, on the library's pool from
    /// [`crate::batch::PARALLEL`] pairs on (what the hosts call on their callers' arrays).
    ///
    /// # Panics
    ///
    /// If the three lengths differ (a caller's bug, as for [`Brdf::eval_batch`]).
    fn pdf_batch(&self, wi: &[DVec3], wo: &[DVec3], out: &mut [f64]) {
        assert!(
            wi.len() == wo.len() && out.len() == wi.len(),
            "pdf_batch: {} wi, {} wo and {} outputs do not match",
            wi.len(),
            wo.len(),
            out.len()
        );
        crate::batch::blocks(out, 1, |s, o| {
            for ((p, a), b) in o.iter_mut().zip(&wi[s..]).zip(&wo[s..]) {
                *p = self.pdf(*a, *b);
            }
        });
    }

    /// Draws `wi` for every `wo[k]` from `u[k]` into `out` (wi, pdf, and `c` weights per pair).
    /// A pair with no sample — `wo` below the horizon, a non-finite `wo`, a `u` outside
    /// [0, 1)² ([`crate::batch::drawable`]), a zero lobe —
    /// gets wi = 0, pdf = 0 and weights 0. On the library's pool from
    /// [`crate::batch::PARALLEL`] pairs on.
    ///
    /// # Panics
    ///
    /// If the lengths do not match `wo.len()` pairs.
    fn sample_batch(&self, wo: &[DVec3], u: &[DVec2], out: crate::batch::SampleOut<'_>) {
        use crate::batch::{SampleOut, drawable, no_sample};
        let c = self.channels().len().max(1);
        crate::batch::sample_blocks(c, wo, u, out, |wo, u, out| {
            let SampleOut { wi, pdf, weight } = out;
            let rows = wi
                .iter_mut()
                .zip(pdf.iter_mut())
                .zip(weight.chunks_exact_mut(c));
            for (k, ((wi, p), w)) in rows.enumerate() {
                let drawn = match drawable(wo[k], u[k]) {
                    true => self.sample(wo[k], u[k], w),
                    false => None,
                };
                match drawn {
                    Some(d) => (*wi, *p) = (d.wi, d.pdf),
                    None => no_sample(wi, p, w),
                }
            }
        });
    }

    /// Directional albedo a(wi) = ∫ f_r(wi, wo) cos θo dωo for every channel into `out`.
    ///
    /// The default integrates numerically ([`albedo_with`] the default
    /// [`Options`](crate::analysis::albedo::Options): 1e-6 relative); models with a closed form
    /// override it, and data — tables, measured files — integrate to
    /// [`Options::DATA`](crate::analysis::albedo::Options::DATA) (1e-4, bounded work), which their
    /// interpolation's kinks would otherwise drive to the interval limits. For delta models it
    /// is the reflectance of the delta lobe.
    fn albedo(&self, wi: DVec3, out: &mut [f64]) {
        albedo_with(self, wi, &crate::quadrature::Options::default(), out)
    }

    /// Draws an incident direction `wi` for the outgoing direction `wo` from two uniform numbers
    /// `u` in [0,1)², writing the per-channel weight f_r·cos θi / pdf (for delta samples the
    /// lobe's reflectance) into `weight`.
    ///
    /// A `Some` is always a real draw: `wi` is a unit vector — above the horizon, or for a
    /// refractor on the other side of the surface from `wo` — with a finite positive `pdf`,
    /// the density [`Brdf::pdf`] gives for that pair up to rounding (delta samples: `pdf` 1 by
    /// convention, [`Brdf::pdf`] 0), and finite weights ≥ 0.
    ///
    /// Returns `None` when no direction can be drawn (e.g. `wo` below the horizon or not finite,
    /// total internal reflection) and for every `u` outside [0, 1)² — beyond an edge (1
    /// included), infinite or NaN ([`geometry::in_unit_square`]) — whether or not the sampler
    /// uses `u`, as [`Brdf::sample_batch`] does: samplers map only that square, and beyond it
    /// their formulas give directions that are not unit or densities that are wrong. The weight
    /// is then unspecified. Implementations check `u` first; the test kit's contract
    /// (`testkit::check_contract`) holds every source to it.
    ///
    /// The default draws cosine-weighted directions; models override with importance sampling.
    fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
        let wo = geometry::unit(wo)?;
        if wo.z <= 0.0 || !geometry::in_unit_square(u) {
            return None;
        }
        let wi = geometry::cosine_hemisphere(u);
        let pdf = wi.z * std::f64::consts::FRAC_1_PI;
        if pdf <= 0.0 {
            return None;
        }
        let c = self.channels().len();
        self.eval(wi, wo, &mut weight[..c]);
        for w in &mut weight[..c] {
            *w = (*w as f64 * std::f64::consts::PI) as f32;
        }
        Some(BrdfSample {
            wi,
            pdf,
            delta: false,
        })
    }

    /// [`Brdf::sample`] with the weight at the wavelengths `nm` (in nm) instead of the channels:
    /// the same draw (`wi`, `pdf`, `delta`) as `sample(wo, u, ..)`, and `weight[k]` the weight at
    /// `nm[k]` — f_r cos θi / pdf from [`Brdf::eval_wavelength`] for a smooth draw, the delta
    /// lobe's reflectance at `nm[k]` for a delta draw. What a spectral renderer needs: the
    /// weight at the wavelengths its path carries, also for a mirror, whose reflectance lives
    /// only in the sample.
    ///
    /// The default interpolates a delta draw's channel weights as `eval_wavelength`'s default
    /// interpolates channels; the delta models (and sums holding them) override it with their
    /// spectral data. `weight` must hold `nm.len()` values; a weight at a non-wavelength is NaN
    /// (as [`Brdf::eval_wavelength`]'s value).
    ///
    /// # Example
    /// ```
    /// use brdftab::{Brdf, fresnel::FresnelSpec, models::mirror::Mirror, spectrum::Channels};
    /// use glam::{DVec2, DVec3};
    ///
    /// let gold = Mirror::new(&FresnelSpec::Conductor("Au".into()), &Channels::Rgb).unwrap();
    /// let mut w = [0.0f32; 2];
    /// let s = gold.sample_wavelengths(DVec3::Z, DVec2::splat(0.5), &[450.0, 650.0], &mut w);
    /// assert!(s.unwrap().delta);
    /// assert!(w[0] < 0.5 && w[1] > 0.9); // gold reflects red, not blue
    /// ```
    fn sample_wavelengths(
        &self,
        wo: DVec3,
        u: DVec2,
        nm: &[f64],
        weight: &mut [f32],
    ) -> Option<BrdfSample> {
        let mut buf = [0.0f32; MAX_CHANNELS];
        let c = self.channels().len().min(MAX_CHANNELS);
        let s = self.sample(wo, u, &mut buf[..c])?;
        if s.delta {
            mix_channels(self.channels(), &buf[..c], nm, weight);
        } else {
            let k = s.wi.z.abs() / s.pdf;
            let n = nm.len().min(weight.len());
            self.eval_at_wavelengths(s.wi, wo, &nm[..n], &mut weight[..n]);
            for w in &mut weight[..n] {
                *w = (*w as f64 * k) as f32;
            }
        }
        Some(s)
    }

    /// The density with which [`Brdf::sample`] draws `wi` given `wo` (solid angle, 1/sr);
    /// 0 for delta models and for directions the sampler never produces.
    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        match (geometry::normalize(wi), geometry::normalize(wo)) {
            (Some(wi), Some(wo)) if wi.z > 0.0 && wo.z > 0.0 => wi.z * std::f64::consts::FRAC_1_PI,
            _ => 0.0,
        }
    }

    /// `eval` and `pdf` of the same pair in one call (what multiple importance sampling and
    /// mixtures need): writes f_r into `out[..channels]` and returns pdf(wi | wo). Models whose
    /// value and density share work (microfacet models: the half vector, D) override it.
    fn eval_pdf(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) -> f64 {
        self.eval(wi, wo, out);
        self.pdf(wi, wo)
    }

    /// What a bake needs of this source beyond its values ([`BakeSource`]): `None` (the
    /// default) for the analytic models; a MERL file and a table give their stored nodes, an
    /// RGL file the view a bake samples.
    fn bake_source(&self) -> Option<&dyn BakeSource> {
        None
    }

    /// Whether every value this BRDF has returned so far was real. `eval` cannot return an
    /// error, so a source whose data can fail while it is read — a lazily decoded table whose
    /// chunk fails its checksum — returns 0 for the lookups it cannot serve and reports the
    /// failure here from then on (sticky: a failed source stays failed). Call it after a batch
    /// of lookups (a tile, a frame) and discard the batch on an error; it is one atomic load
    /// for a healthy table. Always `Ok` for analytic models and measured files (read whole at
    /// open).
    fn health(&self) -> crate::Result<()> {
        Ok(())
    }
}

/// What a bake asks of a source besides `eval`: the nodes it stores, and what to sample when
/// the source itself is not what a table should follow. Reached through
/// [`Brdf::bake_source`], so the core trait carries one hook instead of the bake's concerns.
pub trait BakeSource {
    /// For sources that are themselves values on nodes in the Rusinkiewicz angles — a MERL
    /// measurement (cell centres), a `halfdiff` table (its nodes): when `hd` is one of those
    /// nodes (to rounding), writes its value **as stored** into `out[..channels]` and returns
    /// `true`. As stored means: also where a direction of the node's pair lies below the
    /// horizon (a measured cell whose centre does), and negative where the source marks a cell
    /// as unmeasured (MERL's −1, scaled like the other values), which `eval` reports as 0.
    ///
    /// Baking on a `halfdiff` grid and resampling on the MERL grid ask this first, so a table of
    /// such a source on its own grid holds its cells verbatim, unmeasured markers included.
    /// Returns `false` (the default) for every other source and angle: then evaluate directions.
    fn stored_node(&self, hd: geometry::HalfDiff, out: &mut [f32]) -> bool {
        let _ = (hd, out);
        false
    }

    /// What a bake of this BRDF samples, when that is not the BRDF itself: `None` (the
    /// default) for every source except a measurement the table cannot follow as it is. An
    /// isotropic RGL file's value at normal incidence depends on the direction from which wi
    /// approaches the normal; its view replaces that by the continuous limit, keeping every
    /// directional albedo ([`crate::measured::rgl_normal`]).
    fn bake_view(&self) -> Option<Box<dyn Brdf + '_>> {
        None
    }
}

/// The length check of [`Brdf::eval_batch`]: returns the number of pairs, panics (with both
/// lengths) if `wi`, `wo` and `out` (`c` channels per pair) disagree.
#[track_caller]
pub fn check_batch(wi: &[DVec3], wo: &[DVec3], out: &[f32], c: usize) -> usize {
    assert!(
        wi.len() == wo.len() && out.len() == wi.len() * c,
        "eval_batch: {} wi, {} wo and {} outputs do not match ({c} channels per pair)",
        wi.len(),
        wo.len(),
        out.len()
    );
    wi.len()
}

/// The directional albedo of `brdf` at `wi` by adaptive quadrature to `opts`
/// ([`crate::analysis::albedo::integrate`]), every channel into `out`: the default of
/// [`Brdf::albedo`], and with [`Options::DATA`](crate::analysis::albedo::Options::DATA) that of
/// tables and measured data.
pub fn albedo_with<B: Brdf + ?Sized>(
    brdf: &B,
    wi: DVec3,
    opts: &crate::quadrature::Options,
    out: &mut [f64],
) {
    let est = crate::quadrature::hemisphere(brdf.channels().len(), wi, opts, |wi, wo, f| {
        brdf.eval(wi, wo, f)
    });
    let c = est.value.len().min(out.len());
    out[..c].copy_from_slice(&est.value[..c]);
}
