//! Tests of the table sampler's pieces against plain references in the paper's terms: the
//! half-vector map and its Jacobian, `pdf` and `sample`, the nodes and their adjoint.

use super::half_map::{LINEAR, s_of_theta};
use super::*;
use crate::rng::Pcg32;
use std::f64::consts::{FRAC_PI_2, PI};

#[test]
fn half_vector_map_round_trips() {
    let mut rng = Pcg32::new(3);
    for _ in 0..10_000 {
        let p = rng.next_dvec2();
        let (h, sin_th) = half_of([p.x, p.y]);
        assert!((h.length() - 1.0).abs() < 1e-12 && h.z >= 0.0);
        assert!((sin_th - (h.x * h.x + h.y * h.y).sqrt()).abs() < 1e-12);
        let q = square_of(h);
        assert!(
            (p.x - q[0]).abs() < 1e-9 && (p.y - q[1]).abs() < 1e-9,
            "{p} -> {h} -> {q:?}"
        );
    }
}

#[test]
fn jacobian_is_the_solid_angle_of_a_patch() {
    // |∂ωi/∂s × ∂ωi/∂y| by finite differences = 4 (wo·h) · half_jacobian.
    let mut rng = Pcg32::new(4);
    let e = 1e-6;
    let wo = geometry::spherical(0.7, 0.2);
    let wi_of = |u: [f64; 2]| {
        let (h, _) = half_of(u);
        2.0 * wo.dot(h) * h - wo
    };
    for _ in 0..1000 {
        let p = rng.next_dvec2() * 0.98 + DVec2::splat(0.01);
        let u = [p.x, p.y];
        let a = wi_of(u);
        let bx = wi_of([u[0] + e, u[1]]) - wi_of([u[0] - e, u[1]]);
        let by = wi_of([u[0], u[1] + e]) - wi_of([u[0], u[1] - e]);
        let area = bx.cross(by).length() / (4.0 * e * e);
        let _ = a;
        let (h, st) = half_of(u);
        let j = 4.0 * wo.dot(h).abs() * half_jacobian(u[0], st);
        assert!((area - j).abs() <= 1e-6 * j + 1e-9, "{u:?}: {area} vs {j}");
    }
}

/// A plain reference of [`TableSampler::pdf`]: libm trigonometry, θo and φo by `acos` and
/// `atan2`, the bilinear density read from the nodes by hand, both preimages summed.
fn pdf_reference(t: &TableSampler, wi: DVec3, wo: DVec3) -> f64 {
    let (wi, wo) = (wi.normalize(), wo.normalize());
    let (theta_o, mut phi_o) = (wo.z.acos(), wo.y.atan2(wo.x));
    // Isotropic: the nodes' frame has φo = 0.
    let rot = if t.isotropic { -phi_o } else { 0.0 };
    let turn = |v: DVec3| {
        let (s, c) = rot.sin_cos();
        DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
    };
    let (wil, wol) = (turn(wi), turn(wo));
    // Conditioning weights: t = √(1 − cos θo) on nt nodes, φo on np periodic nodes.
    let mut slices = Vec::new();
    let tt = (1.0 - theta_o.cos()).sqrt() * (t.nt - 1) as f64;
    let t0 = (tt.floor() as usize).min(t.nt - 2);
    for (kt, wt) in [(t0, 1.0 - (tt - t0 as f64)), (t0 + 1, tt - t0 as f64)] {
        if t.np == 1 {
            slices.push((kt, wt));
            continue;
        }
        if phi_o < 0.0 {
            phi_o += TAU;
        }
        let pp = phi_o / TAU * t.np as f64;
        let p0 = pp.floor() as usize % t.np;
        let fp = pp - pp.floor();
        slices.push((kt * t.np + p0, wt * (1.0 - fp)));
        slices.push((kt * t.np + (p0 + 1) % t.np, wt * fp));
    }
    let (nx, ny) = (t.warp.pdf.nx, t.warp.pdf.ny);
    let node = |sl: usize, x: usize, y: usize| t.warp.pdf.data[sl * nx * ny + y * nx + x] as f64;
    let mut total = 0.0;
    for w in [wil, DVec3::new(wil.x, wil.y, -wil.z)] {
        let h = (w + wol).normalize();
        if h.z <= 0.0 {
            continue;
        }
        // atan2, not acos(h.z): acos loses θh's relative precision near the pole, where
        // the density divides by sin θh.
        let th = (h.x * h.x + h.y * h.y).sqrt().atan2(h.z);
        let s = s_of_theta(th);
        let y = ((h.y.atan2(h.x) + PI) / TAU).rem_euclid(1.0);
        let (fx, fy) = (s * (nx - 1) as f64, y * (ny - 1) as f64);
        let (ix, iy) = ((fx as usize).min(nx - 2), (fy as usize).min(ny - 2));
        let (ax, ay) = (fx - ix as f64, fy - iy as f64);
        let mut p = 0.0;
        for &(sl, wt) in &slices {
            p += wt
                * ((1.0 - ay) * ((1.0 - ax) * node(sl, ix, iy) + ax * node(sl, ix + 1, iy))
                    + ay * ((1.0 - ax) * node(sl, ix, iy + 1) + ax * node(sl, ix + 1, iy + 1)));
        }
        p *= ((nx - 1) * (ny - 1)) as f64;
        let dtheta_ds = FRAC_PI_2 * (LINEAR + 2.0 * (1.0 - LINEAR) * s);
        total += p / (4.0 * wol.dot(h) * th.sin() * dtheta_ds * TAU);
    }
    total
}

