//! RGL-EPFL `.bsdf` evaluation against the published reference reader.
//!
//! `reference_eval_powitacq_rgb.tsv` holds 896 values of `powitacq_rgb::BRDF::eval(wi, wo)`
//! (rgl-epfl/brdf-loader, RGB clipped at 0) for the seven real files. The reference returns
//! f_r · cos θo; brdftab returns f_r, so we compare `value / cos θo`.

use brdftab::Brdf;
use brdftab::geometry::spherical;
use brdftab::measured::RglBrdf;
use brdftab::measured::tensor::{Dtype, TensorFile, TensorWriter};
use brdftab::testkit::TempDir;
use std::collections::BTreeMap;

/// The shipped RGL file `name` (`data/rgl`, see `brdftab::measured::data`); a missing file
/// fails loudly.
fn rgl(name: &str) -> String {
    brdftab::measured::data::rgl_file(name)
        .unwrap_or_else(|e| panic!("{e}"))
        .display()
        .to_string()
}

fn dir(theta_deg: f64, phi_deg: f64) -> glam::DVec3 {
    spherical(theta_deg.to_radians(), phi_deg.to_radians())
}

#[test]
fn matches_reference_reader() {
    let tsv = std::fs::read_to_string(rgl("reference_eval_powitacq_rgb.tsv")).unwrap();
    let mut brdfs: BTreeMap<String, RglBrdf> = BTreeMap::new();
    // (max rel error off the pole, max rel error at θi = 0) per file
    let mut worst: BTreeMap<String, (f64, f64)> = BTreeMap::new();
    let mut rows = 0;
    for line in tsv.lines().skip(1) {
        let c: Vec<&str> = line.split('\t').collect();
        let file = c[0].to_string();
        let v: Vec<f64> = c[1..].iter().map(|x| x.parse().unwrap()).collect();
        let brdf = brdfs
            .entry(file.clone())
            .or_insert_with(|| RglBrdf::open(rgl(&file)).unwrap());
        let (ti, pi, to, po) = (v[0], v[1], v[2], v[3]);
        let wi = dir(ti, pi);
        let wo = dir(to, po);
        let mut f = [0f32; 3];
        brdf.eval(wi, wo, &mut f);
        let cos_o = to.to_radians().cos();
        let e = worst.entry(file).or_default();
        for k in 0..3 {
            let want = v[4 + k] / cos_o;
            let got = f[k] as f64;
            let rel = (got - want).abs() / want.abs().max(1e-6);
            if ti == 0.0 {
                e.1 = e.1.max(rel);
            } else {
                e.0 = e.0.max(rel);
            }
        }
        rows += 1;
    }
    assert_eq!(rows, 896);
    assert_eq!(worst.len(), 7);
    for (file, (off_pole, pole)) in &worst {
        eprintln!("{file}: max rel error {off_pole:.2e} (θi > 0), {pole:.2e} (θi = 0)");
    }
    for (file, (off_pole, pole)) in &worst {
        assert!(*off_pole < 1e-4, "{file}: {off_pole}");
        // At θi = 0 the incident azimuth is undefined: the reader takes φi = atan2(0, 0) = 0 and
        // measures the half vector's azimuth relative to it. The data at θi = 0 are not exactly
        // rotation invariant, so any other choice of φi at the pole (or a direction a rounding
        // error away from it, whose atan2 is arbitrary) selects a different slice of the
        // warp. We use the same convention and match tightly; the tolerance stays looser to
        // leave room for that ambiguity.
        assert!(*pole < 1e-3, "{file} at θi = 0: {pole}");
    }
}

