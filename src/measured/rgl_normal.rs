//! An isotropic RGL measurement made continuous at normal incidence, for baking.
//!
//! The reader ([`RglBrdf`](crate::measured::RglBrdf)) evaluates an isotropic file in the frame of
//! the incident azimuth φi: the outgoing direction enters its warps relative to φi. At θi = 0 that
//! azimuth is undefined, and the file's θi = 0 slice is not rotationally symmetric (a measurement
//! is not), so the value at a pair (wi → z, wo) depends on the direction from which wi approaches
//! the normal: on `cc_iris_purple_gem` by 25 % within 0.2°. No table can follow that: a lookup at
//! wi = z gets one value per wo. Which one it got used to be an accident of where the grid's nodes
//! sat (a table's directional albedo at θ′ = 1° was 3–7 % off on two shipped files).
//!
//! [`ContinuousAtNormal`] is the source a bake samples instead: the file's value plus a
//! weight w0(θi), 1 at the normal and 0 from 5° on, times the difference between the slice's
//! azimuthal mean L(θo) and its value for this approach direction,
//!
//! f̃(wi, wo) cos θo = f(wi, wo) cos θo + w0(θi) · [L(θ′) − f(z, wo′) cos θ′],
//!
//! clamped at 0, where wo′ (elevation θ′) is the mirror of z about the pair's half vector
//! turned by −φi: the point of the normal slice that the reader blends in for this pair (its
//! warps place the slices by the half vector relative to φi). As wi nears the normal from any
//! direction, f̃ tends to the slice's azimuthal mean L(θo) — the continuous limit tables
//! report. w0 falls linearly from 1 at θi = 0 to 0 at [`NORMAL_BAND`] (5°); beyond, the view
//! is the file. At θi = 0 the correction's integral against dωo is exactly 0 (a rotation does
//! not change an integral over the hemisphere), so the albedo there is the file's; within the
//! band it is kept to first order in θi (measured: within 1e-3 at 0.05–4°, tested).
//!
//! [`NORMAL_BAND`]: crate::measured::rgl::NORMAL_BAND

use glam::DVec3;

use crate::brdf::{Brdf, Flags};
use crate::geometry::elevation;
use crate::spectrum::{Channels, MAX_CHANNELS};

/// Nodes of L's θo axis (θo = π/2 · t², t uniform: dense near the normal, where a film's peak
/// is).
const NODES: usize = 513;
/// Azimuths averaged per node (midpoints).
const AZIMUTHS: usize = 720;

/// L(θo): the azimuthal mean of the reader's values at wi = z, per channel, tabulated as
/// L cos θo (bounded up to the horizon, where a measured f_r grows like 1/cos θo) in
/// t = √(2θo/π).
#[derive(Debug, Clone)]
pub(crate) struct NormalLimit {
    /// NODES × channels.
    values: Vec<f32>,
    channels: usize,
}

impl NormalLimit {
    /// Averages the reader `rgl` at wi = z over the outgoing azimuth at every node.
    pub(crate) fn new(rgl: &dyn Brdf) -> NormalLimit {
        let c = rgl.channels().len();
        let mut values = vec![0f32; NODES * c];
        let mut f = [0f32; MAX_CHANNELS];
        let mut sum = [0f64; MAX_CHANNELS];
        for (i, row) in values.chunks_mut(c).enumerate() {
            let t = i as f64 / (NODES - 1) as f64;
            let theta = std::f64::consts::FRAC_PI_2 * t * t;
            sum[..c].fill(0.0);
            for j in 0..AZIMUTHS {
                let phi = std::f64::consts::TAU * (j as f64 + 0.5) / AZIMUTHS as f64;
                let wo = crate::geometry::spherical(theta, phi);
                rgl.eval(DVec3::Z, wo, &mut f[..c]);
                for k in 0..c {
                    sum[k] += f[k] as f64 * wo.z.max(0.0);
                }
            }
            for k in 0..c {
                row[k] = (sum[k] / AZIMUTHS as f64) as f32;
            }
        }
        NormalLimit {
            values,
            channels: c,
        }
    }

    /// L cos θo at the outgoing elevation `theta_o` (linear in t), added times `w` to `out`.
    #[inline]
    fn add(&self, theta_o: f64, w: f64, out: &mut [f64]) {
        let t = (theta_o * std::f64::consts::FRAC_2_PI).sqrt().min(1.0) * (NODES - 1) as f64;
        let i = (t as usize).min(NODES - 2);
        let s = t - i as f64;
        let c = self.channels;
        let (a, b) = (&self.values[i * c..], &self.values[(i + 1) * c..]);
        for k in 0..c {
            out[k] += w * ((1.0 - s) * a[k] as f64 + s * b[k] as f64);
        }
    }
}

/// An isotropic RGL file as a bake samples it: continuous at normal incidence (see the module
/// docs). Made by [`RglBrdf`](crate::measured::RglBrdf)'s [`BakeSource::bake_view`](crate::brdf::BakeSource::bake_view); sampling and
/// the pdf are the file's own.
pub struct ContinuousAtNormal<'a> {
    rgl: &'a dyn Brdf,
    limit: &'a NormalLimit,
    /// Where the θi = 0 slice's weight falls linearly from 1 to 0 (radians): from the file's
    /// first θi sample to [`NORMAL_BAND`](crate::measured::rgl::NORMAL_BAND) beyond it.
    slice: [f64; 2],
}

impl<'a> ContinuousAtNormal<'a> {
    /// The view of the reader `rgl` whose first θi samples are `slice`.
    pub(crate) fn new(rgl: &'a dyn Brdf, limit: &'a NormalLimit, slice: [f64; 2]) -> Self {
        ContinuousAtNormal { rgl, limit, slice }
    }

