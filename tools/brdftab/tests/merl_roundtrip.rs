//! MERL → MERL, MERL baked on the MERL grid, and MERL → table → MERL keep every measured cell
//! (to f32, the precision a table stores) and every unmeasured (−1) cell.
//!
//! The file is the one of issue 12: a random positive value in every cell, the −1 sentinel only
//! where the θh index is ≥ 80 and the θd index ≥ 85. Many measured cells there have a centre
//! pair with a direction below the horizon (e.g. θh 83, θd 15, φd 145), which resampling at
//! directions cannot reach.

mod common;

use std::path::Path;

use brdftab::measured::MerlBrdf;
use brdftab::measured::merl::{self, RES_PHI_D, RES_THETA_D, RES_THETA_H, SAMPLES, SCALE};
use brdftab::store::Store;
use brdftab::testkit::{Pcg32, TempDir};

fn unmeasured(ith: usize, itd: usize) -> bool {
    ith >= 80 && itd >= 85
}

/// The issue's file, written to `path`; returns its raw values.
fn issue_file(path: &Path) -> Vec<f64> {
    let mut rng = Pcg32::new(2012);
    let mut data = vec![0.0f64; 3 * SAMPLES];
    for ith in 0..RES_THETA_H {
        for itd in 0..RES_THETA_D {
            for ipd in 0..RES_PHI_D {
                let k = merl::sample_index(ith, itd, ipd);
                for c in 0..3 {
                    data[c * SAMPLES + k] = if unmeasured(ith, itd) {
                        -1.0
                    } else {
                        // [1, 3000): positive, with bits a f32 cannot all hold, and far
                        // above log16's floor (1e-7 of a chunk's largest value), where its
                        // bound is relative.
                        1.0 + 2999.0 * rng.next_f64()
                    };
                }
            }
        }
    }
    MerlBrdf::from_raw("issue 12", data.clone())
        .unwrap()
        .write(path)
        .unwrap();
    data
}

/// Runs `brdftab ARGS`, which must succeed.
fn brdftab_ok(args: &[&str]) {
    let o = common::brdftab(args);
    assert!(o.ok, "brdftab {args:?}: {}", o.stderr);
}

/// f32 rounding of the scaled value (relative 2^-24) and two f64 operations.
const F32_REL: f64 = 1.0 / (1u64 << 24) as f64 + 1e-15;

/// Every sentinel is −1 again and every measured value is back within `rel` (relative).
fn assert_same_file(a: &[f64], path: &Path, rel: f64) {
    let b = MerlBrdf::open(path).unwrap();
    let b = b.raw();
    let mut worst = 0.0f64;
    for (k, (&x, &y)) in a.iter().zip(b).enumerate() {
        if x < 0.0 {
            assert_eq!(y, -1.0, "sentinel at {k} became {y}");
        } else {
            assert!(y > 0.0, "measured value {x} at {k} became {y}");
            worst = worst.max((y - x).abs() / x);
        }
    }
    assert!(worst <= rel, "worst relative change {worst:e} > {rel:e}");
}

#[test]
fn merl_to_merl_keeps_every_cell() {
    let dir = TempDir::new("merlrt-m2m");
    let (a, b) = (dir.join("a.binary"), dir.join("b.binary"));
    let data = issue_file(&a);
    brdftab_ok(&["convert", a.to_str().unwrap(), b.to_str().unwrap()]);
    assert_same_file(&data, &b, F32_REL);
    // The cell of the issue: (θh 83, θd 15, φd 145), channel R, measured, centre pair below the
    // horizon.
    let k = merl::sample_index(83, 15, 145);
    assert!(MerlBrdf::open(&b).unwrap().raw()[k] > 0.0);
}