#[test]
fn pdf_and_sample_match_a_plain_reference() {
    let iso = crate::spec::ModelSpec::parse(
        r#"{"model": "cook_torrance", "m": 0.2, "fresnel": {"conductor": "Au"}}"#,
    )
    .unwrap()
    .build(&crate::spectrum::Channels::Rgb)
    .unwrap();
    let aniso = crate::spec::ModelSpec::parse(
        r#"{"model": "ward", "ks": 0.3, "alpha_x": 0.1, "alpha_y": 0.3}"#,
    )
    .unwrap()
    .build(&crate::spectrum::Channels::Rgb)
    .unwrap();
    let small = SamplingResolution {
        theta_h: 24,
        phi_h: 20,
        theta_o: 9,
        phi_o: 6,
        floor: 0.005,
    };
    let mut rng = Pcg32::new(8);
    for (b, isotropic) in [(iso.as_ref(), true), (aniso.as_ref(), false)] {
        let t = TableSampler::build(b, isotropic, &small);
        let mut w = [0.0f32; 3];
        for _ in 0..20_000 {
            let wo = geometry::uniform_hemisphere(rng.next_dvec2());
            let wi = geometry::uniform_hemisphere(rng.next_dvec2());
            let (fast, slow) = (t.pdf(wi, wo), pdf_reference(&t, wi, wo));
            assert!(
                (fast - slow).abs() <= 1e-9 * slow,
                "{wi} {wo}: {fast} vs {slow}"
            );
            if let Some(smp) = t.sample(b, wo, rng.next_dvec2(), &mut w) {
                let slow = pdf_reference(&t, smp.wi, wo);
                // Where a preimage's half vector is nearly undefined (w + wo → 0: wi near
                // the mirror image of −wo below the horizon), roundings of 1e-16 in the
                // directions move ĥ by 1e-16/|w + wo| and wo·ĥ with it: relative errors of
                // up to 1e-15/(|w + wo| wo·ĥ) in that term.
                let cond = [smp.wi, mirror_z(smp.wi)]
                    .map(|w| {
                        let h = w + wo;
                        let dot = wo.dot(h) / h.length();
                        if h.z > 0.0 && dot > 0.0 {
                            1e-15 / (h.length() * dot)
                        } else {
                            0.0
                        }
                    })
                    .into_iter()
                    .fold(0.0, f64::max);
                assert!(
                    (smp.pdf - slow).abs() <= (1e-7 + cond) * slow,
                    "{}: {} vs {slow}",
                    smp.wi,
                    smp.pdf
                );
            }
        }
    }
}

/// The exported nodes are the sampler's own, and the adjoint exchanges the directions:
/// for a reciprocal model it gives the same nodes, for a non-reciprocal one others.
#[test]
fn nodes_and_their_adjoint() {
    use crate::spec::ModelSpec;
    let res = SamplingResolution {
        theta_h: 12,
        phi_h: 10,
        theta_o: 5,
        ..SamplingResolution::default()
    };
    let open = |json: &str| {
        ModelSpec::parse(json)
            .unwrap()
            .build(&crate::spectrum::Channels::Rgb)
            .unwrap()
    };
    let ggx = open(r#"{"model": "ggx", "alpha": 0.3}"#);
    let n = SamplingNodes::build(ggx.as_ref(), true, &res);
    assert_eq!((n.nx, n.ny, n.nt, n.np), (12, 10, 5, 1));
    assert_eq!(
        n.data,
        SamplingNodes::build_par(ggx.as_ref(), true, &res).data
    );
    assert_eq!(n.data.len(), 12 * 10 * 5);
    let a = SamplingNodes::build(&Adjoint(ggx.as_ref()), true, &res);
    for (x, y) in n.data.iter().zip(&a.data) {
        assert!((x - y).abs() <= 1e-5 * x.abs().max(1e-6), "{x} vs {y}");
    }
    // Original Phong divides by cos θi: not reciprocal, so its adjoint differs.
    let phong = open(r#"{"model": "phong", "ks": 0.5, "n": 20}"#);
    let p = SamplingNodes::build(phong.as_ref(), true, &res);
    let q = SamplingNodes::build(&Adjoint(phong.as_ref()), true, &res);
    let diff = p
        .data
        .iter()
        .zip(&q.data)
        .filter(|(x, y)| (*x - *y).abs() > 1e-3 * x.abs());
    assert!(diff.count() > 10);
    let mut f = [0.0f32; 3];
    let mut g = [0.0f32; 3];
    let (wi, wo) = (DVec3::new(0.3, 0.1, 0.9), DVec3::new(-0.5, 0.2, 0.6));
    phong.eval(wo, wi, &mut f);
    Adjoint(phong.as_ref()).eval(wi, wo, &mut g);
    assert_eq!(f, g);
}