#[test]
fn reference_cosine_convention() {
    // README: paper_white eval(60°, 0°) = 0.258 and eval(0°, 60°) = 0.127 ≈ 0.258 · cos 60°.
    let b = RglBrdf::open(rgl("paper_white_rgb.bsdf")).unwrap();
    let mut f = [0f32; 3];
    b.eval_cos(dir(60.0, 0.0), dir(0.0, 0.0), &mut f);
    assert!((f[1] - 0.258).abs() < 0.01, "{f:?}");
    b.eval_cos(dir(0.0, 0.0), dir(60.0, 0.0), &mut f);
    assert!((f[1] - 0.127).abs() < 0.01, "{f:?}");
    assert!(b.description().contains("White A4 paper"));
    assert_eq!(
        b.sha256(),
        "9d641fbb56358275509b2b1053d1002313e2dabc7b3ec202eb5c5a6943f7b70e"
    );
}

#[test]
fn below_horizon_and_nan_give_zero() {
    let b = RglBrdf::open(rgl("paper_white_rgb.bsdf")).unwrap();
    let mut f = [1f32; 3];
    b.eval(dir(30.0, 0.0), glam::DVec3::new(0.0, 0.3, -0.5), &mut f);
    assert_eq!(f, [0.0; 3]);
    b.eval(glam::DVec3::new(f64::NAN, 0.0, 1.0), glam::DVec3::Z, &mut f);
    assert_eq!(f, [0.0; 3]);
    b.eval(glam::DVec3::ZERO, glam::DVec3::Z, &mut f);
    assert_eq!(f, [0.0; 3]);
    // Grazing and exactly opposite-ish pairs stay finite.
    b.eval(dir(89.999, 0.0), dir(89.999, 180.0), &mut f);
    assert!(f.iter().all(|x| x.is_finite() && *x >= 0.0));
}

#[test]
fn a_hair_above_the_horizon_eval_saturates_where_eval_wavelength_grows() {
    // Measured f_r grows like 1/cos θo towards the horizon: where it passes f32's range `eval`
    // gave 0 (an f32 overflow taken for corrupt data) while `eval_wavelength` (f64) gave the
    // value. It now gives f32::MAX there and agrees with `eval_wavelength` below it (which reads
    // the RGB channels at a wavelength through the RGB basis).
    let b = RglBrdf::open(rgl("paper_white_rgb.bsdf")).unwrap();
    let wi = dir(40.0, 0.0);
    for z in [1e-3, 1e-20, 1e-40, 1e-100, 1e-200, 1e-300] {
        let wo = glam::DVec3::new(-(1.0f64 - z * z).sqrt(), 0.0, z);
        let mut f = [0f32; 3];
        b.eval(wi, wo, &mut f);
        for nm in [450.0, 550.0, 650.0] {
            let want = b.eval_wavelength(wi, wo, nm);
            assert!(want > 0.0 && want.is_finite(), "z {z:e}: {want}");
            if want < 0.5 * f32::MAX as f64 {
                let w = brdftab::colour::rgb_basis_at(nm);
                let mix: f64 = (0..3).map(|c| w[c] * f[c] as f64).sum();
                assert!((mix / want - 1.0).abs() < 1e-6, "z {z:e}: {f:?} vs {want}");
            } else {
                assert_eq!(f, [f32::MAX; 3], "z {z:e}: {f:?} vs {want}");
            }
        }
    }
}

/// Rebuilds a real file field by field so tests can alter one field.
fn rebuild(
    file: &str,
    edit: impl Fn(&str, Dtype, &[u64], Vec<u8>) -> Option<(Dtype, Vec<u64>, Vec<u8>)>,
) -> Vec<u8> {
    let t = TensorFile::open(rgl(file)).unwrap();
    let mut w = TensorWriter::new();
    for f in t.fields() {
        let shape: Vec<u64> = f.shape.iter().map(|&d| d as u64).collect();
        if let Some((d, s, b)) = edit(&f.name, f.dtype, &shape, t.raw(f).to_vec()) {
            w = w.raw(&f.name, d, &s, b);
        }
    }
    w.to_bytes()
}

