//! `Box<B>` and `Arc<B>` of a `Brdf` are `Brdf`s.

use glam::{DVec2, DVec3};

use super::{BakeSource, Brdf, BrdfSample, Flags};
use crate::spectrum::Channels;

/// Smart pointers to a `Brdf` are `Brdf`s: every method forwards to the pointee (so overrides such
/// as a table's `eval_batch` or a model's closed-form `albedo` are kept).
macro_rules! forward_brdf {
    ($($ptr:ident)::+) => {
        impl<B: Brdf + ?Sized> Brdf for $($ptr)::+<B> {
            fn channels(&self) -> &Channels {
                (**self).channels()
            }
            fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
                (**self).eval(wi, wo, out)
            }
            fn flags(&self) -> Flags {
                (**self).flags()
            }
            fn describe(&self) -> String {
                (**self).describe()
            }
            fn grows_at_horizon(&self) -> bool {
                (**self).grows_at_horizon()
            }
            fn eval_wavelength(&self, wi: DVec3, wo: DVec3, nm: f64) -> f64 {
                (**self).eval_wavelength(wi, wo, nm)
            }
            fn eval_at_wavelengths(&self, wi: DVec3, wo: DVec3, nm: &[f64], out: &mut [f32]) {
                (**self).eval_at_wavelengths(wi, wo, nm, out)
            }
            fn eval_batch(&self, wi: &[DVec3], wo: &[DVec3], out: &mut [f32]) {
                (**self).eval_batch(wi, wo, out)
            }
            fn albedo(&self, wi: DVec3, out: &mut [f64]) {
                (**self).albedo(wi, out)
            }
            fn pdf_batch(&self, wi: &[DVec3], wo: &[DVec3], out: &mut [f64]) {
                (**self).pdf_batch(wi, wo, out)
            }
            fn sample_batch(&self, wo: &[DVec3], u: &[DVec2], out: crate::batch::SampleOut<'_>) {
                (**self).sample_batch(wo, u, out)
            }
            fn sample(&self, wo: DVec3, u: DVec2, weight: &mut [f32]) -> Option<BrdfSample> {
                (**self).sample(wo, u, weight)
            }
            fn sample_wavelengths(
                &self,
                wo: DVec3,
                u: DVec2,
                nm: &[f64],
                weight: &mut [f32],
            ) -> Option<BrdfSample> {
                (**self).sample_wavelengths(wo, u, nm, weight)
            }
            fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
                (**self).pdf(wi, wo)
            }
            fn eval_pdf(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) -> f64 {
                (**self).eval_pdf(wi, wo, out)
            }
            fn bake_source(&self) -> Option<&dyn BakeSource> {
                (**self).bake_source()
            }
            fn health(&self) -> crate::Result<()> {
                (**self).health()
            }
        }
    };
}

forward_brdf!(Box);
forward_brdf!(std::sync::Arc);
