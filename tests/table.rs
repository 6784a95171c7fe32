//! Dense tables: baking, symmetry reduction, lookup — as specifications.

use brdftab::analysis::accuracy;
use brdftab::geometry::{self, spherical};
use brdftab::models::lambert::Lambert;
use brdftab::table::{
    Axis, BakeOptions, ChunkLoader, Grid, Interp, Mapping, Nodes, Param, Symmetry, Table,
    TabulatedBrdf, bake, bake_chunks, pair_of, symmetry,
};
use brdftab::testkit::{Pcg32, TempDir};
use brdftab::{Brdf, Channels, Error, Flags, Result, Value};
use glam::DVec3;
use proptest::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

const SCALE: [f32; 3] = [1.0, 0.5, 0.25];

/// A smooth source with every symmetry: a reciprocal-Phong-like lobe plus a diffuse term.
struct Symmetric;
impl Brdf for Symmetric {
    fn channels(&self) -> &Channels {
        &Channels::Rgb
    }
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let Some((wi, wo)) = geometry::upper_pair(wi, wo) else {
            out[..3].fill(0.0);
            return;
        };
        let c = (geometry::reflect_z(wi).dot(wo)).max(0.0);
        let f = 0.2 + 2.0 * c.powi(8) + 0.3 * (wi.z * wo.z);
        for k in 0..3 {
            out[k] = f as f32 * SCALE[k];
        }
    }
    fn flags(&self) -> Flags {
        Flags::SMOOTH_SYMMETRIC
    }
    fn describe(&self) -> String {
        "symmetric test lobe".into()
    }
}

/// An anisotropic source that is reciprocal and bilateral (depends on x², not x·y).
struct Aniso;
impl Brdf for Aniso {
    fn channels(&self) -> &Channels {
        &Channels::Rgb
    }
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let Some((wi, wo)) = geometry::upper_pair(wi, wo) else {
            out[..3].fill(0.0);
            return;
        };
        let h = (wi + wo).normalize();
        let f = 0.1 + (-(h.x * h.x * 8.0 + h.y * h.y * 2.0)).exp() + 0.2 * wi.z * wo.z;
        for k in 0..3 {
            out[k] = f as f32 * SCALE[k];
        }
    }
    fn flags(&self) -> Flags {
        Flags {
            isotropic: false,
            ..Flags::SMOOTH_SYMMETRIC
        }
    }
    fn describe(&self) -> String {
        "anisotropic test lobe".into()
    }
}

/// Not reciprocal: depends on wi only.
struct OneSided;
impl Brdf for OneSided {
    fn channels(&self) -> &Channels {
        &Channels::Rgb
    }
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let v = if wi.z > 0.0 && wo.z > 0.0 {
            (1.0 + wi.z) as f32
        } else {
            0.0
        };
        out[..3].fill(v);
    }
    fn flags(&self) -> Flags {
        Flags::SMOOTH_SYMMETRIC // lies about reciprocity
    }
    fn describe(&self) -> String {
        "one-sided".into()
    }
}

/// A source that is multilinear in the stored fractional indices of `grid`.
struct Multilinear(Grid);
impl Multilinear {
    fn g(s: [f64; 4]) -> f64 {
        // φ terms vanish where the φ angle is undefined (θ = 0 nodes).
        1.0 + 0.3 * s[0]
            + 0.2 * s[2]
            + 0.01 * s[0] * s[2]
            + 0.05 * s[0] * s[2] * s[3]
            + 0.1 * s[0] * s[1]
            + 0.003 * s[0] * s[1] * s[2]
    }
}
impl Brdf for Multilinear {
    fn channels(&self) -> &Channels {
        self.0.channels()
    }
    fn eval(&self, wi: DVec3, wo: DVec3, out: &mut [f32]) {
        let g = &self.0;
        let Some(x) = symmetry::canonical_coords(g.param(), g.symmetry(), wi, wo) else {
            out[..3].fill(0.0);
            return;
        };
        let ax = g.stored_axes();
        // Periodic axes: s in [0, n) with values a hair below n (rounding at node 0) snapped to 0.
        let s = [0, 1, 2, 3].map(|k| {
            let s = ax[k].continuous(x[k]);
            let n = ax[k].size as f64;
            if ax[k].periodic && s > n - 1e-6 {
                s - n
            } else {
                s
            }
        });
        let f = Self::g(s);
        for k in 0..3 {
            out[k] = f as f32 * SCALE[k];
        }
    }
    fn flags(&self) -> Flags {
        Flags::default()
    }
    fn describe(&self) -> String {
        "multilinear".into()
    }
}

