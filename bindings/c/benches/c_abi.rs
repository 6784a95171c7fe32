//! Batch and one-pair evaluation through the C ABI against the library's own calls on the same
//! table, in the same run (ratios, not absolute times, are the figures).
//!
//! `cargo bench -p brdftab-c --bench c_abi` — bakes the default (medium preset) Cook-Torrance
//! gold table into a temporary file, then times, median of 9 runs each, alternating:
//! `Brdf::eval_batch` vs `brdftab_eval` on 10^6 random pairs, and `Brdf::eval` vs
//! `brdftab_eval(n = 1)` per pair.

use std::ffi::CString;
use std::time::Instant;

use brdftab::bake::{BakeRequest, BakeTarget};
use brdftab::testkit::Pcg32;
use brdftab::{Brdf, geometry};
use brdftab_c::*;
use glam::DVec3;

/// CPU time of `clock` in seconds: the whole process (every rayon worker) or the calling
/// thread. On a shared machine the wall clock measures the neighbours as much as the code.
/// (Off Unix — the figures are taken on Linux — both are wall time: [`cpu_of`] below.)
#[cfg(unix)]
fn cpu_of(clock: libc::clockid_t) -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    unsafe { libc::clock_gettime(clock, &mut t) };
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

/// Wall time since the first call, in seconds, in place of a CPU clock.
#[cfg(not(unix))]
fn cpu_of(_clock: ()) -> f64 {
    static START: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64()
}

fn cpu() -> f64 {
    #[cfg(unix)]
    return cpu_of(libc::CLOCK_PROCESS_CPUTIME_ID);
    #[cfg(not(unix))]
    cpu_of(())
}

fn thread_cpu() -> f64 {
    #[cfg(unix)]
    return cpu_of(libc::CLOCK_THREAD_CPUTIME_ID);
    #[cfg(not(unix))]
    cpu_of(())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let dir = brdftab::testkit::TempDir::new("c-bench");
    let path = dir.join("ct.btdb").to_str().unwrap().to_owned();
    let spec = r#"{"model":"cook_torrance","m":0.3,"fresnel":{"conductor":"Au"}}"#;
    BakeRequest::new(spec)
        .run(&BakeTarget::file(&path))
        .expect("bake");
    let rust = brdftab::open(&path).expect("open");
    let csrc = CString::new(path.clone()).unwrap();
    let h = unsafe { brdftab_open(csrc.as_ptr()) };
    assert!(!h.is_null());
    let c = rust.channels().len();

    let n = 1_000_000;
    let mut rng = Pcg32::new(7);
    let (wi, wo): (Vec<DVec3>, Vec<DVec3>) = (0..n)
        .map(|_| {
            (
                geometry::uniform_hemisphere(rng.next_dvec2()),
                geometry::uniform_hemisphere(rng.next_dvec2()),
            )
        })
        .unzip();
    let flat = |v: &[DVec3]| -> Vec<f64> { v.iter().flat_map(|d| d.to_array()).collect() };
    let (wi_c, wo_c) = (flat(&wi), flat(&wo));
    let mut out = vec![0.0f32; n * c];
    rust.eval_batch(&wi, &wo, &mut out); // warm up: decode every chunk
    let (mut batch_rust, mut batch_c) = (Vec::new(), Vec::new());
    let (mut cpu_rust, mut cpu_c) = (Vec::new(), Vec::new());
    for _ in 0..9 {
        let (t, c0) = (Instant::now(), cpu());
        rust.eval_batch(&wi, &wo, &mut out);
        batch_rust.push(n as f64 / t.elapsed().as_secs_f64());
        cpu_rust.push(n as f64 / (cpu() - c0));
        std::hint::black_box(&out);
        let (t, c0) = (Instant::now(), cpu());
        let rc = unsafe { brdftab_eval(h, n, wi_c.as_ptr(), wo_c.as_ptr(), out.as_mut_ptr()) };
        batch_c.push(n as f64 / t.elapsed().as_secs_f64());
        cpu_c.push(n as f64 / (cpu() - c0));
        assert_eq!(rc, 0);
        std::hint::black_box(&out);
    }
    let m = 200_000;
    // The C handle is a second copy of the table (its own chunks): each loop is timed right
    // after an untimed pass over the same pairs, so that both start from their own copy in
    // the caches (timed back to back, the second loop paid for the first one's evictions:
    // "+57 ns per call" that was the table's, not the ABI's).
    let rust_pass = |out: &mut [f32]| {
        let t = thread_cpu();
        for k in 0..m {
            rust.eval(wi[k], wo[k], &mut out[..c]);
        }
        (thread_cpu() - t) * 1e9 / m as f64
    };
    let c_pass = |out: &mut [f32]| {
        let t = thread_cpu();
        for k in 0..m {
            unsafe {
                brdftab_eval(
                    h,
                    1,
                    wi_c[3 * k..].as_ptr(),
                    wo_c[3 * k..].as_ptr(),
                    out.as_mut_ptr(),
                )
            };
        }
        (thread_cpu() - t) * 1e9 / m as f64
    };
    let (mut one_rust, mut one_c) = (Vec::new(), Vec::new());
    for _ in 0..9 {
        rust_pass(&mut out);
        one_rust.push(rust_pass(&mut out));
        std::hint::black_box(&out);
        c_pass(&mut out);
        one_c.push(c_pass(&mut out));
        std::hint::black_box(&out);
    }
    let (br, bc) = (median(batch_rust), median(batch_c));
    let (pr, pc) = (median(cpu_rust), median(cpu_c));
    let (or, oc) = (median(one_rust), median(one_c));
    println!("table: {path} (CT m=0.3 gold, medium preset, {c} channels)");
    println!(
        "batch, 10^6 pairs: eval_batch {:.2} M/s, brdftab_eval {:.2} M/s, ratio C/Rust {:.3}",
        br / 1e6,
        bc / 1e6,
        bc / br
    );
    println!(
        "batch, per core of CPU time: eval_batch {:.2} M/s, brdftab_eval {:.2} M/s, ratio C/Rust {:.3}",
        pr / 1e6,
        pc / 1e6,
        pc / pr
    );
    println!(
        "one pair (thread CPU time): Brdf::eval {or:.1} ns, brdftab_eval(n=1) {oc:.1} ns, overhead {:.1} ns",
        oc - or
    );
    unsafe { brdftab_close(h) };
}
