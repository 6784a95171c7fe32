//! Evaluating an RGL file: the incident and outgoing directions through the warps to the
//! reflectance table, and the tensor's own luminance sampling ([`RglBrdf::tensor_sample`]).

use std::f64::consts::{FRAC_PI_2, PI};

use glam::DVec3;

use super::{
    AtIncidence, Corners, Incident, RglBrdf, elevation, mulsign_neg, param_weight, phi2u, theta2u,
};
use crate::geometry;
use crate::table::warp2d::{NO_PARAMS, bilinear};

impl RglBrdf {
    pub(super) fn corners(&self, phi_i: f64, theta_i: f64) -> Corners {
        let (p0, p1, wp) = param_weight(&self.phi_i, phi_i);
        let (t0, t1, wt) = param_weight(&self.theta_i, theta_i);
        let nt = self.theta_i.len();
        Corners {
            slice: [p0 * nt + t0, p0 * nt + t1, p1 * nt + t0, p1 * nt + t1],
            w: [
                (1.0 - wp) * (1.0 - wt),
                (1.0 - wp) * wt,
                wp * (1.0 - wt),
                wp * wt,
            ],
        }
    }

    /// The warped point, the corners and the Jacobian factor for a pair; `None` → value 0.
    #[inline]
    pub(super) fn prepare(&self, wi: DVec3, wo: DVec3) -> Option<([f64; 2], Corners, f64, f64)> {
        let (wi, wo) = geometry::upper_pair(wi, wo)?;
        self.outgoing(&self.incident(wi), wo)
    }

    /// What [`prepare`](Self::prepare) derives from the incident direction alone (`wi` as
    /// `upper_pair` returns it).
    #[inline]
    pub(super) fn incident(&self, mut wi: DVec3) -> Incident {
        let mut signs = None;
        if self.reduction >= 2 {
            let sy = wi.y;
            let sx = if self.reduction == 4 { wi.x } else { sy };
            wi.x = mulsign_neg(wi.x, sx);
            wi.y = mulsign_neg(wi.y, sy);
            signs = Some((sx, sy));
        }
        let theta_i = elevation(wi);
        let phi_i = wi.y.atan2(wi.x);
        let u_wi = [theta2u(theta_i), phi2u(phi_i)];
        let k = self.corners(phi_i, theta_i);
        let sigma = if self.jacobian {
            bilinear(&self.sigma, &NO_PARAMS, 0, 0, u_wi)
        } else {
            1.0
        };
        Incident {
            wi,
            signs,
            phi_i,
            k,
            sigma,
        }
    }

    /// [`prepare`](Self::prepare) of `wo` (as `upper_pair` returns it) for an incidence.
    #[inline]
    pub(super) fn outgoing(
        &self,
        inc: &Incident,
        mut wo: DVec3,
    ) -> Option<([f64; 2], Corners, f64, f64)> {
        let cos_o = wo.z;
        if let Some((sx, sy)) = inc.signs {
            wo.x = mulsign_neg(wo.x, sx);
            wo.y = mulsign_neg(wo.y, sy);
        }
        let wm = geometry::normalize(inc.wi + wo)?;
        let theta_m = elevation(wm);
        let phi_m = wm.y.atan2(wm.x);
        let mut u_wm = [
            theta2u(theta_m),
            phi2u(if self.isotropic {
                phi_m - inc.phi_i
            } else {
                phi_m
            }),
        ];
        u_wm[1] -= u_wm[1].floor();
        let k = inc.k;
        let sample = self.vndf.invert(u_wm, &k);
        let scale = if self.jacobian {
            let ndf = bilinear(&self.ndf, &NO_PARAMS, 0, 0, u_wm);
            let sigma = inc.sigma;
            if sigma.is_nan() || sigma <= 0.0 {
                return None;
            }
            ndf / (4.0 * sigma)
        } else {
            1.0
        };
        Some((sample, k, scale, cos_o))
    }