fn sym(i: bool, r: bool, b: bool) -> Symmetry {
    Symmetry {
        isotropic: i,
        reciprocal: r,
        bilateral: b,
    }
}

fn grid(param: Param, sizes: [usize; 4], s: Symmetry) -> Grid {
    let m = match param {
        Param::HalfDiff => [Mapping::Sqrt, Mapping::Uniform],
        Param::InOut => [Mapping::Cos, Mapping::Cos],
    };
    Grid::with_sizes(param, sizes, m, Channels::Rgb, s).unwrap()
}

fn tab(src: &dyn Brdf, g: &Grid, interp: Interp) -> TabulatedBrdf {
    let (t, _) = bake(src, g, &BakeOptions::default()).unwrap();
    TabulatedBrdf::from_table(t).with_interp(interp)
}

fn eval3(b: &dyn Brdf, wi: DVec3, wo: DVec3) -> [f32; 3] {
    let mut f = [0.0; 3];
    b.eval(wi, wo, &mut f);
    f
}

fn close(a: [f32; 3], b: [f32; 3], tol: f32) -> bool {
    a.iter()
        .zip(&b)
        .all(|(x, y)| (x - y).abs() <= tol * x.abs().max(y.abs()).max(1e-6))
}

fn random_pair(rng: &mut Pcg32) -> (DVec3, DVec3) {
    (
        geometry::uniform_hemisphere(rng.next_dvec2()),
        geometry::uniform_hemisphere(rng.next_dvec2()),
    )
}

// ---------------------------------------------------------------------------------------------
// Symmetry reduction is exact.

