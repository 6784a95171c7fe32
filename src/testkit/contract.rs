//! [`check_contract`]: the `Brdf` contract, checked on one value (module docs of
//! [`crate::testkit`]).

use glam::{DVec2, DVec3};

use crate::brdf::Brdf;
use crate::geometry;
use crate::rng::Pcg32;
use crate::spectrum::{Channels, MAX_CHANNELS};

/// How hard [`check_contract`] looks.
#[derive(Debug, Clone, PartialEq)]
pub struct Contract {
    /// Random direction pairs for positivity, symmetry and batches.
    pub pairs: usize,
    /// Samples drawn at each view direction of the sampling checks (0 skips them).
    pub samples: usize,
    /// Relative tolerance of the declared symmetries: f32 rounding of the two values plus the
    /// rounding of two different computations of the same coordinates (default 1e-5).
    pub symmetry_tolerance: f64,
    /// Absolute tolerance of the declared symmetries, as a fraction of the channel's largest
    /// value over the pairs (default 1e-6). A table's linear lookup computes its angles with
    /// polynomial `atan2`/`acos` (error ≤ 2e-7 rad), so two pairs related by a symmetry land
    /// up to that far apart: |Δf| ≤ |∂f/∂φ| · 2e-7, which is large relative to f only where f
    /// is tiny and steep — negligible against the material's own scale.
    pub symmetry_floor: f64,
    /// Angular resolution of the declared symmetries, in radians (default 4e-7): a table's
    /// linear lookup computes its angles with polynomial `atan2`/`acos` (error ≤ 2e-7 rad each),
    /// so two pairs related by a symmetry may be looked up that far apart. Where f differs by
    /// more than the tolerances above, the difference must stay within f's own change when a
    /// direction turns by this angle about the normal.
    pub symmetry_angle: f64,
    /// Relative tolerance between a sample's pdf and `pdf(wi, wo)` (default 1e-7: both from
    /// f64 arithmetic; a sampler whose warps are f32 data, as an RGL file's, agrees to f32
    /// rounding through the warp, ~1e-6).
    pub pdf_tolerance: f64,
    /// Relative tolerance of `eval_batch` against `eval` (default 1e-6: a batch path may
    /// reorder the same f32 arithmetic, not approximate it differently).
    pub batch_tolerance: f64,
    /// Seed of the pairs and samples.
    pub seed: u64,
}

impl Default for Contract {
    fn default() -> Self {
        Contract {
            pairs: 2000,
            samples: 200,
            symmetry_tolerance: 1e-5,
            symmetry_floor: 1e-6,
            symmetry_angle: 4e-7,
            pdf_tolerance: 1e-7,
            batch_tolerance: 1e-6,
            seed: 1,
        }
    }
}

/// The view directions of the sampling checks: normal, moderate, steep and near-grazing, at
/// azimuths off the axes so anisotropic lobes are exercised.
pub(crate) fn views() -> [DVec3; 5] {
    [
        (0.0f64, 0.0f64),
        (30.0, 0.4),
        (60.0, 2.0),
        (80.0, -1.1),
        (88.0, 0.9),
    ]
    .map(|(t, p)| geometry::spherical(t.to_radians(), p))
}

/// At most this many violations are reported per check (one failure mode usually repeats).
const PER_CHECK: usize = 5;

/// Collects violations, `PER_CHECK` per check.
struct Log {
    all: Vec<String>,
    counts: Vec<(&'static str, usize)>,
}

impl Log {
    fn new() -> Log {
        Log {
            all: Vec::new(),
            counts: Vec::new(),
        }
    }

    #[cfg(test)]
    #[track_caller]
    fn assert_empty(self, what: &str) {
        assert!(self.all.is_empty(), "{what}:\n{}", self.all.join("\n"));
    }