/// `bake --grid merl` stores cell (i, j, k) at node (i, 0, j, k) as the f32 of its f_r, the
/// sentinels as −1 × scale; the store's f32 codec is lossless, so the check is bit for bit.
#[test]
fn bake_on_the_merl_grid_holds_the_cells_verbatim() {
    let dir = TempDir::new("merlrt-bake");
    let a = dir.join("a.binary");
    let t = dir.join("t.btdb");
    let data = issue_file(&a);
    brdftab_ok(&[
        "bake",
        a.to_str().unwrap(),
        "--grid",
        "merl",
        "--codec",
        "f32",
        "-o",
        t.to_str().unwrap(),
    ]);
    let s = Store::open(&t).unwrap();
    let st = s.single().unwrap();
    let grid = st.grid().unwrap();
    assert_eq!(grid.stored_shape(), [90, 1, 90, 180]);
    let values = st.read_all().unwrap();
    for ith in 0..RES_THETA_H {
        for itd in 0..RES_THETA_D {
            for ipd in 0..RES_PHI_D {
                let o = grid.layout().offset([ith, 0, itd, ipd]).unwrap();
                let k = merl::sample_index(ith, itd, ipd);
                for c in 0..3 {
                    let want = (data[c * SAMPLES + k] * SCALE[c]) as f32;
                    assert_eq!(
                        values[o + c].to_bits(),
                        want.to_bits(),
                        "cell ({ith}, {itd}, {ipd}) channel {c}: {} vs {want}",
                        values[o + c]
                    );
                }
            }
        }
    }
    // And back to MERL from the baked table.
    let b = dir.join("b.binary");
    brdftab_ok(&["convert", t.to_str().unwrap(), b.to_str().unwrap()]);
    assert_same_file(&data, &b, F32_REL);
}

/// MERL → table → MERL through `convert` (the file's own cells, no resampling): with the f32
/// codec to f32 precision, with the default log16 codec within its 1e-3 bound — and every
/// sentinel in both (log16 keeps the sign).
#[test]
fn merl_to_table_to_merl_keeps_every_cell() {
    let dir = TempDir::new("merlrt-m2t2m");
    let a = dir.join("a.binary");
    let data = issue_file(&a);
    for (codec, rel) in [("f32", F32_REL), ("log16", 1e-3 * (1.0 + 1e-6) + F32_REL)] {
        let t = dir.join(format!("t-{codec}.btdb"));
        let b = dir.join(format!("b-{codec}.binary"));
        brdftab_ok(&[
            "convert",
            a.to_str().unwrap(),
            t.to_str().unwrap(),
            "--codec",
            codec,
            "--pairs",
            "0",
        ]);
        brdftab_ok(&["convert", t.to_str().unwrap(), b.to_str().unwrap()]);
        assert_same_file(&data, &b, rel);
    }
    // A raw table file too.
    let t = dir.join("t.tbl");
    let b = dir.join("b-raw.binary");
    brdftab_ok(&[
        "convert",
        a.to_str().unwrap(),
        t.to_str().unwrap(),
        "--pairs",
        "0",
    ]);
    brdftab_ok(&["convert", t.to_str().unwrap(), b.to_str().unwrap()]);
    assert_same_file(&data, &b, F32_REL);
}

/// The relative RMSE of `convert`'s accuracy line on stderr (`accuracy vs native (INTERP, N pairs):
/// relative RMSE of f_r cos θi cos θo X, max relative Y`), with the interpolation it names.
fn reported_accuracy(stderr: &str) -> (String, f64) {
    let line = stderr
        .lines()
        .find(|l| l.trim_start().starts_with("accuracy vs native ("))
        .unwrap_or_else(|| panic!("no accuracy line in {stderr}"));
    let interp = line.split('(').nth(1).unwrap().split(',').next().unwrap();
    let rmse = line
        .split("cos θo ")
        .nth(1)
        .and_then(|r| r.split(',').next())
        .and_then(|x| x.trim().parse().ok())
        .unwrap_or_else(|| panic!("no relative RMSE in {line}"));
    (interp.to_owned(), rmse)
}