    /// This file at one incident direction: [`AtIncidence::eval`] is `eval(wi, wo)` to the bit,
    /// with what depends on `wi` alone (its azimuth and elevation, the slices around it, σ)
    /// found once. The RGL writer's placement measures albedos of the file it reads back,
    /// thousands of outgoing directions per incidence (session 42).
    pub(crate) fn at_incidence(&self, wi: DVec3) -> AtIncidence<'_> {
        let l2 = wi.length_squared();
        // `upper_pair` treats each direction alone when both are near unit length.
        let inc = (wi.z > 0.0 && geometry::is_near_unit_l2(l2))
            .then(|| self.incident(geometry::unit_or_near(wi, l2)));
        AtIncidence {
            file: self,
            wi,
            inc,
        }
    }

    /// The channels of a prepared pair (`out` zeroed).
    #[inline]
    pub(super) fn finish(
        &self,
        (sample, k, scale, cos_o): ([f64; 2], Corners, f64, f64),
        out: &mut [f32],
    ) {
        for (o, mix) in out.iter_mut().zip(&self.out_map) {
            let v = mix.apply(|c| self.out_channel(sample, &k, c));
            let f = v * scale / cos_o;
            // Negative ndf/sigma (only in corrupt files) or NaN must not leak out; a value
            // beyond f32 (measured f_r grows like 1/cos θo: 3.7e99 at cos 1e-100) saturates, as
            // the original Phong's does, rather than dropping to 0 where `eval_wavelength`
            // gives it.
            *o = if f > 0.0 {
                f.min(f32::MAX as f64) as f32
            } else {
                0.0
            };
        }
    }

    /// Output channel `c`'s value before the cosine: the file's channel, or for a spectral file
    /// asked for RGB the projected planes'.
    #[inline]
    pub(super) fn out_channel(&self, sample: [f64; 2], k: &Corners, c: usize) -> f64 {
        match &self.rgb_of_spectra {
            Some(t) => {
                let plane = t.plane_len();
                bilinear(t, k, 3 * plane, c * plane, sample).max(0.0)
            }
            None => self.channel(sample, k, c),
        }
    }

    /// The stored reflectance of file channel `c` at the warped point, clipped at 0.
    #[inline]
    pub(super) fn channel(&self, sample: [f64; 2], k: &Corners, c: usize) -> f64 {
        let nch = self.wavelengths.as_ref().map_or(3, |w| w.len());
        let plane = self.table.plane_len();
        bilinear(&self.table, k, nch * plane, c * plane, sample).max(0.0)
    }

    /// Signs for the φ reduction of anisotropic files, from the tensor-incident direction.
    #[inline]
    pub(super) fn reduction_signs(&self, inc: DVec3) -> Option<(f64, f64)> {
        (self.reduction >= 2).then(|| {
            let sy = inc.y;
            (if self.reduction == 4 { inc.x } else { sy }, sy)
        })
    }

    #[inline]
    pub(super) fn flip(v: DVec3, signs: Option<(f64, f64)>) -> DVec3 {
        match signs {
            Some((sx, sy)) => DVec3::new(mulsign_neg(v.x, sx), mulsign_neg(v.y, sy), v.z),
            None => v,
        }
    }

    /// Solid-angle density with which the measurement's own sampler (luminance warp, then VNDF
    /// warp, then reflection about the half vector) draws `out` for the tensor-incident
    /// direction `inc`.
    pub fn tensor_pdf(&self, inc: DVec3, out: DVec3) -> f64 {
        let Some((inc, out)) = geometry::upper_pair(inc, out) else {
            return 0.0;
        };
        let signs = self.reduction_signs(inc);
        let (inc, out) = (Self::flip(inc, signs), Self::flip(out, signs));
        let Some(wm) = geometry::normalize(inc + out) else {
            return 0.0;
        };
        let theta_i = elevation(inc);
        let phi_i = inc.y.atan2(inc.x);
        let phi_m = wm.y.atan2(wm.x);
        let mut u_wm = [
            theta2u(elevation(wm)),
            phi2u(if self.isotropic { phi_m - phi_i } else { phi_m }),
        ];
        u_wm[1] -= u_wm[1].floor();
        let k = self.corners(phi_i, theta_i);
        let (sample, vndf_pdf) = self.vndf.invert_pdf(u_wm, &k);
        let lum = self.luminance.as_ref().map_or(1.0, |l| l.eval(sample, &k));
        let sin_m = (wm.x * wm.x + wm.y * wm.y).sqrt();
        let jac = (2.0 * PI * PI * u_wm[0] * sin_m).max(1e-6) * 4.0 * inc.dot(wm);
        let pdf = vndf_pdf * lum / jac;
        if pdf.is_finite() && pdf > 0.0 {
            pdf
        } else {
            0.0
        }
    }

    /// Draws an outgoing direction for the tensor-incident direction `inc` with the
    /// measurement's sampler; returns it with its solid-angle density.
    pub fn tensor_sample(&self, inc: DVec3, u: glam::DVec2) -> Option<(DVec3, f64)> {
        let inc = geometry::normalize(inc)?;
        if inc.z <= 0.0 {
            return None;
        }
        let signs = self.reduction_signs(inc);
        let inc = Self::flip(inc, signs);
        let theta_i = elevation(inc);
        let phi_i = inc.y.atan2(inc.x);
        let k = self.corners(phi_i, theta_i);
        let (sample, lum_pdf) = match &self.luminance {
            Some(l) => l.sample([u.y, u.x], &k),
            None => ([u.y, u.x], 1.0),
        };
        let (u_m, ndf_pdf) = self.vndf.sample(sample, &k);
        let theta_m = u_m[0] * u_m[0] * FRAC_PI_2;
        let mut phi_m = (2.0 * u_m[1] - 1.0) * PI;
        if self.isotropic {
            phi_m += phi_i;
        }
        let m = geometry::spherical(theta_m, phi_m);
        let jac = (2.0 * PI * PI * u_m[0] * theta_m.sin()).max(1e-6) * 4.0 * inc.dot(m);
        let out = geometry::reflect(inc, m);
        let pdf = ndf_pdf * lum_pdf / jac;
        if out.z <= 0.0 || !(pdf.is_finite() && pdf > 0.0) {
            return None;
        }
        Some((Self::flip(out, signs), pdf))
    }
}
