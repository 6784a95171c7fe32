//! Lookup timing: how fast a `Brdf` evaluates random pairs, one at a time on one thread and in
//! batches ([`Brdf::eval_batch`]) on every core, and what its `sample` and `pdf` cost beside one
//! `eval` in the same rounds (a renderer calls all three per bounce). The pairs are timed twice:
//! exact in f64, and as renderers hold them — rounded to f32 and normalized there, unit only to
//! f32 precision — since a lookup that takes a slower path for those (it used to: 1.8–2.1× one
//! `eval`, 4.5–5.5× a batch) would be fast only on the benchmark's own inputs.
//!
//! The machines this runs on are shared, so each figure comes with its CPU-time twin (Linux
//! schedstat): wall-clock time alone says more about the neighbours than about the code. Medians
//! over the repeats. A CPU-time figure is NaN where it is unknown: off Linux, and for a run the
//! clock does not resolve — schedstat's runtime advances at scheduler events (ticks of a few ms),
//! so a repeat that shows none was shorter than that, and no figure is better than 0 ns or an
//! infinite rate.

use std::time::Instant;

use glam::DVec3;
use serde::Serialize;

use crate::brdf::Brdf;
use crate::error::{Error, Result};
use crate::geometry;
use crate::rng::Pcg32;

/// What [`lookups`] measured.
#[derive(Debug, Clone, Serialize)]
pub struct LookupTiming {
    /// The source's description.
    pub source: String,
    /// Random pairs per repeat.
    pub pairs: usize,
    /// Channels per lookup.
    pub channels: usize,
    /// Repeats (the figures are medians).
    pub repeats: usize,
    /// Wall-clock ns per `eval` on one thread.
    pub ns_per_lookup_single_thread: f64,
    /// CPU ns per `eval` on one thread (NaN where unknown: no CPU clock, as where
    /// `/proc/thread-self/schedstat` reads 0 in some containers; `null` in JSON, `unknown` in
    /// `brdftab bench`'s text).
    pub cpu_ns_per_lookup_single_thread: f64,
    /// Lookups per wall-clock second of `eval_batch`.
    pub lookups_per_s_batch: f64,
    /// Lookups per second of CPU time of `eval_batch` (per core; NaN where unknown).
    pub lookups_per_s_batch_per_core_cpu_time: f64,
    /// Threads `eval_batch` may use.
    pub threads: usize,
    /// Wall-clock ns per `sample` (direction, pdf and weight) on one thread, for the same views
    /// and rounds as `eval`.
    pub ns_per_sample_single_thread: f64,
    /// Wall-clock ns per `pdf` on one thread, same pairs and rounds as `eval`.
    pub ns_per_pdf_single_thread: f64,
    /// Median over the rounds of one `sample` / one `eval` (each round times both).
    pub sample_over_eval: f64,
    /// Samples per second of CPU time of `sample_batch` on the same views (per core; NaN where
    /// unknown).
    pub samples_per_s_batch_per_core_cpu_time: f64,
    /// Wall-clock ns per `eval` on one thread of the same pairs as renderers hold them: each
    /// direction rounded to f32 and normalized there (unit only to f32 precision), in the same
    /// rounds as the exact pairs.
    pub ns_per_lookup_f32_directions: f64,
    /// Lookups per second of CPU time of `eval_batch` on those f32 pairs (per core; NaN where
    /// unknown).
    pub lookups_per_s_batch_f32_directions_per_core_cpu_time: f64,
}