#[test]
fn rebuilt_file_evaluates_identically() {
    let bytes = rebuild("paper_white_rgb.bsdf", |_, d, s, b| {
        Some((d, s.to_vec(), b))
    });
    let t = TensorFile::from_bytes("rebuilt", bytes).unwrap();
    let a = RglBrdf::from_tensor(&t, None).unwrap();
    let b = RglBrdf::open(rgl("paper_white_rgb.bsdf")).unwrap();
    let (mut fa, mut fb) = ([0f32; 3], [0f32; 3]);
    for (ti, to) in [(10.0, 50.0), (45.0, 45.0), (70.0, 10.0)] {
        a.eval(dir(ti, 10.0), dir(to, 200.0), &mut fa);
        b.eval(dir(ti, 10.0), dir(to, 200.0), &mut fb);
        assert_eq!(fa, fb);
    }
}

#[test]
fn bad_files_are_typed_errors() {
    let tmp = TempDir::new("rgl-bad");
    let orig = std::fs::read(rgl("paper_white_rgb.bsdf")).unwrap();
    // Truncated copies: every cut must be an error, never a panic.
    for cut in [0, 10, 17, 100, 1000, orig.len() / 2, orig.len() - 1] {
        let p = tmp.join("cut.bsdf");
        std::fs::write(&p, &orig[..cut]).unwrap();
        let e = RglBrdf::open(&p).unwrap_err();
        assert!(matches!(e, brdftab::Error::Format { .. }), "cut {cut}: {e}");
        assert!(e.to_string().contains("cut.bsdf"), "{e}");
    }
    let check = |bytes: Vec<u8>, want: &str| {
        let t =
            TensorFile::from_bytes("x.bsdf", bytes).and_then(|t| RglBrdf::from_tensor(&t, None));
        let e = match t {
            Ok(_) => panic!("accepted, expected `{want}`"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains(want), "expected `{want}` in: {e}");
    };
    // rgb with the wrong shape.
    check(
        rebuild("paper_white_rgb.bsdf", |n, d, s, b| {
            Some((
                d,
                if n == "rgb" {
                    vec![1, 8, 4, 32, 32]
                } else {
                    s.to_vec()
                },
                b,
            ))
        }),
        "field `rgb`",
    );
    // vndf as f64 instead of f32 (same bytes, so half the elements).
    check(
        rebuild("paper_white_rgb.bsdf", |n, d, s, b| {
            let mut s = s.to_vec();
            if n == "vndf" {
                s[3] /= 2;
                return Some((Dtype::F64, s, b));
            }
            Some((d, s, b))
        }),
        "expected f32",
    );
    // NaN in sigma.
    check(
        rebuild("paper_white_rgb.bsdf", |n, d, s, mut b| {
            if n == "sigma" {
                b[8..12].copy_from_slice(&f32::NAN.to_le_bytes());
            }
            Some((d, s.to_vec(), b))
        }),
        "field `sigma`",
    );
    // Missing field.
    check(
        rebuild("paper_white_rgb.bsdf", |n, d, s, b| {
            (n != "ndf").then(|| (d, s.to_vec(), b))
        }),
        "field `ndf`: required field is missing",
    );
    // theta_i not increasing.
    check(
        rebuild("paper_white_rgb.bsdf", |n, d, s, mut b| {
            if n == "theta_i" {
                b[4..8].copy_from_slice(&0f32.to_le_bytes());
            }
            Some((d, s.to_vec(), b))
        }),
        "strictly increasing",
    );
}

#[test]
fn spectral_file_matches_rgb_at_channel_wavelengths() {
    // A spectral file whose three wavelengths carry B, G, R of paper_white (ascending order).
    let t = TensorFile::open(rgl("paper_white_rgb.bsdf")).unwrap();
    let mut w = TensorWriter::new();
    for f in t.fields() {
        let shape: Vec<u64> = f.shape.iter().map(|&d| d as u64).collect();
        if f.name == "rgb" {
            let raw = t.raw(f);
            let plane = f.shape[3] * f.shape[4] * 4;
            let slices = f.shape[0] * f.shape[1];
            let mut out = Vec::with_capacity(raw.len());
            for s in 0..slices {
                for c in [2usize, 1, 0] {
                    let o = (s * 3 + c) * plane;
                    out.extend_from_slice(&raw[o..o + plane]);
                }
            }
            w = w.raw("spectra", Dtype::F32, &shape, out);
            w = w.f32("wavelengths", &[3], &[444.0, 526.0, 645.0]);
        } else {
            w = w.raw(&f.name, f.dtype, &shape, t.raw(f).to_vec());
        }
    }
    let spec = RglBrdf::from_tensor(
        &TensorFile::from_bytes("s.bsdf", w.to_bytes()).unwrap(),
        None,
    )
    .unwrap();
    let rgb = RglBrdf::open(rgl("paper_white_rgb.bsdf")).unwrap();
    assert_eq!(spec.channels().len(), 3);
    let (mut a, mut b) = ([0f32; 3], [0f32; 3]);
    for (ti, to, po) in [(20.0, 40.0, 170.0), (65.0, 30.0, 10.0)] {
        let (wi, wo) = (dir(ti, 0.0), dir(to, po));
        spec.eval(wi, wo, &mut a);
        rgb.eval(wi, wo, &mut b);
        assert_eq!([a[2], a[1], a[0]], b);
        let mid = spec.eval_wavelength(wi, wo, 485.0);
        assert!((mid - 0.5 * (b[2] as f64 + b[1] as f64)).abs() < 1e-6 * mid);
    }
}

/// The shipped RGB file `name` made spectral at wavelengths `nm`: each texel's value at λ is
/// `value(its RGB clipped at 0, λ)`.
fn spectral_copy(name: &str, nm: &[f64], value: impl Fn([f64; 3], f64) -> f32) -> TensorFile {
    let t = TensorFile::open(rgl(name)).unwrap();
    let mut w = TensorWriter::new();
    for f in t.fields() {
        let mut shape: Vec<u64> = f.shape.iter().map(|&d| d as u64).collect();
        if f.name == "rgb" {
            let raw = t.raw(f);
            let plane = f.shape[3] * f.shape[4];
            let slices = f.shape[0] * f.shape[1];
            let v = |s: usize, c: usize, i: usize| {
                let o = ((s * 3 + c) * plane + i) * 4;
                f32::from_le_bytes(raw[o..o + 4].try_into().unwrap()).max(0.0) as f64
            };
            let mut out = Vec::with_capacity(slices * nm.len() * plane * 4);
            for s in 0..slices {
                for &x in nm {
                    for i in 0..plane {
                        let rgb = [v(s, 0, i), v(s, 1, i), v(s, 2, i)];
                        out.extend_from_slice(&value(rgb, x).to_le_bytes());
                    }
                }
            }
            shape[2] = nm.len() as u64;
            w = w.raw("spectra", Dtype::F32, &shape, out);
            let wl: Vec<f32> = nm.iter().map(|&x| x as f32).collect();
            w = w.f32("wavelengths", &[nm.len() as u64], &wl);
        } else {
            w = w.raw(&f.name, f.dtype, &shape, t.raw(f).to_vec());
        }
    }
    TensorFile::from_bytes("s.bsdf", w.to_bytes()).unwrap()
}

#[test]
fn a_spectral_file_asked_for_rgb_gives_the_colour_of_its_spectra() {
    // cc_ibiza (saturated) made spectral as `convert` makes it — each texel's RGB (clipped at 0)
    // through the RGB basis every 10 nm — and opened for RGB: its spectra projected to sRGB.
    // Projection is linear, so the result is A · (the RGB file's value) with A the projection
    // of the sampled basis (A = I but for the 10 nm sampling); reading the spectra at
    // representative wavelengths instead gave up to 3 % cross-talk between channels.
    let name = "cc_ibiza_sunset_rgb.bsdf";
    let nm: Vec<f64> = (0..48).map(|i| 360.0 + 10.0 * i as f64).collect();
    let basis: Vec<[f64; 3]> = nm
        .iter()
        .map(|&x| brdftab::colour::rgb_basis_at(x))
        .collect();
    let file = spectral_copy(name, &nm, |rgb, x| {
        let b = brdftab::colour::rgb_basis_at(x);
        (b[0] * rgb[0] + b[1] * rgb[1] + b[2] * rgb[2]) as f32
    });
    let spec = RglBrdf::from_tensor(&file, Some(&brdftab::Channels::Rgb)).unwrap();
    let rgb = RglBrdf::open(rgl(name)).unwrap();
    let weights = brdftab::colour::srgb_weights(&nm);
    let a: Vec<[f64; 3]> = (0..3)
        .map(|r| {
            let mut row = [0.0; 3];
            for (wk, b) in weights.iter().zip(&basis) {
                for c in 0..3 {
                    row[c] += wk[r] * b[c];
                }
            }
            row
        })
        .collect();
    for (r, row) in a.iter().enumerate() {
        for (c, x) in row.iter().enumerate() {
            let want = if r == c { 1.0 } else { 0.0 };
            assert!((x - want).abs() < 5e-3, "A = {a:?}"); // the basis sampled every 10 nm
        }
    }
    let (mut got, mut f) = ([0f32; 3], [0f32; 3]);
    for (ti, pi, to, po) in [
        (45.0, 0.0, 45.0, 180.0),
        (20.0, 30.0, 60.0, 150.0),
        (70.0, 0.0, 10.0, 90.0),
    ] {
        let (wi, wo) = (dir(ti, pi), dir(to, po));
        spec.eval(wi, wo, &mut got);
        rgb.eval(wi, wo, &mut f);
        let top = f.iter().fold(0f32, |m, &x| m.max(x)) as f64;
        for r in 0..3 {
            let want: f64 = (0..3).map(|c| a[r][c] * f[c] as f64).sum();
            // f32 spectra and planes: rounding of the ~48-term sums
            assert!(
                (got[r] as f64 - want).abs() < 1e-5 * top,
                "{got:?} vs {f:?}"
            );
        }
    }
    // At a wavelength the file's spectra are read directly (linear between samples).
    let (wi, wo) = (dir(45.0, 0.0), dir(45.0, 180.0));
    rgb.eval(wi, wo, &mut f);
    let b = brdftab::colour::rgb_basis_at(550.0);
    let want: f64 = (0..3).map(|c| b[c] * f[c] as f64).sum();
    assert!((spec.eval_wavelength(wi, wo, 550.0) / want - 1.0).abs() < 1e-5);
}

/// paper_white's data replicated over `phis` incident azimuths (an anisotropic file).
fn anisotropic(phis: &[f32]) -> RglBrdf {
    let t = TensorFile::open(rgl("paper_white_rgb.bsdf")).unwrap();
    let np = phis.len();
    let mut w = TensorWriter::new();
    for f in t.fields() {
        let mut shape: Vec<u64> = f.shape.iter().map(|&d| d as u64).collect();
        let raw = t.raw(f).to_vec();
        if f.name == "phi_i" {
            w = w.f32("phi_i", &[np as u64], phis);
        } else if ["vndf", "luminance", "rgb"].contains(&f.name.as_str()) {
            shape[0] = np as u64;
            w = w.raw(&f.name, f.dtype, &shape, raw.repeat(np));
        } else {
            w = w.raw(&f.name, f.dtype, &shape, raw);
        }
    }
    RglBrdf::from_tensor(
        &TensorFile::from_bytes("a.bsdf", w.to_bytes()).unwrap(),
        None,
    )
    .unwrap()
}

#[test]
fn anisotropic_reductions_fold_by_symmetry() {
    use std::f32::consts::PI;
    let full = anisotropic(&[-PI, 0.0, PI]);
    assert!(!full.flags().isotropic);
    let half = anisotropic(&[-PI, -PI / 2.0, 0.0]);
    let quarter = anisotropic(&[-PI, -0.75 * PI, -PI / 2.0]);
    let mirror_y = |v: glam::DVec3| glam::DVec3::new(v.x, -v.y, v.z);
    let mirror_x = |v: glam::DVec3| glam::DVec3::new(-v.x, v.y, v.z);
    let (mut a, mut b) = ([0f32; 3], [0f32; 3]);
    for (ti, pi, to, po) in [(30.0, 40.0, 50.0, 100.0), (60.0, -120.0, 20.0, 10.0)] {
        let (wi, wo) = (dir(ti, pi), dir(to, po));
        full.eval(wi, wo, &mut a);
        assert!(
            a.iter().all(|x| x.is_finite() && *x >= 0.0) && a[0] > 0.0,
            "{a:?}"
        );
        half.eval(wi, wo, &mut a);
        // Reduction 2 is a half-turn symmetry: (x, y) → (−x, −y).
        half.eval(mirror_x(mirror_y(wi)), mirror_x(mirror_y(wo)), &mut b);
        assert_eq!(a, b);
        quarter.eval(wi, wo, &mut a);
        quarter.eval(mirror_x(wi), mirror_x(wo), &mut b);
        assert_eq!(a, b);
        quarter.eval(mirror_y(wi), mirror_y(wo), &mut b);
        assert_eq!(a, b);
    }
}

#[test]
fn corrupted_headers_never_panic() {
    // Flip random header bytes (names, dtypes, offsets, shapes) of a real file: every outcome must
    // be Ok or a typed error, never a panic or a huge allocation.
    let orig = std::fs::read(rgl("paper_white_rgb.bsdf")).unwrap();
    let mut rng = brdftab::testkit::Pcg32::new(5);
    for _ in 0..3000 {
        let mut b = orig.clone();
        for _ in 0..1 + rng.below(3) {
            let at = rng.below(420) as usize;
            b[at] = rng.below(256) as u8;
        }
        if let Ok(t) = TensorFile::from_bytes("fuzz", b)
            && let Ok(brdf) = RglBrdf::from_tensor(&t, None)
        {
            let mut f = [0f32; 3];
            brdf.eval(dir(40.0, 10.0), dir(30.0, 200.0), &mut f);
            assert!(f.iter().all(|x| x.is_finite() && *x >= 0.0));
        }
    }
}

#[test]
fn random_pairs_are_finite_and_non_negative() {
    let mut rng = brdftab::testkit::Pcg32::new(8);
    for file in ["cg_sunflower_rgb.bsdf", "satin_rosaline_rgb.bsdf"] {
        let b = RglBrdf::open(rgl(file)).unwrap();
        let mut f = [0f32; 3];
        for _ in 0..20_000 {
            let wi = brdftab::geometry::uniform_hemisphere(rng.next_dvec2());
            let wo = brdftab::geometry::uniform_hemisphere(rng.next_dvec2());
            b.eval(wi, wo, &mut f);
            assert!(
                f.iter().all(|x| x.is_finite() && *x >= 0.0),
                "{wi} {wo} {f:?}"
            );
        }
    }
}

#[test]
fn sampler_passes_chi_square() {
    use brdftab::analysis::chi2::{self, Chi2Options};
    let files = ["paper_white_rgb.bsdf", "cc_ibiza_sunset_rgb.bsdf"];
    let wos = [dir(30.0, 20.0), dir(70.0, -100.0)];
    let alpha = chi2::sidak(0.01, files.len() * wos.len());
    let opts = Chi2Options {
        samples: 100_000,
        cos_bins: 20,
        phi_bins: 40,
        ..Chi2Options::default()
    };
    for file in files {
        let b = RglBrdf::open(rgl(file)).unwrap();
        for wo in wos {
            let r = chi2::test(&b, wo, &opts);
            eprintln!("{file} wo={wo}: {r:?}");
            assert!(r.passes(alpha), "{file} wo={wo}: p = {}", r.p_value);
        }
    }
}

/// A hand-edited file whose angles or microfacet fields leave their domain is an error naming
/// the field, not a file that reads as zeros or as one clamped slice.
#[test]
fn fields_outside_their_domain_are_errors() {
    type Edit = fn(usize, f32) -> f32;
    let edit = |field: &'static str, f: Edit| {
        rebuild("paper_white_rgb.bsdf", move |n, d, s, b| {
            let b = if n == field {
                (b.chunks(4).enumerate())
                    .flat_map(|(i, c)| {
                        f(i, f32::from_le_bytes(c.try_into().unwrap())).to_le_bytes()
                    })
                    .collect()
            } else {
                b
            };
            Some((d, s.to_vec(), b))
        })
    };
    let cases: [(&str, Edit); 6] = [
        ("theta_i", |_, v| v.to_degrees()),
        ("phi_i", |_, v| v + 4.0),
        ("ndf", |_, _| 0.0),
        ("ndf", |i, v| if i == 7 { -v } else { v }),
        ("sigma", |_, _| 0.0),
        ("sigma", |i, v| if i == 3 { -v } else { v }),
    ];
    for (field, f) in cases {
        let t = TensorFile::from_bytes("x.bsdf", edit(field, f)).unwrap();
        match RglBrdf::from_tensor(&t, None) {
            Ok(b) => {
                let mut out = [0f32; 3];
                b.eval(dir(30.0, 0.0), dir(30.0, 180.0), &mut out);
                panic!("{field}: accepted, evaluates to {out:?}");
            }
            Err(e) => assert!(
                matches!(e, brdftab::Error::Format { .. }) && e.to_string().contains(field),
                "{field}: {e}"
            ),
        }
    }
    // σ may vanish at the horizon (the last column): such a file still opens.
    let t = TensorFile::from_bytes(
        "x.bsdf",
        edit("sigma", |i, v| if i % 128 == 127 { 0.0 } else { v }),
    )
    .unwrap();
    RglBrdf::from_tensor(&t, None).unwrap();
}