    fn fail(&mut self, check: &'static str, msg: impl FnOnce() -> String) {
        let n = match self.counts.iter_mut().find(|(c, _)| *c == check) {
            Some((_, n)) => n,
            None => {
                self.counts.push((check, 0));
                &mut self.counts.last_mut().expect("just pushed").1
            }
        };
        *n += 1;
        if *n <= PER_CHECK {
            self.all.push(format!("{check}: {}", msg()));
        }
    }
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    close_abs(a, b, rel, 1e-30)
}

fn close_abs(a: f64, b: f64, rel: f64, abs: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
}

/// Checks the whole `Brdf` contract on `brdf` (module docs); `Err` lists the violations found
/// (at most five per check, each naming its check and the directions).
pub fn check_contract(brdf: &dyn Brdf, opts: &Contract) -> Result<(), Vec<String>> {
    let mut log = Log::new();
    let c = brdf.channels().len();
    if c == 0 || c > MAX_CHANNELS {
        return Err(vec![format!("channels: {c} (expected 1..={MAX_CHANNELS})")]);
    }
    let mut rng = Pcg32::new(opts.seed);
    let pairs: Vec<(DVec3, DVec3)> = (0..opts.pairs)
        .map(|_| {
            (
                geometry::uniform_hemisphere(rng.next_dvec2()),
                geometry::uniform_hemisphere(rng.next_dvec2()),
            )
        })
        .collect();
    values_and_symmetry(brdf, opts, &pairs, &mut log);
    batches(brdf, opts, &pairs, &mut log);
    bad_input(brdf, &mut log);
    lengths(brdf, opts, &pairs, &mut log);
    if opts.samples > 0 {
        sampling(brdf, opts, &views(), &mut rng, &mut log);
    }
    if let Err(e) = brdf.health() {
        log.fail("health", || e.to_string());
    }
    if log.all.is_empty() {
        Ok(())
    } else {
        let hidden: usize = log
            .counts
            .iter()
            .map(|(_, n)| n.saturating_sub(PER_CHECK))
            .sum();
        if hidden > 0 {
            log.all.push(format!("... and {hidden} more"));
        }
        Err(log.all)
    }
}

fn eval<B: Brdf + ?Sized>(brdf: &B, wi: DVec3, wo: DVec3) -> [f32; MAX_CHANNELS] {
    let mut f = [0.0f32; MAX_CHANNELS];
    brdf.eval(wi, wo, &mut f[..brdf.channels().len()]);
    f
}

/// Positivity, and the symmetries the flags declare.
fn values_and_symmetry(brdf: &dyn Brdf, opts: &Contract, pairs: &[(DVec3, DVec3)], log: &mut Log) {
    let c = brdf.channels().len();
    let flags = brdf.flags();
    let tol = opts.symmetry_tolerance;
    let mirror = |v: DVec3| DVec3::new(v.x, -v.y, v.z);
    let mut scale = [0.0f64; MAX_CHANNELS];
    for &(wi, wo) in pairs {
        let f = eval(brdf, wi, wo);
        for ch in 0..c {
            if f[ch].is_finite() {
                scale[ch] = scale[ch].max(f[ch] as f64 * opts.symmetry_floor);
            }
        }
    }
    for (k, &(wi, wo)) in pairs.iter().enumerate() {
        let f = eval(brdf, wi, wo);
        if let Some(x) = f[..c].iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
            log.fail("positive", || format!("f({wi}, {wo}) = {x}"));
        }
        let mut same = |check: &'static str, a: DVec3, b: DVec3| {
            let g = eval(brdf, a, b);
            for ch in 0..c {
                let slack = scale[ch] + 1e-30;
                if !close_abs(f[ch] as f64, g[ch] as f64, tol, slack)
                    && !close_abs(
                        f[ch] as f64,
                        g[ch] as f64,
                        tol,
                        slack + sensitivity(brdf, wi, wo, ch, opts.symmetry_angle),
                    )
                {
                    log.fail(check, || {
                        format!(
                            "channel {ch}: f({wi}, {wo}) = {} but f({a}, {b}) = {}",
                            f[ch], g[ch]
                        )
                    });
                    break;
                }
            }
        };
        if flags.reciprocal {
            same("reciprocal", wo, wi);
        }
        if flags.isotropic {
            // A rotation about the normal by an angle drawn from the pair's index.
            let a = 0.7 + k as f64 * 2.399963;
            let rot = |v: DVec3| {
                let (s, co) = a.sin_cos();
                DVec3::new(co * v.x - s * v.y, s * v.x + co * v.y, v.z)
            };
            same("isotropic", rot(wi), rot(wo));
        }
        if flags.bilateral {
            same("bilateral", mirror(wi), mirror(wo));
        }
    }
}