/// Times `src` on `pairs` random pairs (uniform on the hemisphere, fixed seed), `repeats` times.
pub fn lookups(src: &dyn Brdf, pairs: usize, repeats: usize) -> Result<LookupTiming> {
    if pairs == 0 || repeats == 0 {
        let (name, n) = if pairs == 0 {
            ("pairs", pairs)
        } else {
            ("repeats", repeats)
        };
        return Err(Error::arg(name, format!("{n}: at least 1 is needed")));
    }
    let c = src.channels().len();
    let mut rng = Pcg32::new(2024);
    let (wi, wo): (Vec<DVec3>, Vec<DVec3>) = (0..pairs)
        .map(|_| {
            (
                geometry::uniform_hemisphere(rng.next_dvec2()),
                geometry::uniform_hemisphere(rng.next_dvec2()),
            )
        })
        .unzip();
    let u: Vec<glam::DVec2> = (0..pairs).map(|_| rng.next_dvec2()).collect();
    // What pbrt-v4, Mitsuba 3 or a float32 array hands over: unit to f32 rounding only.
    let as_f32 = |w: &Vec<DVec3>| -> Vec<DVec3> {
        w.iter()
            .map(|d| d.as_vec3().normalize().as_dvec3())
            .collect()
    };
    let (fi, fo) = (as_f32(&wi), as_f32(&wo));
    let mut out = vec![0.0f32; pairs * c];
    // Warm up (loads lazy chunks, faults pages, builds a table's sampler).
    src.eval_batch(&wi, &wo, &mut out);
    std::hint::black_box(src.sample(wo[0], u[0], &mut out[..c]));
    // A source that failed while it was read (a corrupt table chunk) would time its zeros.
    src.health()?;
    let n = pairs as f64;
    let (mut single, mut single_cpu) = (Vec::new(), Vec::new());
    let (mut sample, mut pdf, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
    let (mut single_f32, mut batch_f32) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        // Untimed: the table back in the caches after the last round's sample and pdf passes,
        // so that the two timed lookup passes below start from the same state.
        for (k, o) in out.chunks_exact_mut(c).enumerate() {
            src.eval(fi[k], fo[k], o);
        }
        std::hint::black_box(&out);
        let (t, cpu) = (Instant::now(), thread_cpu_ns());
        for (k, o) in out.chunks_exact_mut(c).enumerate() {
            src.eval(wi[k], wo[k], o);
        }
        let eval_ns = t.elapsed().as_secs_f64() * 1e9 / n;
        single.push(eval_ns);
        single_cpu.push(cpu_ns(cpu, thread_cpu_ns()).map(|d| d / n));
        std::hint::black_box(&out);
        let t = Instant::now();
        for (k, o) in out.chunks_exact_mut(c).enumerate() {
            src.eval(fi[k], fo[k], o);
        }
        single_f32.push(t.elapsed().as_secs_f64() * 1e9 / n);
        std::hint::black_box(&out);
        let t = Instant::now();
        for (k, o) in out.chunks_exact_mut(c).enumerate() {
            std::hint::black_box(src.sample(wo[k], u[k], o));
        }
        let sample_ns = t.elapsed().as_secs_f64() * 1e9 / n;
        sample.push(sample_ns);
        ratio.push(sample_ns / eval_ns);
        let t = Instant::now();
        for k in 0..pairs {
            std::hint::black_box(src.pdf(wi[k], wo[k]));
        }
        pdf.push(t.elapsed().as_secs_f64() * 1e9 / n);
    }
    let (mut batch, mut batch_cpu) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        let (t, cpu) = (Instant::now(), process_cpu_ns());
        src.eval_batch(&wi, &wo, &mut out);
        batch.push(n / t.elapsed().as_secs_f64());
        // Per core of CPU time: independent of how busy the machine is and of how many
        // threads `eval_batch` used.
        batch_cpu.push(cpu_ns(cpu, process_cpu_ns()).map(|d| n / (d * 1e-9)));
        std::hint::black_box(&out);
        let cpu = process_cpu_ns();
        src.eval_batch(&fi, &fo, &mut out);
        batch_f32.push(cpu_ns(cpu, process_cpu_ns()).map(|d| n / (d * 1e-9)));
        std::hint::black_box(&out);
    }
    let (mut swi, mut spdf) = (vec![DVec3::ZERO; pairs], vec![0.0; pairs]);
    let mut sample_batch = Vec::new();
    for _ in 0..repeats {
        let cpu = process_cpu_ns();
        let out = crate::batch::SampleOut {
            wi: &mut swi,
            pdf: &mut spdf,
            weight: &mut out,
        };
        src.sample_batch(&wo, &u, out);
        sample_batch.push(cpu_ns(cpu, process_cpu_ns()).map(|d| n / (d * 1e-9)));
        std::hint::black_box(&swi);
    }
    Ok(LookupTiming {
        source: src.describe(),
        pairs,
        channels: c,
        repeats,
        ns_per_lookup_single_thread: median(&mut single),
        cpu_ns_per_lookup_single_thread: median_known(&single_cpu),
        lookups_per_s_batch: median(&mut batch),
        lookups_per_s_batch_per_core_cpu_time: median_known(&batch_cpu),
        threads: crate::par::threads(),
        ns_per_sample_single_thread: median(&mut sample),
        ns_per_pdf_single_thread: median(&mut pdf),
        sample_over_eval: median(&mut ratio),
        samples_per_s_batch_per_core_cpu_time: median_known(&sample_batch),
        ns_per_lookup_f32_directions: median(&mut single_f32),
        lookups_per_s_batch_f32_directions_per_core_cpu_time: median_known(&batch_f32),
    })
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|x, y| x.total_cmp(y));
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// The median of CPU-time figures, NaN unless every repeat has one: a repeat the clock did not
/// resolve makes the others no more than ticks counted over a run of similar length.
fn median_known(v: &[Option<f64>]) -> f64 {
    match v.iter().copied().collect::<Option<Vec<f64>>>() {
        Some(mut known) => median(&mut known),
        None => f64::NAN,
    }
}