/// Written fields start at multiples of 8 bytes, as in the published files and Mitsuba's
/// `tensor_io.write`, so a reader that maps the file reads its f32 fields aligned.
#[test]
fn written_fields_are_aligned_as_the_published_files() {
    let published = TensorFile::open(rgl("paper_white_rgb.bsdf")).unwrap();
    let written = TensorFile::from_bytes(
        "rebuilt",
        rebuild("paper_white_rgb.bsdf", |_, d, s, b| {
            Some((d, s.to_vec(), b))
        }),
    )
    .unwrap();
    for t in [&published, &written] {
        for f in t.fields() {
            assert_eq!(
                f.offset % 8,
                0,
                "{}: field `{}` at {}",
                t.file_name(),
                f.name,
                f.offset
            );
        }
    }
    let offsets = |t: &TensorFile| t.fields().iter().map(|f| f.offset).collect::<Vec<_>>();
    assert_eq!(offsets(&written), offsets(&published));
}

/// Re-encoding a file the reader accepts (`convert x.bsdf y.bsdf`: the file's own
/// parameterization, the file as the source) either writes a file the reader accepts or is an
/// error. `tests/data/fuzz_bsdf_luminance_overflow.bsdf` (9,043 bytes: the `bsdf` fuzz target's
/// crash `crash-c04d9de8…`, session 40) stores values near f32's largest: each finite, and its
/// own luminance field valid, but the luminance the writer computes from them integrates to
/// inf, and the writer wrote a file the reader refuses ("slice 2 integrates to inf").
#[test]
fn a_reencoded_file_reads_back_or_is_an_error() {
    use brdftab::measured::rgl_write::{Options, Parameterization, encode};
    let p = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/fuzz_bsdf_luminance_overflow.bsdf"
    );
    let t = TensorFile::open(p).unwrap();
    let src = RglBrdf::from_tensor(&t, None).expect("the reader accepts the input");
    let opts = Options {
        parameterization: Some(Parameterization::from_tensor(&t).unwrap()),
        ..Options::default()
    };
    match encode(&src, &opts, &brdftab::Silent) {
        Ok(f) => {
            let back = TensorFile::from_bytes("out.bsdf", f.to_bytes()).unwrap();
            if let Err(e) = RglBrdf::from_tensor(&back, None) {
                panic!("the writer wrote a file the reader refuses: {e}");
            }
        }
        Err(e) => assert!(
            matches!(e, brdftab::Error::InvalidArgument { .. }),
            "an error naming the source: {e}"
        ),
    }
}