/// `convert a.binary t.btdb` copies the cells, and every host opens such a table nearest by
/// default (`interp` auto): its accuracy report measures that lookup, exact to f32 rounding.
/// It measured a linear lookup whatever the table, which no host does by default, and printed
/// 2.6 % and a max relative error of 9258 for a table of a Cook-Torrance file's own cells; and
/// `--interp auto`, which every other command takes, was refused.
#[test]
fn converting_merl_cells_reports_the_lookup_hosts_use() {
    let dir = TempDir::new("merlrt-acc");
    let a = dir.join("a.binary");
    issue_file(&a);
    let a = a.to_str().unwrap();
    for (i, extra) in [&[][..], &["--interp", "auto"][..]].iter().enumerate() {
        let t = dir.join(format!("t{i}.btdb"));
        let mut args = vec!["convert", a, t.to_str().unwrap(), "--codec", "f32"];
        args.extend_from_slice(&["--pairs", "20000"]);
        args.extend_from_slice(extra);
        let r = common::brdftab(&args);
        assert!(r.ok, "{args:?}: {}", r.stderr);
        let (interp, rmse) = reported_accuracy(&r.stderr);
        assert_eq!(interp, "Nearest", "{}", r.stderr);
        // The f32 table holds each cell's f32 value, the file's reader returns the same f32:
        // equal but for the f64 arithmetic of the comparison (F32_REL is a bound per value).
        assert!(rmse <= 2.0 * F32_REL, "{}", r.stderr);
    }
    // Asked for, the linear lookup is still what is measured: it blends the random cells.
    let t = dir.join("lin.btdb");
    let r = common::brdftab(&[
        "convert",
        a,
        t.to_str().unwrap(),
        "--pairs",
        "20000",
        "--interp",
        "linear",
    ]);
    assert!(r.ok, "{}", r.stderr);
    let (interp, rmse) = reported_accuracy(&r.stderr);
    assert_eq!(interp, "Linear", "{}", r.stderr);
    assert!(rmse > 1e-2, "{}", r.stderr);
}

/// What a lookup makes of the unmeasured cells: 0 at them (nearest), a blend towards 0 next to
/// them (linear), never a negative value.
#[test]
fn lookups_see_unmeasured_cells_as_zero() {
    use brdftab::Brdf;
    use brdftab::table::{Interp, TabulatedBrdf};
    let mut data = vec![1500.0f64; 3 * SAMPLES];
    for ith in 0..RES_THETA_H {
        for itd in 0..RES_THETA_D {
            for ipd in 0..RES_PHI_D {
                if unmeasured(ith, itd) {
                    for c in 0..3 {
                        data[c * SAMPLES + merl::sample_index(ith, itd, ipd)] = -1.0;
                    }
                }
            }
        }
    }
    let m = MerlBrdf::from_raw("step", data).unwrap();
    let table = m.to_table();
    // The table keeps the sentinels (negative), the lookups do not show them.
    assert!(table.values().iter().any(|&v| v < 0.0));
    let nearest = TabulatedBrdf::from_table(table.clone()).with_interp(Interp::Nearest);
    let linear = TabulatedBrdf::from_table(table);
    let mut rng = Pcg32::new(5);
    let mut blended = 0;
    for _ in 0..200_000 {
        let wi = brdftab::geometry::uniform_hemisphere(rng.next_dvec2());
        let wo = brdftab::geometry::uniform_hemisphere(rng.next_dvec2());
        let (mut fr, mut fn_, mut fl) = ([0f32; 3], [0f32; 3], [0f32; 3]);
        m.eval(wi, wo, &mut fr);
        nearest.eval(wi, wo, &mut fn_);
        linear.eval(wi, wo, &mut fl);
        for c in 0..3 {
            assert!(fn_[c] >= 0.0 && fl[c] >= 0.0);
            // Nearest = the reader (unmeasured → 0), to f32.
            assert!(
                (fn_[c] - fr[c]).abs() <= 1e-6 * fr[c].max(1.0),
                "{fn_:?} {fr:?}"
            );
            // Linear stays within [0, the measured value].
            assert!(fl[c] <= (1500.0 * SCALE[c]) as f32 * (1.0 + 1e-6));
        }
        if fl[0] > 0.0 && fl[0] < (1500.0 * SCALE[0]) as f32 * 0.999 {
            blended += 1;
        }
    }
    assert!(blended > 0, "no lookup fell next to the unmeasured region");
}