/// How much f's channel `ch` changes when either direction turns by ±`angle` about the normal.
fn sensitivity(brdf: &dyn Brdf, wi: DVec3, wo: DVec3, ch: usize, angle: f64) -> f64 {
    let f = eval(brdf, wi, wo)[ch] as f64;
    let turn = |v: DVec3, a: f64| {
        let (s, c) = a.sin_cos();
        DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
    };
    [
        (turn(wi, angle), wo),
        (turn(wi, -angle), wo),
        (wi, turn(wo, angle)),
        (wi, turn(wo, -angle)),
    ]
    .iter()
    .map(|&(a, b)| (eval(brdf, a, b)[ch] as f64 - f).abs())
    .fold(0.0, f64::max)
}

/// `eval_batch` against `eval` and `sample_batch` against `sample`, pair by pair
/// (unnormalized, below-horizon and, for sampling, non-finite views included).
/// `eval_at_wavelengths` is `eval_wavelength` at each wavelength (as f32), bit for bit, on
/// pairs of every kind: wavelengths inside, between and outside the channels, one and many.
fn at_wavelengths(brdf: &dyn Brdf, pairs: &[(DVec3, DVec3)], log: &mut Log) {
    let mut nm: Vec<f64> = vec![380.0, 450.0, 517.3, 550.0, 612.5, 700.0, 830.0];
    nm.extend((0..brdf.channels().len()).map(|i| brdf.channels().wavelength(i)));
    let mut out = vec![0.0f32; nm.len()];
    for (k, &(a, b)) in pairs.iter().enumerate().take(400) {
        let (wi, wo) = match k % 7 {
            0 => (a, DVec3::new(b.x, b.y, -b.z)),
            1 => (a * 3.5, b * 0.25),
            _ => (a, b),
        };
        let n = 1 + k % nm.len();
        brdf.eval_at_wavelengths(wi, wo, &nm[..n], &mut out[..n]);
        for (j, &x) in nm[..n].iter().enumerate() {
            let want = brdf.eval_wavelength(wi, wo, x) as f32;
            if out[j].to_bits() != want.to_bits() {
                log.fail("eval_at_wavelengths", || {
                    format!(
                        "({wi}, {wo}) at {x} nm: {} vs eval_wavelength's {want}",
                        out[j]
                    )
                });
            }
        }
    }
}