/// The CPU ns between two clock readings, `None` where a reading is missing or the clock did not
/// advance (or went back: a thread of the process that ended between the readings took its time
/// with it).
fn cpu_ns(a0: Option<u64>, a1: Option<u64>) -> Option<f64> {
    match a1?.checked_sub(a0?) {
        Some(d) if d > 0 => Some(d as f64),
        _ => None,
    }
}

/// CPU time of the calling thread in ns (Linux `/proc/thread-self/schedstat`).
pub fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

/// CPU time of every thread of the process in ns.
pub fn process_cpu_ns() -> Option<u64> {
    let mut total = 0;
    for e in std::fs::read_dir("/proc/self/task").ok()? {
        let p = e.ok()?.path().join("schedstat");
        if let Ok(s) = std::fs::read_to_string(p) {
            total += s.split_whitespace().next()?.parse::<u64>().ok()?;
        }
    }
    Some(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timing_a_model_gives_positive_figures() {
        let m = crate::spec::ModelSpec::parse(r#"{"model": "lambert", "kd": 0.5}"#)
            .unwrap()
            .build(&crate::Channels::Rgb)
            .unwrap();
        let t = lookups(m.as_ref(), 2000, 3).unwrap();
        assert_eq!((t.pairs, t.channels, t.repeats), (2000, 3, 3));
        assert!(t.ns_per_lookup_single_thread > 0.0 && t.lookups_per_s_batch > 0.0);
        assert!(t.ns_per_sample_single_thread > 0.0 && t.ns_per_pdf_single_thread > 0.0);
        assert!(t.sample_over_eval > 0.0);
        assert!(t.ns_per_lookup_f32_directions > 0.0);
        assert!(lookups(m.as_ref(), 0, 3).is_err());
    }

    #[test]
    fn a_cpu_time_the_clock_does_not_resolve_is_unknown_not_zero_or_infinite() {
        // schedstat's runtime advances at scheduler events, not per instruction: ten lookups
        // take no CPU time it can see. That is no figure (NaN), not "0.0 ns CPU time" or an
        // infinite rate per core (what `brdftab bench --pairs 2000` printed).
        let m = crate::spec::ModelSpec::parse(r#"{"model": "lambert", "kd": 0.5}"#)
            .unwrap()
            .build(&crate::Channels::Rgb)
            .unwrap();
        let t = lookups(m.as_ref(), 10, 3).unwrap();
        for (name, x) in [
            ("single", t.cpu_ns_per_lookup_single_thread),
            ("batch", t.lookups_per_s_batch_per_core_cpu_time),
            ("sample batch", t.samples_per_s_batch_per_core_cpu_time),
            (
                "f32 batch",
                t.lookups_per_s_batch_f32_directions_per_core_cpu_time,
            ),
        ] {
            assert!(x.is_nan() || (x.is_finite() && x > 0.0), "{name}: {x}");
        }
    }
}