    /// The weight of the θi = 0 slice in the reader's interpolation at elevation `theta_i`.
    #[inline]
    fn normal_slice_weight(&self, theta_i: f64) -> f64 {
        let [t0, t1] = self.slice;
        1.0 - ((theta_i - t0) / (t1 - t0)).clamp(0.0, 1.0)
    }
}

impl Brdf for ContinuousAtNormal<'_> {
    fn channels(&self) -> &Channels {
        self.rgl.channels()
    }

    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        self.rgl.eval(wi, wo, out);
        let Some((wi, wo)) = crate::geometry::upper_pair(wi, wo) else {
            return;
        };
        let w0 = self.normal_slice_weight(elevation(wi));
        if w0 <= 0.0 {
            return;
        }
        let c = self.limit.channels;
        // The reader places the slices by the half vector, relative to φi: the θi = 0 slice
        // as this approach direction sees it is f(z, wo') with wo' the mirror of z about the
        // half vector turned by −φi.
        let Some(m) = crate::geometry::normalize(wi + wo) else {
            return;
        };
        let (s, co) = wi.y.atan2(wi.x).sin_cos();
        let m = DVec3::new(co * m.x + s * m.y, co * m.y - s * m.x, m.z);
        let seen = crate::geometry::reflect(DVec3::Z, m);
        if seen.z <= 0.0 {
            return;
        }
        // In f_r cos θo (what the reader interpolates, bounded): the slice's value there
        // replaced by its azimuthal mean, then divided by this pair's cos θo.
        let mut g = [0f32; MAX_CHANNELS];
        self.rgl.eval(DVec3::Z, seen, &mut g[..c]);
        let w = w0 / wo.z;
        let mut acc = [0f64; MAX_CHANNELS];
        for k in 0..c {
            acc[k] = out[k] as f64 - w * g[k] as f64 * seen.z;
        }
        self.limit.add(elevation(seen), w, &mut acc[..c]);
        for k in 0..c {
            out[k] = acc[k].max(0.0) as f32;
        }
    }

    fn flags(&self) -> Flags {
        self.rgl.flags()
    }

    fn describe(&self) -> String {
        format!("{} (continuous at normal incidence)", self.rgl.describe())
    }

    fn sample(
        &self,
        wo: DVec3,
        u: glam::DVec2,
        weight: &mut [f32],
    ) -> Option<crate::brdf::BrdfSample> {
        self.rgl.sample(wo, u, weight)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.rgl.pdf(wi, wo)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::spherical;
    use crate::measured::RglBrdf;

    fn file(name: &str) -> RglBrdf {
        let p = crate::measured::data::rgl_file(name).unwrap();
        RglBrdf::open(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
    }

    #[test]
    fn the_view_is_continuous_at_the_normal_and_the_file_is_not() {
        let rgl = file("cc_iris_purple_gem_rgb.bsdf");
        let view = rgl
            .bake_source()
            .and_then(|b| b.bake_view())
            .expect("an isotropic file has a view");
        let wo = spherical(30f64.to_radians(), 0.7);
        let (mut a, mut b) = ([0f32; 3], [0f32; 3]);
        let mut spread = |brdf: &dyn Brdf| {
            // wi 1e-4 rad from the normal, approaching from eight azimuths.
            let mut lo = [f32::MAX; 3];
            let mut hi = [0f32; 3];
            for j in 0..8 {
                let wi = spherical(1e-4, j as f64 * std::f64::consts::TAU / 8.0);
                brdf.eval(wi, wo, &mut a);
                for k in 0..3 {
                    lo[k] = lo[k].min(a[k]);
                    hi[k] = hi[k].max(a[k]);
                }
            }
            // Relative to the brightest channel (this file's red is nearly 0 here).
            let top = hi.iter().fold(0f32, |m, &x| m.max(x));
            (0..3).map(|k| (hi[k] - lo[k]) / top).fold(0f32, f32::max)
        };
        let file_spread = spread(&rgl);
        let view_spread = spread(view.as_ref());
        // The file's limit depends on the approach (by a third of its value here); the view's
        // varies with w0 over 1e-4 rad (1e-4 / 5°) and with the half vector's shift (1e-4
        // rad) times the slice's slope: a few 1e-3, a hundredth of the file's.
        assert!(file_spread > 0.1, "{file_spread}");
        assert!(
            view_spread < 0.01 * file_spread,
            "{view_spread} {file_spread}"
        );
        // Beyond the band the view is the file.
        let wi = spherical(6f64.to_radians(), 0.3);
        rgl.eval(wi, wo, &mut a);
        view.eval(wi, wo, &mut b);
        assert_eq!(a, b);
    }

    #[test]
    fn the_view_keeps_every_directional_albedo() {
        let rgl = file("vch_golden_yellow_rgb.bsdf");
        let view = rgl.bake_source().and_then(|b| b.bake_view()).unwrap();
        let opts = crate::analysis::fidelity::FidelityOptions {
            albedo_thetas_deg: vec![0.0, 0.05, 0.5, 1.0, 2.0, 4.0],
            ..Default::default()
        };
        let (a, b) = crate::analysis::fidelity::albedo_pair(view.as_ref(), &rgl, &opts).unwrap();
        for (x, y) in a.iter().zip(&b) {
            for k in 0..3 {
                // At θi = 0 the correction integrates to 0 up to L's tabulation (513 nodes,
                // 720 azimuths); within the band to first order in θi.
                assert!((x[k] - y[k]).abs() < 1e-3 * y[k], "{x:?} {y:?}");
            }
        }
    }
}