/// At a non-wavelength (NaN, ±∞, 0, < 0 nm) `eval_wavelength`, `eval_at_wavelengths` and the
/// weights of `sample_wavelengths` are NaN, on pairs of every kind ([`Brdf::eval_wavelength`]):
/// never a value a renderer could take for data.
fn at_non_wavelengths(brdf: &dyn Brdf, pairs: &[(DVec3, DVec3)], log: &mut Log) {
    let bad = [
        f64::NAN,
        0.0,
        -0.0,
        -550.0,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut out = [0.0f32; 7];
    for (k, &(a, b)) in pairs.iter().enumerate().take(50) {
        let (wi, wo) = match k % 5 {
            0 => (a, DVec3::new(b.x, b.y, -b.z)),
            _ => (a, b),
        };
        // One real wavelength among them keeps its value.
        let nm = [bad[0], bad[1], bad[2], 550.0, bad[3], bad[4], bad[5]];
        brdf.eval_at_wavelengths(wi, wo, &nm, &mut out);
        for (j, &x) in nm.iter().enumerate() {
            let f = brdf.eval_wavelength(wi, wo, x);
            if x == 550.0 {
                if out[j].to_bits() != (f as f32).to_bits() {
                    log.fail("non-wavelength", || {
                        format!("({wi}, {wo}) at 550 nm among non-wavelengths: {}", out[j])
                    });
                }
            } else if !f.is_nan() || !out[j].is_nan() {
                log.fail("non-wavelength", || {
                    format!(
                        "({wi}, {wo}) at {x} nm: eval_wavelength {f}, eval_at_wavelengths {} \
                         (NaN expected)",
                        out[j]
                    )
                });
            }
        }
        let u = DVec2::new((k as f64 + 0.5) / 50.0, 0.37);
        let mut w = [0.0f32; 6];
        if brdf.sample_wavelengths(b, u, &bad, &mut w).is_some() && w.iter().any(|v| !v.is_nan()) {
            log.fail("non-wavelength", || {
                format!("sample_wavelengths({b}, {u}) weights {w:?} at {bad:?} (NaN expected)")
            });
        }
    }
}

fn batches(brdf: &dyn Brdf, opts: &Contract, pairs: &[(DVec3, DVec3)], log: &mut Log) {
    at_wavelengths(brdf, pairs, log);
    at_non_wavelengths(brdf, pairs, log);
    let c = brdf.channels().len();
    let (wi, wo): (Vec<DVec3>, Vec<DVec3>) = pairs
        .iter()
        .enumerate()
        .map(|(k, &(a, b))| match k % 13 {
            0 => (a, DVec3::new(b.x, b.y, -b.z)),
            1 => (a * 3.5, b * 0.25),
            _ => (a, b),
        })
        .unzip();
    let mut out = vec![0.0f32; wi.len() * c];
    brdf.eval_batch(&wi, &wo, &mut out);
    for (k, got) in out.chunks_exact(c).enumerate() {
        let want = eval(brdf, wi[k], wo[k]);
        if (0..c).any(|ch| !close(got[ch] as f64, want[ch] as f64, opts.batch_tolerance)) {
            log.fail("eval_batch", || {
                format!(
                    "pair ({}, {}): batch {got:?} vs eval {:?}",
                    wi[k],
                    wo[k],
                    &want[..c]
                )
            });
        }
    }
    // The same views drawn from in one batch and one by one (the `u` of pair k from its wi).
    let mut wo_s = wo.clone();
    wo_s[2] = DVec3::new(f64::NAN, 0.0, 1.0);
    let u: Vec<DVec2> = wi
        .iter()
        .map(|a| DVec2::new(a.x.abs().fract(), a.y.abs().fract()))
        .collect();
    let n = wo_s.len();
    let (mut swi, mut spdf, mut sw) = (vec![DVec3::ZERO; n], vec![0.0; n], vec![0.0f32; n * c]);
    let out = crate::batch::SampleOut {
        wi: &mut swi,
        pdf: &mut spdf,
        weight: &mut sw,
    };
    brdf.sample_batch(&wo_s, &u, out);
    let mut w = [0.0f32; MAX_CHANNELS];
    for k in 0..n {
        let one = match crate::batch::drawable(wo_s[k], u[k]) {
            true => brdf.sample(wo_s[k], u[k], &mut w[..c]),
            false => None,
        };
        let got = &sw[k * c..(k + 1) * c];
        let agrees = match one {
            Some(s) => {
                (swi[k] - s.wi).length() <= opts.batch_tolerance
                    && close(spdf[k], s.pdf, opts.batch_tolerance)
                    && (0..c).all(|ch| close(got[ch] as f64, w[ch] as f64, opts.batch_tolerance))
            }
            None => swi[k] == DVec3::ZERO && spdf[k] == 0.0 && got.iter().all(|&x| x == 0.0),
        };
        if !agrees {
            log.fail("sample_batch", || {
                format!(
                    "wo {}, u {}: batch ({}, {}, {got:?}) vs sample {one:?} {:?}",
                    wo_s[k],
                    u[k],
                    swi[k],
                    spdf[k],
                    &w[..c]
                )
            });
        }
    }
}

/// Below the horizon, NaN, infinite and zero directions: f = 0, pdf = 0, no sample; no sample
/// for a `u` outside [0, 1)² either (beyond an edge, infinite or NaN).
fn bad_input<B: Brdf + ?Sized>(brdf: &B, log: &mut Log) {
    let c = brdf.channels().len();
    let up = DVec3::new(0.2, 0.1, 1.0);
    let bad = [
        DVec3::new(0.0, 0.3, -1.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(f64::NAN, 0.0, 1.0),
        DVec3::new(0.0, f64::INFINITY, 1.0),
        DVec3::ZERO,
    ];
    let transmits = brdf.flags().transmission;
    for b in bad {
        // A refractor is non-zero across the horizon; the non-finite and zero ones still give 0.
        if transmits && b.is_finite() && b != DVec3::ZERO && b.z != 0.0 {
            continue;
        }
        for (wi, wo) in [(b, up), (up, b), (b, b)] {
            let mut f = [1.0f32; MAX_CHANNELS];
            brdf.eval(wi, wo, &mut f[..c]);
            if f[..c].iter().any(|&x| x != 0.0) {
                log.fail("horizon", || format!("eval({wi}, {wo}) = {:?}", &f[..c]));
            }
            let nm = brdf.channels().wavelength(0);
            if brdf.eval_wavelength(wi, wo, nm) != 0.0 {
                log.fail("horizon", || format!("eval_wavelength({wi}, {wo}) ≠ 0"));
            }
            if brdf.pdf(wi, wo) != 0.0 {
                log.fail("horizon", || format!("pdf({wi}, {wo}) ≠ 0"));
            }
        }
        let mut w = [0.0f32; MAX_CHANNELS];
        if let Some(s) = brdf.sample(b, DVec2::new(0.3, 0.6), &mut w[..c]) {
            log.fail("horizon", || format!("sample(wo = {b}) gave {s:?}"));
        }
    }
    // A hair above the horizon (cosines a renderer's f64 directions can carry, down to the
    // smallest subnormal, 5e-324): values may overflow (f_r grows like 1/cos θ there for many
    // lobes) but are never NaN or negative — an underflowed product must not turn into 0/0,
    // nor an overflowed one times a zero factor (a Fresnel term or k_s of 0) into 0·∞.
    for z in [1e-20f64, 1e-100, 1e-200, 1e-300, f64::from_bits(1)] {
        let r = (1.0 - z * z).sqrt();
        let g = |x: f64, y: f64| DVec3::new(x * r, y * r, z);
        let pairs = [
            (g(0.0, 1.0), g(0.0, -1.0)),
            (g(0.0, 1.0), g(-0.6, -0.8)),
            (g(0.6, 0.8), g(0.6, 0.8)),
            (g(1.0, 0.0), up),
            (up, g(1.0, 0.0)),
        ];
        for (k, (wi, wo)) in pairs.into_iter().enumerate() {
            let mut f = [0.0f32; MAX_CHANNELS];
            brdf.eval(wi, wo, &mut f[..c]);
            let nm = brdf.channels().wavelength(0);
            let (fw, p) = (brdf.eval_wavelength(wi, wo, nm), brdf.pdf(wi, wo));
            if !(f[..c].iter().all(|&x| x >= 0.0) && fw >= 0.0 && p >= 0.0) {
                log.fail("horizon", || {
                    format!(
                        "a hair above it, cos {z:e}, pair {k}: eval = {:?}, at {nm} nm {fw}, pdf {p}",
                        &f[..c]
                    )
                });
            }
        }
        let mut w = [0.0f32; MAX_CHANNELS];
        if let Some(s) = brdf.sample(g(0.6, 0.8), DVec2::new(0.3, 0.6), &mut w[..c])
            && !(s.pdf > 0.0 && w[..c].iter().all(|&x| x >= 0.0))
        {
            log.fail("horizon", || {
                format!(
                    "a hair above it, cos {z:e}: sample gave {s:?} {:?}",
                    &w[..c]
                )
            });
        }
    }
    // A u outside [0, 1)² has no sample, as in `sample_batch` (a sampler that ignores u
    // included): beyond it the samplers' maps leave the unit sphere or their densities.
    for u in [
        DVec2::new(f64::NAN, 0.6),
        DVec2::new(0.3, f64::NAN),
        DVec2::new(f64::INFINITY, 0.6),
        DVec2::new(0.3, f64::NEG_INFINITY),
        DVec2::new(1.0, 0.5),
        DVec2::new(0.5, 1.0),
        DVec2::new(1.5, -0.2),
        DVec2::new(-1e-300, 0.6),
        DVec2::new(0.3, 1.0 + f64::EPSILON),
    ] {
        let mut w = [0.0f32; MAX_CHANNELS];
        if let Some(s) = brdf.sample(up, u, &mut w[..c]) {
            log.fail("horizon", || {
                format!("sample(wo = {up}, u = {u}) gave {s:?}")
            });
        }
    }
}

/// Directions of any finite nonzero length are directions: scaled by 1e-300 … 1e300 (squared
/// lengths that underflow to 0 or overflow to ∞; they gave 0 in `eval` and `pdf` while the
/// samplers that look only at the sign of cos θo drew), every output equals the unit pair's.
fn lengths<B: Brdf + ?Sized>(brdf: &B, opts: &Contract, pairs: &[(DVec3, DVec3)], log: &mut Log) {
    let c = brdf.channels().len();
    let nm = brdf.channels().wavelength(0);
    // Scaling and normalizing again moves each component by a few ulps: the tolerances of two
    // computations of the same coordinates.
    let (rel, prel) = (opts.symmetry_tolerance, opts.symmetry_tolerance);
    for &(wi, wo) in pairs.iter().take(40) {
        let (f, p, fw) = (
            eval(brdf, wi, wo),
            brdf.pdf(wi, wo),
            brdf.eval_wavelength(wi, wo, nm),
        );
        for k in [1e-300, 1e-160, 3.0, 1e160, 1e300] {
            for (a, b) in [(wi * k, wo), (wi, wo * k), (wi * k, wo * k)] {
                let g = eval(brdf, a, b);
                let (q, gw) = (brdf.pdf(a, b), brdf.eval_wavelength(a, b, nm));
                let same = (0..c).all(|ch| close(f[ch] as f64, g[ch] as f64, rel))
                    && close(p, q, prel)
                    && close(fw, gw, rel);
                if !same {
                    log.fail("lengths", || {
                        format!(
                            "({}, {}): f {:?}, pdf {q}, at {nm} nm {gw}; unit: {:?}, {p}, {fw}",
                            sci(a),
                            sci(b),
                            &g[..c],
                            &f[..c]
                        )
                    });
                }
            }
        }
    }
    let u = DVec2::new(0.3, 0.6);
    for wo in views() {
        let mut w = [0.0f32; MAX_CHANNELS];
        let s = brdf.sample(wo, u, &mut w[..c]);
        for k in [1e-300, 1e-160, 1e160, 1e300] {
            let mut v = [0.0f32; MAX_CHANNELS];
            let t = brdf.sample(wo * k, u, &mut v[..c]);
            let same = match (s, t) {
                (None, None) => true,
                (Some(s), Some(t)) => {
                    (s.wi - t.wi).length() < 1e-9
                        && close(s.pdf, t.pdf, prel)
                        && (0..c).all(|ch| close(w[ch] as f64, v[ch] as f64, rel))
                }
                _ => false,
            };
            if !same {
                log.fail("lengths", || {
                    format!("sample(wo {wo} × {k:e}) = {t:?} {:?}; unit: {s:?}", &v[..c])
                });
            }
        }
    }
}

/// A vector in scientific notation (the lengths check's are far from 1).
fn sci(v: DVec3) -> String {
    format!("[{:e}, {:e}, {:e}]", v.x, v.y, v.z)
}

/// The bad-input part of the contract alone, panicking with the violations (the crate's model
/// tests).
#[cfg(test)]
#[track_caller]
pub(crate) fn assert_bad_input_gives_zero<B: Brdf + ?Sized>(brdf: &B) {
    let mut log = Log::new();
    bad_input(brdf, &mut log);
    log.assert_empty(&brdf.describe());
}

/// The sampling part of the contract alone, `n` samples at each of `wos`, panicking with the
/// violations (the crate's model tests).
#[cfg(test)]
#[track_caller]
pub(crate) fn assert_sampling_consistent<B: Brdf + ?Sized>(brdf: &B, wos: &[DVec3], n: usize) {
    let opts = Contract {
        samples: n,
        ..Contract::default()
    };
    let mut log = Log::new();
    sampling(brdf, &opts, wos, &mut Pcg32::new(5), &mut log);
    log.assert_empty(&brdf.describe());
}

/// Samples against pdf and eval at each of [`views`].
fn sampling<B: Brdf + ?Sized>(
    brdf: &B,
    opts: &Contract,
    wos: &[DVec3],
    rng: &mut Pcg32,
    log: &mut Log,
) {
    let c = brdf.channels().len();
    let delta = brdf.flags().delta;
    for &wo in wos {
        let mut got = 0;
        for _ in 0..opts.samples {
            let mut w = [0.0f32; MAX_CHANNELS];
            let u = rng.next_dvec2();
            let Some(s) = brdf.sample(wo, u, &mut w[..c]) else {
                continue;
            };
            got += 1;
            spectral_sample(brdf, wo, u, &s, &w[..c], log);
            if !((s.wi.length() - 1.0).abs() < 1e-9 && s.wi.is_finite()) {
                log.fail("sample", || format!("wo {wo}: wi {} not unit", s.wi));
                continue;
            }
            if w[..c].iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
                log.fail("sample", || format!("wo {wo}: weight {:?}", &w[..c]));
            }
            if s.delta || delta {
                if !s.delta {
                    log.fail("sample", || {
                        format!("wo {wo}: a delta BRDF's sample not delta")
                    });
                }
                continue;
            }
            if !brdf.flags().transmission && s.wi.z <= 0.0 {
                log.fail("sample", || {
                    format!("wo {wo}: wi {} below the horizon", s.wi)
                });
            }
            let pdf = brdf.pdf(s.wi, wo);
            if !close(s.pdf, pdf, opts.pdf_tolerance) || !(pdf > 0.0) {
                log.fail("pdf", || {
                    format!(
                        "wo {wo}, wi {}: sample's pdf {} vs pdf() {pdf}",
                        s.wi, s.pdf
                    )
                });
            }
            let f = eval(brdf, s.wi, wo);
            let mut f2 = [0.0f32; MAX_CHANNELS];
            let p2 = brdf.eval_pdf(s.wi, wo, &mut f2[..c]);
            if !close(p2, pdf, 1e-12) || (0..c).any(|k| !close(f2[k] as f64, f[k] as f64, 1e-6)) {
                log.fail("eval_pdf", || {
                    format!(
                        "wo {wo}, wi {}: eval_pdf ({p2}, {:?}) vs pdf {pdf}, eval {:?}",
                        s.wi,
                        &f2[..c],
                        &f[..c]
                    )
                });
            }
            for k in 0..c {
                let want = f[k] as f64 * s.wi.z.abs() / s.pdf;
                if !close(w[k] as f64, want, 1e-5) {
                    log.fail("weight", || {
                        format!(
                            "wo {wo}, wi {}: channel {k} weight {} vs f cos θi / pdf {want}",
                            s.wi, w[k]
                        )
                    });
                }
            }
        }
        if got * 4 < opts.samples {
            log.fail("sample", || {
                format!("wo {wo}: only {got} of {} samples drawn", opts.samples)
            });
        }
    }
}

/// `sample_wavelengths` makes `sample`'s draw, weighs a smooth draw by `eval_wavelength`, and at
/// the channels' own wavelengths (sources of wavelength channels) gives `sample`'s weights.
fn spectral_sample<B: Brdf + ?Sized>(
    brdf: &B,
    wo: DVec3,
    u: DVec2,
    s: &crate::brdf::BrdfSample,
    w: &[f32],
    log: &mut Log,
) {
    let nm = match brdf.channels() {
        Channels::Wavelengths(nm) => nm.clone(),
        Channels::Rgb => vec![450.0, 550.0, 650.0],
    };
    let mut ws = [0.0f32; MAX_CHANNELS];
    let got = brdf.sample_wavelengths(wo, u, &nm, &mut ws[..nm.len()]);
    if got != Some(*s) {
        log.fail("sample_wavelengths", || {
            format!("wo {wo}, u {u}: draw {got:?} vs sample's {s:?}")
        });
        return;
    }
    if !s.delta {
        // A smooth draw: f_r at each wavelength, cos θi / pdf.
        for (k, &x) in nm.iter().enumerate() {
            let want = brdf.eval_wavelength(s.wi, wo, x) * s.wi.z.abs() / s.pdf;
            if !close_abs(ws[k] as f64, want, 1e-5, 1e-7) {
                log.fail("sample_wavelengths", || {
                    format!(
                        "wo {wo}, u {u}: weight {} at {x} nm vs f cos θi / pdf {want}",
                        ws[k]
                    )
                });
            }
        }
    }
    if let Channels::Wavelengths(_) = brdf.channels() {
        for (k, (&a, &b)) in ws.iter().zip(w).enumerate() {
            if !close_abs(a as f64, b as f64, 1e-5, 1e-7) {
                log.fail("sample_wavelengths", || {
                    format!("wo {wo}, u {u}: weight {a} at {} nm vs sample's {b}", nm[k])
                });
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::{BrdfSample, Flags};
    use crate::spectrum::Channels;

    /// Lambert (kd = 0.3) with one flaw.
    struct Flawed(&'static str);

    impl Brdf for Flawed {
        fn channels(&self) -> &Channels {
            &Channels::Rgb
        }
        fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
            let ok = |v: DVec3| v.is_finite() && v.z > 0.0;
            let v = if !(ok(wi) && ok(wo)) && self.0 != "horizon" {
                0.0
            } else {
                match self.0 {
                    "negative" if wi.x > 0.5 => -0.1,
                    "reciprocal" => 0.3 + 0.1 * wi.z as f32,
                    "isotropic" => 0.3 + 0.1 * wi.x as f32,
                    _ => 0.3,
                }
            };
            out.fill(v);
        }
        fn eval_batch(&self, wi: &[DVec3], wo: &[DVec3], out: &mut [f32]) {
            for ((a, b), o) in wi.iter().zip(wo).zip(out.chunks_exact_mut(3)) {
                self.eval(*a, *b, o);
                if self.0 == "batch" {
                    o[0] *= 1.001;
                }
            }
        }
        fn flags(&self) -> Flags {
            Flags::SMOOTH_SYMMETRIC
        }
        fn describe(&self) -> String {
            self.0.into()
        }
        fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
            let p = match (geometry::unit(wi), geometry::unit(wo)) {
                (Some(i), Some(o)) if i.z > 0.0 && o.z > 0.0 => i.z / std::f64::consts::PI,
                _ => 0.0,
            };
            if self.0 == "pdf" { p * 1.01 } else { p }
        }
        fn sample(&self, wo: DVec3, u: DVec2, w: &mut [f32]) -> Option<BrdfSample> {
            let o = geometry::unit(wo)?;
            // "square": draws from any finite u, as the Phong family once did.
            let drawable = match self.0 {
                "square" => u.is_finite(),
                _ => geometry::in_unit_square(u),
            };
            if o.z <= 0.0 || !drawable {
                return None;
            }
            let wi = geometry::cosine_hemisphere(u);
            let pdf = wi.z / std::f64::consts::PI;
            let k = if self.0 == "weight" { 1.1 } else { 1.0 };
            w.fill((0.3 * std::f64::consts::PI * k) as f32);
            Some(BrdfSample {
                wi,
                pdf,
                delta: false,
            })
        }
    }

    #[test]
    fn each_flaw_is_caught_by_its_check_and_lambert_passes() {
        let quick = Contract {
            pairs: 300,
            samples: 50,
            ..Contract::default()
        };
        assert_eq!(check_contract(&Flawed("none"), &quick), Ok(()));
        for flaw in [
            "negative",
            "reciprocal",
            "isotropic",
            "batch",
            "horizon",
            "pdf",
            "weight",
            "square",
        ] {
            let v = check_contract(&Flawed(flaw), &quick).expect_err(flaw);
            let check = match flaw {
                "negative" => "positive",
                "batch" => "eval_batch",
                "square" => "horizon",
                f => f,
            };
            assert!(v.iter().any(|m| m.starts_with(check)), "{flaw}: {v:?}");
        }
    }
}
