//! The [`Brdf`] impl of a [`TabulatedBrdf`]: its lookups one pair at a time and in batches (the
//! hot path, kept in one file), and the table's sampler behind `sample` and `pdf`.

use glam::{DVec2, DVec3};
use std::sync::atomic::Ordering;

use super::TabulatedBrdf;
use crate::brdf::{BakeSource, Brdf, BrdfSample, Flags};
use crate::error::{Error, Result};
use crate::spectrum::Channels;
use crate::table::kernel::{LANES, project_out};
use crate::table::lookup::{Interp, Prepared};

/// Lookups per group in [`TabulatedBrdf::eval_batch`]'s two-phase loop.
const GROUP: usize = 8;

impl TabulatedBrdf {
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
    ///
    /// [`TableSampler`]: crate::table::sampling::TableSampler
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
