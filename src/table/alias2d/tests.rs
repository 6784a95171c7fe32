//! The alias tables' unit tests: the masses drawn, the draws inverting their CDFs, the 2D
//! warps' draws following their density, the same density as the interpolated warp.

use super::*;
use crate::rng::Pcg32;

/// The distribution an alias table draws from: what every slot keeps plus what it gives.
fn implied(pk: Packing, table: &[u32]) -> Vec<f64> {
    let n = table.len() as f64;
    let mut p = vec![0.0; table.len()];
    for (i, &e) in table.iter().enumerate() {
        let (keep, other) = pk.unpack(e);
        p[i] += keep / n;
        p[other] += (1.0 - keep) / n;
    }
    p
}

#[test]
fn alias_tables_draw_their_masses() {
    let mut rng = Pcg32::new(11);
    for n in [1usize, 2, 3, 7, 63, 200] {
        // Masses over six orders of magnitude, some zero.
        let m: Vec<f64> = (0..n)
            .map(|i| {
                if i % 5 == 3 {
                    0.0
                } else {
                    10f64.powf(6.0 * rng.next_f64() - 3.0)
                }
            })
            .collect();
        let pk = Packing::for_slots(n);
        let mut t = vec![0u32; n];
        pk.build(&m, &mut t);
        let total: f64 = m.iter().sum();
        for (i, p) in implied(pk, &t).iter().enumerate() {
            let want = if total > 0.0 {
                m[i] / total
            } else {
                1.0 / n as f64
            };
            // Fixed-point probabilities: a rounding of 2^-(33 - bits) per slot that gives
            // to this one (at most n of them), over n; plus f64 rounding.
            let step = 0.5 / (1u64 << pk.keep_bits()) as f64;
            assert!(
                (p - want).abs() <= 1e-12 * want + step,
                "n {n}, slot {i}: {p} vs {want}"
            );
        }
    }
    let pk = Packing::for_slots(4);
    let mut t = vec![0u32; 4];
    pk.build(&[0.0; 4], &mut t);
    assert_eq!(implied(pk, &t), vec![0.25; 4]);
}

#[test]
fn rising_and_falling_draws_invert_their_cdfs() {
    // CDFs t² (rising) and 1 − (1 − t)² (falling).
    for i in 0..=1000 {
        let v = i as f64 / 1000.0;
        let (up, down) = (rise_or_fall(1, v), rise_or_fall(0, v));
        assert!((up * up - v).abs() <= 4e-16, "{v}: {up}");
        assert!(
            (1.0 - (1.0 - down).powi(2) - v).abs() <= 4e-16,
            "{v}: {down}"
        );
        assert!((0.0..=1.0).contains(&up) && (0.0..=1.0).contains(&down));
    }
}

#[test]
fn pick_keeps_the_remainder_uniform() {
    // A table of two slots, masses 1 : 3 → slot 0 keeps ½, slot 1 keeps all.
    let pk = Packing::for_slots(2);
    let mut t = vec![0u32; 2];
    pk.build(&[1.0, 3.0], &mut t);
    let (n, bins) = (200_000, 10);
    let mut hist = vec![[0usize; 10]; 2];
    let mut rng = Pcg32::new(2);
    for _ in 0..n {
        let (i, r) = pk.pick(&t, rng.next_f64());
        assert!((0.0..=1.0).contains(&r));
        hist[i][((r * bins as f64) as usize).min(bins - 1)] += 1;
    }
    for (i, share) in [(0, 0.25), (1, 0.75)] {
        for &h in &hist[i] {
            let want = n as f64 * share / bins as f64;
            // 5 standard deviations of a binomial count.
            assert!((h as f64 - want).abs() < 5.0 * want.sqrt(), "{hist:?}");
        }
    }
}

fn planes(rng: &mut Pcg32, nx: usize, ny: usize, slices: usize) -> Planes {
    let data = (0..nx * ny * slices)
        .map(|i| {
            if i % nx == 0 {
                0.0 // a zero column, as the sampler's pole
            } else {
                (5.0 * rng.next_f64()).exp() as f32
            }
        })
        .collect();
    Planes { nx, ny, data }
}

/// Sampling returns the density [`AliasWarp::eval`] gives at the drawn point, and the draws
/// follow it: a chi-square test over the cells of a finer histogram.
#[test]
fn draws_follow_the_density() {
    let mut rng = Pcg32::new(5);
    let (nx, ny) = (7, 5);
    let w = AliasWarp::build(planes(&mut rng, nx, ny, 4)).unwrap();
    let k = Corners {
        slice: [0, 1, 2, 3],
        w: [0.1, 0.2, 0.3, 0.4],
    };
    let (bx, by) = (18, 12);
    let n = 400_000;
    let mut hist = vec![0f64; bx * by];
    for _ in 0..n {
        let (p, pdf) = w.sample([rng.next_f64(), rng.next_f64()], &k);
        let e = w.eval(p, &k);
        assert!((pdf - e).abs() <= 1e-6 * e, "{p:?}: {pdf} vs {e}");
        let (ix, iy) = (
            ((p[0] * bx as f64) as usize).min(bx - 1),
            ((p[1] * by as f64) as usize).min(by - 1),
        );
        hist[iy * bx + ix] += 1.0;
    }
    // Expected counts by a 16 × 16 midpoint rule per bin (the density is bilinear per
    // patch, the bins straddle patches: the rule's error is far below the counts' noise).
    let mut chi2 = 0.0;
    let q = 16;
    for iy in 0..by {
        for ix in 0..bx {
            let mut mass = 0.0;
            for a in 0..q {
                for b in 0..q {
                    let x = (ix as f64 + (a as f64 + 0.5) / q as f64) / bx as f64;
                    let y = (iy as f64 + (b as f64 + 0.5) / q as f64) / by as f64;
                    mass += w.eval([x, y], &k);
                }
            }
            let expect = n as f64 * mass / (q * q * bx * by) as f64;
            chi2 += (hist[iy * bx + ix] - expect).powi(2) / expect;
        }
    }
    // 215 degrees of freedom: mean 215, σ ≈ 20.7; 300 is beyond 4σ.
    assert!(chi2 < 300.0, "chi2 {chi2}");
}

/// The mixture draw has the density of the interpolated warp: `Warp::eval` and
/// [`AliasWarp::eval`] agree on the same nodes.
#[test]
fn same_density_as_the_interpolated_warp() {
    let mut rng = Pcg32::new(9);
    let p = planes(&mut rng, 9, 6, 2);
    let (a, b) = (
        Warp::build(p.clone()).unwrap(),
        AliasWarp::build(p).unwrap(),
    );
    let k = Corners {
        slice: [0, 1, 0, 1],
        w: [0.35, 0.65, 0.0, 0.0],
    };
    for _ in 0..1000 {
        let u = [rng.next_f64(), rng.next_f64()];
        // The same bilinear sums in another order: a few roundings apart.
        let (x, y) = (a.eval(u, &k), b.eval(u, &k));
        assert!((x - y).abs() <= 1e-14 * x, "{u:?}: {x} vs {y}");
    }
}