/// Reductions that commute with interpolation: a table reduced by reciprocity and bilateral
/// symmetry (on top of the same base) returns the same value as the unreduced one for any pair.
#[test]
fn reciprocity_and_bilateral_reduction_are_exact_for_any_pair() {
    let cases: Vec<(Param, [usize; 4], bool, &dyn Brdf)> = vec![
        (Param::HalfDiff, [12, 16, 10, 16], true, &Symmetric),
        (Param::InOut, [10, 16, 10, 16], true, &Symmetric),
        (Param::HalfDiff, [8, 16, 8, 16], false, &Aniso),
        (Param::InOut, [6, 12, 6, 12], false, &Aniso),
    ];
    for (param, sizes, iso, src) in cases {
        for interp in [Interp::Linear, Interp::Nearest] {
            let base = tab(src, &grid(param, sizes, sym(iso, false, false)), interp);
            for s in [
                sym(iso, true, false),
                sym(iso, false, true),
                sym(iso, true, true),
            ] {
                let red = tab(src, &grid(param, sizes, s), interp);
                assert!(red.grid().stored_values() < base.grid().stored_values());
                let mut rng = Pcg32::new(9);
                for _ in 0..20_000 {
                    let (wi, wo) = random_pair(&mut rng);
                    let (a, b) = (eval3(&base, wi, wo), eval3(&red, wi, wo));
                    // Nearest may pick the other node at an exact tie (measure zero); linear is
                    // exact up to rounding.
                    assert!(
                        close(a, b, 2e-5),
                        "{param:?} {s} {interp:?} wi={wi} wo={wo}: {a:?} vs {b:?}"
                    );
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Isotropy: on node-aligned pairs (φi and φo on full φ nodes, θ on nodes) the isotropic
    /// table returns the unreduced table's value, for any common rotation by a node multiple.
    #[test]
    fn isotropic_reduction_matches_full_table_on_nodes(
        a in 0usize..8, b in 0usize..8, p in 0usize..16, q in 0usize..16,
        ar in 0usize..8, br in 0usize..8, pr in 0usize..16, qr in 0usize..16,
        halfdiff in any::<bool>(),
    ) {
        let param = if halfdiff { Param::HalfDiff } else { Param::InOut };
        let sizes = [8, 16, 8, 16];
        thread_local! {
            static T: std::cell::RefCell<Option<Vec<TabulatedBrdf>>> = const { std::cell::RefCell::new(None) };
        }
        let full_g = grid(param, sizes, Symmetry::NONE);
        let ax = full_g.stored_axes().clone();
        let coords = [ax[0].node(a), ax[1].node(p), ax[2].node(b), ax[3].node(q)];
        let coords_r = [ax[0].node(ar), ax[1].node(pr), ax[2].node(br), ax[3].node(qr)];
        T.with(|t| {
            let mut t = t.borrow_mut();
            let tables = t.get_or_insert_with(Vec::new);
            if tables.is_empty() {
                for hd in [false, true] {
                    let pm = if hd { Param::HalfDiff } else { Param::InOut };
                    tables.push(tab(&Symmetric, &grid(pm, sizes, Symmetry::NONE), Interp::Nearest));
                    tables.push(tab(&Symmetric, &grid(pm, sizes, Symmetry::ALL), Interp::Nearest));
                }
            }
            let k = if halfdiff { 2 } else { 0 };
            for c in [coords, coords_r] {
                let (wi, wo) = pair_of(param, c);
                if wi.z <= 2e-3 || wo.z <= 2e-3 { continue; }
                let f = eval3(&tables[k], wi, wo);
                let r = eval3(&tables[k + 1], wi, wo);
                prop_assert!(close(f, r, 1e-4), "{param:?} {c:?}: {f:?} vs {r:?}");
            }
            Ok(())
        })?;
    }

    /// The canonical map is a function of the orbit: a pair, its swap, its mirror image and a
    /// rotated copy give the same canonical coordinates.
    #[test]
    fn canonical_coords_are_invariant(
        ti in 0.01f64..1.55, pi in 0.0f64..TAU, to in 0.01f64..1.55, po in 0.0f64..TAU,
        rot in 0.0f64..TAU, halfdiff in any::<bool>(),
    ) {
        let param = if halfdiff { Param::HalfDiff } else { Param::InOut };
        let (wi, wo) = (spherical(ti, pi), spherical(to, po));
        let s = Symmetry::ALL;
        let c = symmetry::canonical_coords(param, s, wi, wo).unwrap();
        let (sr, cr) = rot.sin_cos();
        let r = |v: DVec3| DVec3::new(cr * v.x - sr * v.y, sr * v.x + cr * v.y, v.z);
        let m = |v: DVec3| DVec3::new(v.x, -v.y, v.z);
        for (a, b) in [(wo, wi), (m(wi), m(wo)), (r(wi), r(wo)), (m(r(wo)), m(r(wi)))] {
            let d = symmetry::canonical_coords(param, s, a, b).unwrap();
            for k in 0..4 {
                prop_assert!((c[k] - d[k]).abs() < 1e-9, "{param:?} {c:?} vs {d:?}");
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Lookup.

#[test]
fn nearest_lookup_at_nodes_returns_the_baked_values() {
    let grids = [
        grid(Param::HalfDiff, [12, 16, 10, 16], Symmetry::ALL),
        grid(Param::HalfDiff, [6, 8, 6, 8], Symmetry::NONE),
        grid(Param::InOut, [10, 16, 10, 16], Symmetry::ALL),
        grid(Param::InOut, [6, 8, 6, 8], sym(false, true, true)),
        grid(Param::InOut, [6, 8, 5, 8], Symmetry::NONE),
    ];
    for g in grids {
        let src: &dyn Brdf = if g.symmetry().isotropic {
            &Symmetric
        } else {
            &Aniso
        };
        let (t, _) = bake(src, &g, &BakeOptions::default()).unwrap();
        let tb = TabulatedBrdf::from_table(t.clone()).with_interp(Interp::Nearest);
        let [n0, s1, n2, s3] = g.stored_shape();
        let mut checked = 0;
        for a in 0..n0 {
            for p in 0..s1 {
                for b in 0..n2 {
                    for q in 0..s3 {
                        let Some(v) = t.node([a, p, b, q]) else {
                            continue;
                        };
                        let (wi, wo) = pair_of(g.param(), g.node_angles([a, p, b, q]));
                        if wi.z <= 2e-3 || wo.z <= 2e-3 {
                            continue; // lifted below-horizon node
                        }
                        let f = eval3(&tb, wi, wo);
                        assert_eq!(&f[..], v, "{} node {:?}", g.summary(), [a, p, b, q]);
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 100, "{checked}");
    }
}

#[test]
fn linear_interpolation_reproduces_multilinear_functions() {
    let edges = |param, sizes: [usize; 4], s, m: [Mapping; 2]| {
        Grid::new(
            param,
            [
                Axis::theta(sizes[0], m[0].clone(), Nodes::Edges),
                Axis::phi(sizes[1]),
                Axis::theta(sizes[2], m[1].clone(), Nodes::Edges),
                Axis::phi(sizes[3]),
            ],
            Channels::Rgb,
            s,
        )
        .unwrap()
    };
    let grids = [
        // Every stored axis non-periodic: exact everywhere.
        edges(
            Param::HalfDiff,
            [9, 16, 7, 16],
            Symmetry::ALL,
            [Mapping::Sqrt, Mapping::Uniform],
        ),
        edges(
            Param::HalfDiff,
            [9, 16, 7, 16],
            Symmetry::ALL,
            [Mapping::Cos, Mapping::Sqrt],
        ),
        edges(
            Param::InOut,
            [7, 16, 9, 24],
            sym(true, false, true),
            [Mapping::Uniform, Mapping::Cos],
        ),
        // Periodic axes: exact away from the wrap-around cell.
        edges(
            Param::InOut,
            [5, 8, 6, 8],
            Symmetry::NONE,
            [Mapping::Uniform, Mapping::Uniform],
        ),
        edges(
            Param::HalfDiff,
            [5, 8, 6, 12],
            sym(false, true, false),
            [Mapping::Sqrt, Mapping::Uniform],
        ),
    ];
    for g in grids {
        let src = Multilinear(g.clone());
        let tb = tab(&src, &g, Interp::Linear);
        let ax = g.stored_axes().clone();
        let mut rng = Pcg32::new(1);
        let mut n = 0;
        while n < 20_000 {
            let (wi, wo) = random_pair(&mut rng);
            let x = symmetry::canonical_coords(g.param(), g.symmetry(), wi, wo).unwrap();
            if (0..4).any(|k| ax[k].periodic && ax[k].continuous(x[k]) >= (ax[k].size - 1) as f64) {
                continue;
            }
            // Nodes outside the physical domain are baked at a lifted pair: stay clear of them.
            let cell_ok = {
                let (lo, hi) = (ax[0].linear(x[0]), ax[2].linear(x[2]));
                let s = |k: usize, i: usize| ax[k].node(i);
                [lo.0, lo.1].iter().all(|&i| {
                    [hi.0, hi.1].iter().all(|&j| match g.param() {
                        Param::HalfDiff => s(0, i) + s(2, j) < FRAC_PI_2 - 1e-3,
                        Param::InOut => i + 1 < ax[0].size && j + 1 < ax[2].size,
                    })
                })
            };
            if !cell_ok {
                continue;
            }
            n += 1;
            let got = eval3(&tb, wi, wo);
            let want = eval3(&src, wi, wo);
            assert!(
                close(got, want, 2e-5),
                "{} wi={wi} wo={wo}: {got:?} vs {want:?}",
                g.summary()
            );
        }
    }
}

#[test]
fn lambert_tables_are_exact() {
    let l = Lambert::new(Value::Rgb([0.1, 0.2, 0.3]), &Channels::Rgb).unwrap();
    let grids = [
        Grid::merl(Channels::Rgb),
        grid(Param::HalfDiff, [16, 32, 16, 32], Symmetry::ALL),
        grid(Param::InOut, [8, 16, 8, 16], Symmetry::ALL),
        grid(Param::InOut, [4, 8, 4, 8], Symmetry::NONE),
    ];
    for g in grids {
        for interp in [Interp::Nearest, Interp::Linear] {
            let tb = tab(&l, &g, interp);
            let acc = accuracy::compare(&tb, &l, 20_000, 3).unwrap();
            assert!(acc.max_rel < 1e-6, "{} {interp:?}: {acc:?}", g.summary());
        }
    }
}

#[test]
fn merl_grid_nearest_lookup_reproduces_the_merl_reader() {
    // The MERL reader (BRDFRead.cpp), transcribed: angles → indices.
    fn rotate(v: [f64; 3], axis: [f64; 3], ang: f64) -> [f64; 3] {
        let (s, c) = ang.sin_cos();
        let d = axis[0] * v[0] + axis[1] * v[1] + axis[2] * v[2];
        let cr = [
            axis[1] * v[2] - axis[2] * v[1],
            axis[2] * v[0] - axis[0] * v[2],
            axis[0] * v[1] - axis[1] * v[0],
        ];
        [0, 1, 2].map(|k| v[k] * c + axis[k] * d * (1.0 - c) + cr[k] * s)
    }
    fn merl_index(ti: f64, pi: f64, to: f64, po: f64) -> usize {
        let vin = [ti.sin() * pi.cos(), ti.sin() * pi.sin(), ti.cos()];
        let vout = [to.sin() * po.cos(), to.sin() * po.sin(), to.cos()];
        let h = [0, 1, 2].map(|k| (vin[k] + vout[k]) / 2.0);
        let n = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
        let h = h.map(|x| x / n);
        let th = h[2].acos();
        let ph = h[1].atan2(h[0]);
        let tmp = rotate(vin, [0.0, 0.0, 1.0], -ph);
        let d = rotate(tmp, [0.0, 1.0, 0.0], -th);
        let td = d[2].acos();
        let mut pd = d[1].atan2(d[0]);
        let ih = if th <= 0.0 {
            0
        } else {
            ((((th / (PI / 2.0)) * 90.0) * 90.0).sqrt() as i64).clamp(0, 89) as usize
        };
        let id = ((td / (PI * 0.5) * 90.0) as i64).clamp(0, 89) as usize;
        if pd < 0.0 {
            pd += PI;
        }
        let ip = ((pd / PI * 180.0) as i64).clamp(0, 179) as usize;
        ip + id * 180 + ih * 180 * 90
    }
    let g = Grid::merl(Channels::wavelengths(vec![550.0]).unwrap());
    // The value of every node is its MERL index.
    let t = Table::from_fn(g, "index", |idx, _, out| {
        out[0] = (idx[3] + idx[2] * 180 + idx[0] * 180 * 90) as f32;
    });
    let tb = TabulatedBrdf::from_table(t).with_interp(Interp::Nearest);
    let mut rng = Pcg32::new(77);
    let mut mismatches = 0;
    for _ in 0..200_000 {
        let (ti, to) = (rng.next_f64() * FRAC_PI_2, rng.next_f64() * FRAC_PI_2);
        let (pi, po) = (rng.next_f64() * TAU - PI, rng.next_f64() * TAU - PI);
        let mut f = [0.0f32];
        tb.eval(spherical(ti, pi), spherical(to, po), &mut f);
        if f[0] as usize != merl_index(ti, pi, to, po) {
            mismatches += 1;
        }
    }
    // Our half/diff vectors use vector algebra, MERL's trigonometry: indices may differ where an
    // angle is within ~1e-15 of a cell boundary.
    assert!(mismatches <= 2, "{mismatches} mismatches");
}

// ---------------------------------------------------------------------------------------------
// Baking.

#[test]
fn symmetry_violation_is_an_error_unless_forced() {
    let g = grid(Param::HalfDiff, [8, 16, 8, 16], Symmetry::ALL);
    let e = bake(&OneSided, &g, &BakeOptions::default()).unwrap_err();
    assert!(
        matches!(
            &e,
            Error::Symmetry {
                symmetry: brdftab::error::SymmetryKind::Reciprocal,
                ..
            }
        ),
        "{e}"
    );
    let g = grid(Param::HalfDiff, [8, 16, 8, 16], sym(true, false, false));
    let e = bake(&Aniso, &g, &BakeOptions::default()).unwrap_err();
    assert!(
        matches!(
            &e,
            Error::Symmetry {
                symmetry: brdftab::error::SymmetryKind::Isotropic,
                ..
            }
        ),
        "{e}"
    );
    let forced = BakeOptions {
        force: true,
        ..Default::default()
    };
    let (_, report) = bake(&Aniso, &g, &forced).unwrap();
    assert!(report.forced.is_some());
    // Detection agrees.
    assert_eq!(symmetry::detect(&Aniso, 1e-3), sym(false, true, true));
    assert_eq!(symmetry::detect(&OneSided, 1e-3), sym(true, false, true));
    assert_eq!(symmetry::detect(&Symmetric, 1e-3), Symmetry::ALL);
}

#[test]
fn chunked_bake_equals_in_memory_bake() {
    for g in [
        grid(Param::InOut, [9, 16, 9, 16], Symmetry::ALL),
        grid(Param::HalfDiff, [10, 16, 8, 16], sym(true, true, false)),
    ] {
        let (t, _) = bake(&Symmetric, &g, &BakeOptions::default()).unwrap();
        let opts = BakeOptions {
            memory_budget: 1000, // a few chunks per group
            supersample: 1,
            ..Default::default()
        };
        let mut next = 0;
        let mut all = Vec::new();
        bake_chunks(&Symmetric, &g, &opts, |i, v| {
            assert_eq!(i, next);
            assert_eq!(v.len(), g.layout().chunk_len(i));
            assert_eq!(v, t.chunk(i));
            next += 1;
            all.extend_from_slice(v);
            Ok(())
        })
        .unwrap();
        assert_eq!(next, g.layout().chunk_count());
        assert_eq!(all, t.values());
    }
}

#[test]
fn sink_errors_stop_the_bake() {
    let g = grid(Param::HalfDiff, [8, 16, 8, 16], Symmetry::ALL);
    let mut calls = 0;
    let r = bake_chunks(&Symmetric, &g, &BakeOptions::default(), |i, _| {
        calls += 1;
        if i == 2 {
            Err(Error::Unsupported("disk full".into()))
        } else {
            Ok(())
        }
    });
    assert!(r.is_err());
    assert_eq!(calls, 3);
}

#[test]
fn supersampling_averages_over_the_cell() {
    let g = grid(Param::HalfDiff, [8, 16, 8, 16], Symmetry::ALL);
    let l = Lambert::new(Value::Grey(0.3), &Channels::Rgb).unwrap();
    let opts = BakeOptions {
        supersample: 3,
        ..Default::default()
    };
    let (t, _) = bake(&l, &g, &opts).unwrap();
    assert!(t.values().iter().all(|&v| (v - 0.3).abs() < 1e-6));
    // A sharp lobe: supersampled node values are cell means, lower than the peak node.
    let (a, _) = bake(&Symmetric, &g, &BakeOptions::default()).unwrap();
    let (b, _) = bake(&Symmetric, &g, &opts).unwrap();
    assert_ne!(a.values(), b.values());
}

// ---------------------------------------------------------------------------------------------
// Storage behind chunks.

struct FromTable(Table, bool);
impl ChunkLoader for FromTable {
    fn load(&self, chunk: usize) -> Result<Vec<f32>> {
        if self.1 && chunk == 1 {
            return Err(Error::Unsupported("broken chunk".into()));
        }
        Ok(self.0.chunk(chunk).to_vec())
    }
}

#[test]
fn lazy_chunks_load_on_first_touch_and_failures_read_as_zero() {
    let g = grid(Param::HalfDiff, [8, 16, 8, 16], Symmetry::ALL);
    let (t, _) = bake(&Symmetric, &g, &BakeOptions::default()).unwrap();
    let eager = TabulatedBrdf::from_table(t.clone());
    let lazy = TabulatedBrdf::lazy(g.clone(), Box::new(FromTable(t.clone(), false)), "lazy");
    assert_eq!(lazy.loaded_chunks(), 0);
    let mut rng = Pcg32::new(4);
    for _ in 0..2000 {
        let (wi, wo) = random_pair(&mut rng);
        assert_eq!(eval3(&eager, wi, wo), eval3(&lazy, wi, wo));
    }
    assert!(lazy.load_error().is_none());
    let broken = TabulatedBrdf::lazy(g.clone(), Box::new(FromTable(t, true)), "broken")
        .with_interp(Interp::Nearest);
    // A pair whose nearest θh node is 1.
    let th = g.stored_axes()[0].node(1);
    let (wi, wo) = pair_of(Param::HalfDiff, [th, 0.0, 0.3, 0.2]);
    assert_eq!(eval3(&broken, wi, wo), [0.0; 3]);
    assert!(broken.load_error().unwrap().contains("broken chunk"));
    // load_all gives the loader's own error, not a re-worded copy.
    assert!(
        matches!(broken.load_all(), Err(Error::Unsupported(m)) if m == "broken chunk"),
        "the chunk's error keeps its variant"
    );
}

#[test]
fn raw_file_round_trips() {
    let g = grid(Param::InOut, [6, 8, 6, 8], Symmetry::ALL);
    let (t, _) = bake(&Symmetric, &g, &BakeOptions::default()).unwrap();
    let dir = TempDir::new("table-raw");
    let p = dir.join("t.brdftab");
    t.save_raw(&p).unwrap();
    assert!(Table::is_raw(&p));
    let u = Table::open_raw(&p).unwrap();
    assert_eq!(t, u);
    // Truncated file: a format error, not a panic.
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, &bytes[..bytes.len() - 3]).unwrap();
    assert!(matches!(Table::open_raw(&p), Err(Error::Format { .. })));
}

/// Axis sizes whose product overflows are the grid's "more than 2^40 values" error: the check
/// ran after the layout was built, which reserved a start per θ1 node (`capacity overflow` at
/// 2^61 and above) and multiplied the sizes unchecked. Found by fuzzing (session 40).
#[test]
fn grid_sizes_whose_product_overflows_are_an_error() {
    for sizes in [
        [1 << 62, 4, 1 << 62, 4],
        [1 << 61, 1, 2, 4],
        [4, 1 << 32, 1 << 32, 1 << 33],
    ] {
        for param in [Param::HalfDiff, Param::InOut] {
            let r = Grid::with_sizes(
                param,
                sizes,
                [Mapping::Uniform, Mapping::Uniform],
                Channels::Rgb,
                Symmetry::NONE,
            );
            assert!(
                matches!(&r, Err(Error::InvalidArgument { .. })),
                "{param:?} {sizes:?}: {r:?}"
            );
        }
    }
}

/// The two-phase batch path (prepare, prefetch, gather) is bit-identical to single lookups for
/// every layout it covers and falls back for the others, with invalid pairs mixed in and a
/// count that is not a multiple of the group size.
#[test]
fn batch_is_bit_identical_to_single_lookups_everywhere() {
    let mut rng = Pcg32::new(8);
    for (param, sizes, sym) in [
        (Param::HalfDiff, [12, 24, 12, 24], Symmetry::ALL),
        (Param::HalfDiff, [8, 12, 8, 12], Symmetry::NONE),
        (Param::InOut, [8, 12, 8, 12], Symmetry::ALL),
        (Param::InOut, [6, 12, 6, 12], Symmetry::NONE),
    ] {
        let g = grid(param, sizes, sym);
        for interp in [Interp::Linear, Interp::Nearest] {
            let tb = tab(&Symmetric, &g, interp);
            let n = 1003;
            let (mut wi, mut wo): (Vec<DVec3>, Vec<DVec3>) =
                (0..n).map(|_| random_pair(&mut rng)).unzip();
            wi[5] = DVec3::new(f64::NAN, 0.0, 1.0);
            wo[17] = DVec3::ZERO;
            wi[18] = -DVec3::Z;
            wi[1002] = DVec3::new(0.3, 0.1, -0.2);
            let mut out = vec![-1.0f32; n * 3];
            tb.eval_batch(&wi, &wo, &mut out);
            for k in 0..n {
                assert_eq!(
                    &out[k * 3..k * 3 + 3],
                    &eval3(&tb, wi[k], wo[k])[..],
                    "{param:?} {sym} {interp:?} pair {k}"
                );
            }
            for k in [5, 17, 18, 1002] {
                assert_eq!(&out[k * 3..k * 3 + 3], &[0.0; 3]);
            }
        }
    }
}

#[test]
fn batch_equals_single_and_invalid_input_gives_zero() {
    let g = grid(Param::HalfDiff, [16, 32, 16, 32], Symmetry::ALL);
    let tb = tab(&Symmetric, &g, Interp::Linear);
    let mut rng = Pcg32::new(5);
    let n = 40_000;
    let (wi, wo): (Vec<DVec3>, Vec<DVec3>) = (0..n).map(|_| random_pair(&mut rng)).unzip();
    let mut out = vec![0.0f32; n * 3];
    tb.eval_batch(&wi, &wo, &mut out);
    for k in (0..n).step_by(97) {
        assert_eq!(&out[k * 3..k * 3 + 3], &eval3(&tb, wi[k], wo[k])[..]);
    }
    for (a, b) in [
        (DVec3::new(f64::NAN, 0.0, 1.0), DVec3::Z),
        (DVec3::ZERO, DVec3::Z),
        (DVec3::new(0.0, 0.0, -1.0), DVec3::Z),
        (-DVec3::Z, -DVec3::Z),
    ] {
        assert_eq!(eval3(&tb, a, b), [0.0; 3]);
    }
    // At a wavelength an RGB table reads its channels through the RGB basis.
    let (wi, wo) = (spherical(0.3, 0.0), spherical(0.4, 2.0));
    let f = eval3(&tb, wi, wo);
    for nm in [444.0, 585.5, 700.0] {
        let w = brdftab::colour::rgb_basis_at(nm);
        let want: f64 = (0..3).map(|c| w[c] * f[c] as f64).sum();
        assert!((tb.eval_wavelength(wi, wo, nm) - want).abs() < 1e-6 * want);
    }
}

#[test]
#[should_panic(expected = "do not match")]
fn table_batch_of_mismatched_lengths_panics() {
    let g = grid(Param::HalfDiff, [4, 8, 4, 8], Symmetry::ALL);
    let tb = tab(&Symmetric, &g, Interp::Linear);
    let (wi, wo) = (vec![DVec3::Z; 3], vec![DVec3::Z; 2]);
    let mut out = vec![0.0f32; 9];
    tb.eval_batch(&wi, &wo, &mut out);
}

#[test]
#[should_panic(expected = "do not match")]
fn model_batch_with_a_short_output_panics() {
    let m = brdftab::ModelSpec::parse(r#"{"model": "lambert", "kd": 0.5}"#)
        .unwrap()
        .build(&brdftab::Channels::Rgb)
        .unwrap();
    let (wi, wo) = (vec![DVec3::Z; 3], vec![DVec3::Z; 3]);
    let mut out = vec![0.0f32; 8];
    m.eval_batch(&wi, &wo, &mut out);
}

/// A table's albedo integrates to the library's target for data (1e-4 of the largest channel,
/// bounded work): it agrees with the default 1e-6 integration of the same table within a
/// few times that target (the error estimate |K15 − G7| is an estimate, not a bound; 3×
/// covers it), at normal, oblique and grazing incidence.
#[test]
fn table_albedo_meets_the_data_target() {
    use brdftab::analysis::albedo::{Options, integrate};
    let g = grid(Param::HalfDiff, [16, 1, 16, 24], sym(true, true, true));
    let t = tab(&Symmetric, &g, Interp::Linear);
    for deg in [0.0f64, 45.0, 85.0] {
        let wi = spherical(deg.to_radians(), 0.0);
        let mut a = [0.0f64; 3];
        t.albedo(wi, &mut a);
        let reference = integrate(&t, wi, &Options::default()).value;
        let tol = 3.0 * Options::DATA.rel_tol * reference[0];
        for k in 0..3 {
            assert!(
                (a[k] - reference[k]).abs() <= tol,
                "θ {deg}°, channel {k}: {} vs {}",
                a[k],
                reference[k]
            );
        }
        // The data settings' own estimate claims the target.
        let est = integrate(&t, wi, &Options::DATA);
        assert_eq!(est.value, a.to_vec());
        assert!(est.error <= Options::DATA.rel_tol * a[0], "{est:?}");
    }
}
