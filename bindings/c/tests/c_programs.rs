//! Builds the C test program and the examples with the system compiler against the built
//! library, runs them, and compares what they print with the Rust API on the same sources.
//!
//! Linux only: the programs are built with `cc`/`g++` and GNU ld's flags against
//! `libbrdftab_c.so`, and checked with `readelf` and `nm` (ELF). The C ABI itself is the same
//! on every target; its Rust-side tests (`non_utf8.rs` on Unix, the crate's unit tests) and
//! the library's run elsewhere (README.md, "Platforms").
#![cfg(target_os = "linux")]

use std::path::{Path, PathBuf};
use std::process::Command;

use brdftab::bake::{BakeRequest, BakeTarget};
use brdftab::table::presets::Preset;
use brdftab::testkit::{Pcg32, TempDir};
use brdftab::{Brdf, geometry};
use glam::{DVec2, DVec3};

const CRATE: &str = env!("CARGO_MANIFEST_DIR");

/// Where cargo put libbrdftab_c.{so,a} for this test run: `cargo test` leaves the cdylib and
/// staticlib of the package under test in target/<profile>/deps (only `cargo build` copies them
/// up to target/<profile>), so deps is searched first, then its parent.
fn lib_dir() -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let deps = exe.parent().unwrap().to_path_buf();
    let profile = deps.parent().unwrap().to_path_buf();
    let has = |d: &Path| d.join("libbrdftab_c.so").exists() && d.join("libbrdftab_c.a").exists();
    [deps, profile.clone()]
        .into_iter()
        .find(|d| has(d))
        .unwrap_or_else(|| {
            panic!(
                "libbrdftab_c.so/.a not found in {0}/deps or {0} (cargo builds them with this test)",
                profile.display()
            )
        })
}

fn run(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap_or_else(|e| panic!("{cmd:?}: {e}"));
    assert!(
        out.status.success(),
        "{cmd:?} failed: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// A command running the test program `exe`: directly, or under the wrapper in
/// `BRDFTAB_C_TEST_WRAPPER` (its words split on whitespace: `tools/memcheck.sh valgrind-c`
/// runs every C and C++ program of this file under valgrind's memcheck this way; the wrapper
/// must log elsewhere than stderr, which some tests read).
fn program(exe: impl AsRef<std::ffi::OsStr>) -> Command {
    let wrapper = std::env::var("BRDFTAB_C_TEST_WRAPPER").unwrap_or_default();
    let mut words = wrapper.split_whitespace();
    match words.next() {
        Some(w) => {
            let mut c = Command::new(w);
            c.args(words).arg(exe);
            c
        }
        None => Command::new(exe),
    }
}

/// Compiles `src` (C or C++) against the shared library into `exe`.
fn compile(compiler: &str, extra: &[&str], src: &Path, exe: &Path) {
    let lib = lib_dir();
    let mut c = Command::new(compiler);
    c.args(extra)
        .arg("-O2")
        .arg("-Wall")
        .arg("-Werror")
        .arg(format!("-I{CRATE}/include"))
        .arg(format!("-I{CRATE}/examples"))
        .arg(src)
        .arg(format!("-L{}", lib.display()))
        .arg(format!("-Wl,-rpath,{}", lib.display()))
        // DT_RPATH, not DT_RUNPATH: searched before LD_LIBRARY_PATH, which `cargo test` sets
        // with target/<profile> (where an older `cargo build` may have left another
        // libbrdftab_c.so) — the programs must run the library this test run built.
        .arg("-Wl,--disable-new-dtags")
        .arg("-lbrdftab_c")
        .args(["-lpthread", "-lm"])
        .arg("-o")
        .arg(exe);
    run(&mut c);
}

fn bake_table(dir: &Path) -> String {
    let path = dir.join("ct.btdb").to_str().unwrap().to_owned();
    BakeRequest::new(r#"{"model":"cook_torrance","m":0.3,"fresnel":{"conductor":"Au"}}"#)
        .preset(Preset::Small)
        .run(&BakeTarget::file(&path))
        .unwrap();
    path
}

fn pairs(n: usize) -> Vec<(DVec3, DVec3, DVec2)> {
    let mut rng = Pcg32::new(11);
    (0..n)
        .map(|k| {
            let wi = geometry::uniform_hemisphere(rng.next_dvec2());
            // Some pairs below the horizon and unnormalized, as renderers pass them.
            let mut wo = geometry::uniform_hemisphere(rng.next_dvec2()) * 2.5;
            if k % 17 == 0 {
                wo.z = -wo.z;
            }
            (wi, wo, rng.next_dvec2())
        })
        .collect()
}

fn nums(line: &str) -> Vec<f64> {
    line.split_whitespace()
        .map(|x| x.parse().unwrap_or_else(|_| panic!("`{x}` in `{line}`")))
        .collect()
}

/// The C program's eval, pdf, sample and albedo equal the Rust API's for `source`.
fn check_source(exe: &Path, dir: &Path, source: &str) {
    let p = pairs(500);
    let input = dir.join("pairs.txt");
    let text: String = p
        .iter()
        .map(|(a, b, u)| {
            format!(
                "{:.17e} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e}\n",
                a.x, a.y, a.z, b.x, b.y, b.z, u.x, u.y
            )
        })
        .collect();
    std::fs::write(&input, text).unwrap();
    let output = dir.join("out.txt");
    run(program(exe).arg(source).arg(&input).arg(&output));
    let brdf = brdftab::open(source).unwrap();
    let c = brdf.channels().len();
    let out = std::fs::read_to_string(&output).unwrap();
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), p.len() + 1);
    let mut f = vec![0.0f32; c];
    let mut w = vec![0.0f32; c];
    for ((a, b, u), line) in p.iter().zip(&lines) {
        let v = nums(line);
        assert_eq!(v.len(), 2 * c + 5, "{line}");
        brdf.eval(*a, *b, &mut f);
        for i in 0..c {
            // %.9g prints an f32 exactly: the values must be bit-identical.
            assert_eq!(v[i] as f32, f[i], "eval {source} {a} {b}");
        }
        assert_eq!(v[c], brdf.pdf(*a, *b), "pdf");
        match brdf.sample(*b, *u, &mut w) {
            Some(s) => {
                assert_eq!(DVec3::new(v[c + 1], v[c + 2], v[c + 3]), s.wi);
                assert_eq!(v[c + 4], s.pdf);
                for i in 0..c {
                    assert_eq!(v[c + 5 + i] as f32, w[i]);
                }
            }
            None => assert!(v[c + 1..].iter().all(|x| *x == 0.0), "{line}"),
        }
    }
    let alb = nums(lines[p.len()].trim_start_matches("albedo"));
    let mut a = vec![0.0f64; c];
    brdf.albedo(DVec3::new(0.5, 0.0, 3f64.sqrt() / 2.0), &mut a);
    for i in 0..c {
        assert!(
            (alb[i] - a[i]).abs() <= 1e-12 * a[i].abs().max(1.0),
            "albedo"
        );
    }
}

#[test]
fn the_c_test_program_agrees_with_the_rust_api() {
    let dir = TempDir::new("c-abi");
    let exe = dir.join("abi_test");
    compile(
        "cc",
        &["-std=c11"],
        &Path::new(CRATE).join("tests/abi_test.c"),
        &exe,
    );
    let table = bake_table(dir.path());
    check_source(&exe, dir.path(), &table);
    check_source(
        &exe,
        dir.path(),
        r#"{"model":"lambert","kd":[0.1,0.2,0.3]}"#,
    );
    // A microfacet model: its one-pair `eval_pdf` shares the half vector and D.
    check_source(
        &exe,
        dir.path(),
        r#"{"model":"ggx","alpha":0.3,"fresnel":{"conductor":"Cu"}}"#,
    );
    let rgl = brdftab::measured::data::rgl_dir().expect("the RGL files ship in data/rgl");
    check_source(
        &exe,
        dir.path(),
        rgl.join("paper_white_rgb.bsdf").to_str().unwrap(),
    );
}

#[test]
fn requests_with_json_settings_do_what_the_rust_request_layer_does() {
    use brdftab::request;
    let dir = TempDir::new("c-request");
    let exe = dir.join("request_test");
    compile(
        "cc",
        &["-std=c11"],
        &Path::new(CRATE).join("tests/request_test.c"),
        &exe,
    );
    let out = run(program(&exe).arg(dir.path()));
    let line = |label: &str| {
        out.lines()
            .find_map(|l| l.strip_prefix(&format!("{label} ")))
            .unwrap_or_else(|| panic!("no `{label}` line in\n{out}"))
    };
    // The table: the Lambert's kd, stored as f32 under either interp. Nearest reads the
    // stored value (½ ε from kd); linear blends eight equal corners in f32 (the kernel): three
    // roundings per corner's term (two weight products, the value) and seven additions, so
    // within ½ ε + 10 · ½ ε of kd.
    for label in ["table", "table-default"] {
        for (got, want) in nums(line(label)).iter().zip([0.1, 0.2, 0.3]) {
            assert!(
                (got - want).abs() <= want * 5.5 * f32::EPSILON as f64,
                "{label}: {got} vs {want}"
            );
        }
    }
    // Flags: a Lambert is diffuse, reciprocal, isotropic and bilateral; its table glossy.
    let bits = |f: brdftab::Flags| {
        [
            f.lobes.diffuse,
            f.lobes.glossy,
            f.lobes.delta,
            f.transmission,
            f.reciprocal,
            f.isotropic,
            f.bilateral,
        ]
        .iter()
        .enumerate()
        .map(|(i, &on)| u32::from(on) << i)
        .sum::<u32>()
    };
    let lambert_flags = brdftab::open(r#"{"model":"lambert","kd":[0.1,0.2,0.3]}"#)
        .unwrap()
        .flags();
    assert_eq!(line("lambert-flags"), (1 + 16 + 32 + 64).to_string());
    assert_eq!(line("lambert-flags"), bits(lambert_flags).to_string());
    let table_flags = brdftab::open(dir.join("c.btdb").to_str().unwrap())
        .unwrap()
        .flags();
    assert_eq!(line("table-flags"), bits(table_flags).to_string());
    assert!(table_flags.lobes.glossy);
    // Errors name the field at fault.
    for (label, field) in [
        ("error unknown:", "gird"),
        ("error bad-value:", "supersample"),
        ("error fit-unknown:", "strats"),
        ("error open-interp:", "interp"),
        ("error convert-pairs-bsdf:", "pairs"),
        ("error convert-pairs-table:", "pairs"),
        ("error fit-pairs:", "pairs"),
        ("error fit-pairs-overflow:", "pairs"),
    ] {
        assert!(line(label).contains(field), "{label} {}", line(label));
    }
    // The .bsdf is the one the Rust request layer writes with the same settings.
    let settings: request::ConvertSettings =
        request::from_json(r#"{"theta_i": 4, "resolution": 16, "ndf_resolution": 32, "pairs": 0}"#)
            .unwrap();
    let rust = dir.join("rust.bsdf");
    let lambert = r#"{"model":"lambert","kd":[0.1,0.2,0.3]}"#;
    request::convert(
        lambert,
        rust.to_str().unwrap(),
        &settings,
        &brdftab::progress::Silent,
    )
    .unwrap();
    assert_eq!(
        std::fs::read(dir.join("c.bsdf")).unwrap(),
        std::fs::read(&rust).unwrap()
    );
    // The fit: the Rust layer's result, as JSON.
    let fit: serde_json::Value = serde_json::from_str(line("fit")).unwrap();
    let settings: request::FitSettings =
        request::from_json(r#"{"pairs": 300, "starts": 2}"#).unwrap();
    let want = request::fit(
        r#"{"model":"lambert","kd":0.3}"#,
        "lambert",
        &settings,
        &brdftab::progress::Silent,
    )
    .unwrap();
    assert_eq!(fit["spec"], serde_json::to_value(&want).unwrap()["spec"]);
}

#[test]
fn the_examples_build_and_print_what_the_library_computes() {
    let dir = TempDir::new("c-examples");
    let table = bake_table(dir.path());
    let ex = Path::new(CRATE).join("examples");

    // slice.c, against the shared and against the static library.
    let slice = dir.join("slice");
    compile("cc", &["-std=c11"], &ex.join("slice.c"), &slice);
    let text = run(program(&slice).arg(&table).arg("4"));
    let rows: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(nums)
        .collect();
    assert_eq!(rows.len(), 4);
    assert!(rows.iter().all(|r| r.len() == 4));
    // θh = 0, θd = 0 is the normal-incidence retro-reflection: wi = wo = z.
    let brdf = brdftab::open(&table).unwrap();
    let mut f = [0.0f32; 3];
    brdf.eval(DVec3::Z, DVec3::Z, &mut f);
    assert!((rows[0][0] as f32 - f[0]).abs() <= 1e-5 * f[0], "{text}");
    let lib = lib_dir();
    let slice_static = dir.join("slice_static");
    run(Command::new("cc")
        .args(["-std=c11", "-O2", &format!("-I{CRATE}/include")])
        .arg(ex.join("slice.c"))
        .arg(lib.join("libbrdftab_c.a"))
        .args(["-lpthread", "-ldl", "-lm", "-o"])
        .arg(&slice_static));
    assert_eq!(run(program(&slice_static).arg(&table).arg("4")), text);

    // The pbrt-v4-style BxDF over the C++ wrapper: a Monte Carlo albedo from Sample_f agrees
    // with the library's quadrature albedo (Lambert: the estimator's weight is exactly kd·π
    // for every sample, so the two agree to f32 rounding; the CT table is reciprocal, so the
    // estimate over wi matches the albedo over wo to the Monte Carlo error, < 2 % at 2·10^5).
    let bxdf = dir.join("pbrt_bxdf");
    compile("g++", &["-std=c++17"], &ex.join("pbrt_bxdf.cpp"), &bxdf);
    // A gold mirror: every draw is the delta's (pbrt's specular sample), whose weight is the
    // reflectance: exact. Lambert + gold mirror: each term's draws weigh its reflectance over
    // its probability, so only the choice between them varies (σ < 1e-3 at 2·10^5 draws: the
    // choice follows the terms' mean albedos).
    for (src, tol) in [
        (r#"{"model":"lambert","kd":[0.1,0.2,0.3]}"#, 1e-5),
        (&table[..], 0.02),
        (r#"{"model":"mirror","fresnel":{"conductor":"Au"}}"#, 1e-5),
        (
            r#"{"model":"sum","terms":[{"model":"lambert","kd":0.05},{"model":"mirror","fresnel":{"conductor":"Au"}}]}"#,
            5e-3,
        ),
        // Not reciprocal: the library's albedo (over wo for a fixed wi) is another integral
        // (0.1428 against 0.1496 here), so the program prints a uniform-sampling estimate of
        // the one Sample_f estimates; its relative σ is 0.7 % at 2·10^5 samples: 3 % is > 4σ.
        (r#"{"model":"phong","ks":0.5,"n":20}"#, 0.03),
    ] {
        // 150°: wo below the horizon. pbrt-v4's BxDFs are two-sided (MeasuredBxDF flips a
        // back-side pair), so the adapter sees the front's lobe at 30° (it sampled nothing there,
        // mc 0, when it was front-side only).
        for theta in ["30", "150"] {
            let out = run(program(&bxdf).arg(src).arg(theta));
            let mut it = out.lines();
            let mc = nums(it.next().unwrap().trim_start_matches("mc"));
            let line = it.next().unwrap();
            let reciprocal = !src.contains("\"phong\"");
            let label = if reciprocal { "albedo" } else { "uniform" };
            assert!(line.starts_with(label), "{src}: {line}");
            let alb = nums(line.trim_start_matches(label));
            for i in 0..3 {
                assert!(
                    (mc[i] - alb[i]).abs() <= tol * alb[i] + 1e-6,
                    "{src} at {theta}°: mc {mc:?} vs albedo {alb:?}"
                );
            }
        }
    }
    // A bad SOURCE: the C++ wrapper throws with the library's message; exit 1.
    let out = program(&bxdf).arg("/no/such.btdb").output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/no/such.btdb"));
    // A refractor: the adapter reflects only, so it refuses the source (it rendered black).
    let out = program(&bxdf)
        .arg(r#"{"model":"refractor","eta":1.5}"#)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("transmits"));
}

/// The monitored bake, convert and fit (tests/monitor_test.c): a monitor's 0 at its first
/// call or while the work runs gives -1 with "cancelled" soon after, and no file in the
/// directory but the one bake that was not stopped (no output, no temporary or staging file, no
/// database lock file); the monitor is called on the caller's thread only, n non-decreasing in
/// [0, 1], 1 last on success.
#[test]
fn a_monitor_stops_bakes_conversions_and_fits_leaving_no_file() {
    let dir = TempDir::new("c-monitor");
    let exe = std::env::temp_dir().join(format!("monitor_test_{}", std::process::id()));
    compile(
        "cc",
        &["-std=c11", "-D_POSIX_C_SOURCE=200809L"],
        &Path::new(CRATE).join("tests/monitor_test.c"),
        &exe,
    );
    let out = run(program(&exe).arg(dir.path()));
    let _ = std::fs::remove_file(&exe);
    for what in ["convert-bsdf", "convert-db"] {
        assert!(out.contains(&format!("latency {what} ")), "{out}");
    }
    let mut left: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    left.sort();
    assert_eq!(left, ["done.btdb"], "{out}");
    brdftab::open(dir.join("done.btdb").to_str().unwrap()).unwrap();
}

#[test]
fn the_header_declares_exactly_the_exported_functions() {
    let header = std::fs::read_to_string(Path::new(CRATE).join("include/brdftab.h")).unwrap();
    let mut declared: Vec<String> = header
        .lines()
        .filter(|l| !l.trim_start().starts_with('*') && !l.trim_start().starts_with("/*"))
        .flat_map(|l| {
            l.match_indices("brdftab_")
                .filter_map(|(i, _)| {
                    let rest = &l[i..];
                    let name: String = rest
                        .chars()
                        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                        .collect();
                    rest[name.len()..].starts_with('(').then_some(name)
                })
                .collect::<Vec<_>>()
        })
        .collect();
    declared.sort();
    declared.dedup();
    let nm = run(Command::new("nm")
        .args(["-D", "--defined-only"])
        .arg(lib_dir().join("libbrdftab_c.so")));
    let mut exported: Vec<String> = nm
        .lines()
        .filter_map(|l| l.split_whitespace().nth(2))
        .map(str::to_owned)
        .collect();
    exported.sort();
    // Nothing but the header's functions: no Rust symbol, no allocator, no other name.
    assert_eq!(declared, exported);
    assert!(declared.len() >= 11, "{declared:?}");
}

/// Eight threads on one fresh handle (a lazily decoding table, a measured file, a sum with a
/// mirror) give what one thread gives on another handle, bit for bit; each thread's last error
/// is its own (tests/threads_test.c).
#[test]
fn calls_from_many_threads_on_one_handle_agree_with_one_thread() {
    let dir = TempDir::new("c-threads");
    let exe = dir.join("threads_test");
    compile(
        "cc",
        &["-std=c11"],
        &Path::new(CRATE).join("tests/threads_test.c"),
        &exe,
    );
    let table = bake_table(dir.path());
    let rgl = brdftab::measured::data::rgl_dir().expect("the RGL files ship in data/rgl");
    let paper = rgl.join("paper_white_rgb.bsdf");
    for src in [
        &table[..],
        paper.to_str().unwrap(),
        r#"{"model":"sum","terms":[{"model":"lambert","kd":0.05},{"model":"mirror","fresnel":{"conductor":"Au"}}]}"#,
    ] {
        run(program(&exe).arg(src));
    }
}

/// The C++ wrapper takes empty batches from empty `std::vector`s (whose `data()` may be
/// nullptr): under UBSan, `&wi->x` on nullptr was a member access through a null pointer.
#[test]
fn the_cpp_wrapper_takes_empty_batches_from_empty_vectors() {
    let dir = TempDir::new("c-wrapper");
    let exe = dir.join("wrapper_test");
    let src = Path::new(CRATE).join("tests/wrapper_test.cpp");
    let ubsan = ["-fsanitize=undefined", "-fno-sanitize-recover=undefined"];
    // The sanitizer where the compiler links it (gcc and clang on Linux), else the plain build.
    let probe = dir.join("probe.cpp");
    std::fs::write(&probe, "int main() { return 0; }\n").unwrap();
    let has_ubsan = Command::new("g++")
        .args(ubsan)
        .arg(&probe)
        .arg("-o")
        .arg(dir.join("probe"))
        .status()
        .is_ok_and(|s| s.success());
    let mut extra = vec!["-std=c++17", "-Wextra", "-pedantic"];
    if has_ubsan {
        extra.extend(ubsan);
    }
    compile("g++", &extra, &src, &exe);
    assert_eq!(run(&mut program(&exe)).trim(), "ok");
}

/// The header's version macros, the pkg-config file's `Version`, the CMake package's version
/// (and the major.minor its compatibility rule accepts) and the library's `brdftab_version()`
/// are the crate's version (hostile_test.c compares the macros with the library at run time).
#[test]
fn the_header_and_the_pkg_config_file_carry_the_crates_version() {
    let version = env!("CARGO_PKG_VERSION");
    let header = std::fs::read_to_string(Path::new(CRATE).join("include/brdftab.h")).unwrap();
    let define = |name: &str| {
        header
            .lines()
            .find_map(|l| l.strip_prefix(&format!("#define {name} ")))
            .unwrap_or_else(|| panic!("brdftab.h: no `#define {name}`"))
            .trim()
            .to_owned()
    };
    assert_eq!(define("BRDFTAB_VERSION"), format!("\"{version}\""));
    let parts: Vec<&str> = version.split('.').collect();
    for (name, part) in ["MAJOR", "MINOR", "PATCH"].iter().zip(&parts) {
        assert_eq!(&define(&format!("BRDFTAB_VERSION_{name}")), part, "{name}");
    }
    let pc = std::fs::read_to_string(Path::new(CRATE).join("brdftab.pc.in")).unwrap();
    assert!(
        pc.lines().any(|l| l == format!("Version: {version}")),
        "{pc}"
    );
    let cmake =
        std::fs::read_to_string(Path::new(CRATE).join("cmake/brdftabConfigVersion.cmake")).unwrap();
    for line in [
        format!("set(PACKAGE_VERSION \"{version}\")"),
        format!(
            "if(PACKAGE_FIND_VERSION_MAJOR EQUAL {} AND PACKAGE_FIND_VERSION_MINOR EQUAL {}",
            parts[0], parts[1]
        ),
    ] {
        assert!(cmake.lines().any(|l| l == line), "`{line}` in {cmake}");
    }
    // SAFETY: brdftab_version returns a static NUL-terminated string.
    let lib = unsafe { std::ffi::CStr::from_ptr(brdftab_c::brdftab_version()) };
    assert_eq!(lib.to_str().unwrap(), version);
}

/// The header alone compiles without a warning as strict C99 and C++17 (and C89: it uses no
/// `//` comment, no `inline`, no declaration after a statement).
#[test]
fn the_header_compiles_cleanly_as_c89_c99_and_cpp17() {
    let dir = TempDir::new("c-header");
    for (compiler, std, file) in [
        ("cc", "-std=c89", "h.c"),
        ("cc", "-std=c99", "h.c"),
        ("c++", "-std=c++17", "h.cpp"),
    ] {
        let src = dir.join(file);
        std::fs::write(
            &src,
            "#include \"brdftab.h\"\nint main(void) { return 0; }\n",
        )
        .unwrap();
        run(Command::new(compiler)
            .args([std, "-Wall", "-Wextra", "-pedantic", "-Werror", "-c"])
            .arg(format!("-I{CRATE}/include"))
            .arg(&src)
            .arg("-o")
            .arg(dir.join("h.o")));
    }
}

/// The program the README's build blocks build (`app.c`): one Lambert lookup, printed.
const APP_C: &str = r#"#include <stdio.h>
#include <brdftab.h>
int main(void) {
    double wi[3] = {0, 0.6, 0.8}, wo[3] = {0, 0, 1};
    float f[3];
    brdftab_brdf *b = brdftab_open("{\"model\": \"lambert\", \"kd\": 0.5}");
    if (!b || brdftab_eval(b, 1, wi, wo, f) != 0) {
        fprintf(stderr, "error: %s\n", brdftab_last_error());
        return 1;
    }
    printf("%g %g %g\n", f[0], f[1], f[2]);
    brdftab_close(b);
    return 0;
}
"#;

/// The README's **Install** section: its first `lang` blocks from there on, in order.
fn readme_blocks(lang: &str, n: usize) -> Vec<String> {
    let readme = std::fs::read_to_string(Path::new(CRATE).join("README.md")).unwrap();
    let from = readme
        .find("**Install**")
        .expect("README.md: the **Install** section");
    let blocks: Vec<String> = readme[from..]
        .split(&format!("```{lang}\n"))
        .skip(1)
        .take(n)
        .map(|b| b.split("```").next().unwrap().to_owned())
        .collect();
    assert_eq!(
        blocks.len(),
        n,
        "README.md: {n} {lang} blocks after **Install**"
    );
    blocks
}

/// Runs the README's install block as a user runs it — with PREFIX `dir`/prefix and LIB where
/// this test run's libraries are — then `then` from `dir`/app, which holds `app.c`. Returns
/// the prefix and the app directory.
fn install_as_the_readme_says(dir: &Path, then: &str) -> (PathBuf, PathBuf) {
    let prefix = dir.join("prefix");
    let app = dir.join("app");
    std::fs::create_dir(&app).unwrap();
    std::fs::write(app.join("app.c"), APP_C).unwrap();
    let mut install = readme_blocks("sh", 1).remove(0);
    for (line, value) in [
        ("PREFIX=/usr/local\n", prefix.clone()),
        ("LIB=target/release\n", lib_dir()),
    ] {
        assert!(install.contains(line), "README.md: `{line}` in {install}");
        let name = line.split('=').next().unwrap();
        install = install.replace(line, &format!("{name}='{}'\n", value.display()));
    }
    let root = Path::new(CRATE).join("../..");
    let script = format!(
        "set -eu\ncd '{}'\n{install}cd '{}'\n{then}",
        root.display(),
        app.display()
    );
    run(Command::new("sh").arg("-c").arg(&script));
    (prefix, app)
}

/// `exe` run without cargo's LD_LIBRARY_PATH (it finds the installed library or none) prints
/// the Lambert's value; with `shared`, it records the library as `libbrdftab_c.so` (no
/// prefix's path), else it holds the archive's code.
fn check_app(exe: &Path, shared: bool) {
    let out = run(program(exe).env_remove("LD_LIBRARY_PATH"));
    assert_eq!(out.trim(), "0.5 0.5 0.5", "{}", exe.display());
    let dynamic = run(Command::new("readelf").arg("-d").arg(exe));
    if shared {
        assert!(dynamic.contains("[libbrdftab_c.so]"), "{dynamic}");
    } else {
        assert!(!dynamic.contains("libbrdftab_c"), "{dynamic}");
    }
}

/// The README's install block and build block (bindings/c/README.md, **Install**) run as a
/// user runs them — with PREFIX a scratch directory and LIB where this test run's libraries
/// are — and the programs they build (shared with an rpath, static from the archive) run.
#[test]
fn the_readmes_install_and_pkg_config_flow_works_as_written() {
    let build = readme_blocks("sh", 2).remove(1);
    let dir = TempDir::new("c-install");
    let (prefix, app) = install_as_the_readme_says(dir.path(), &build);
    check_app(&app.join("app"), true);
    check_app(&app.join("app-static"), false);
    // Installed without the release profile's debug line tables (before session 43 the
    // shared library was 54 MB, 48 of them DWARF; the archive 143 MB).
    for lib in ["libbrdftab_c.so", "libbrdftab_c.a"] {
        let sections = run(Command::new("readelf")
            .arg("-SW")
            .arg(prefix.join("lib").join(lib)));
        assert!(sections.contains(".text"), "{lib}: {sections}");
        assert!(!sections.contains(".debug_info"), "{lib} carries DWARF");
    }
}

/// The README's CMake project (bindings/c/README.md, after **Install**) against the prefix its
/// install block fills, configured and built with cmake as a user would: both programs run,
/// the shared one recording `libbrdftab_c.so`. The version file accepts 0.1 and no version,
/// and refuses 0.2 and 0.1.1; the prefix moved elsewhere still works (the package finds its
/// files relative to itself).
#[test]
#[ignore = "needs cmake: .ci/run installs it and runs this test"]
fn the_readmes_cmake_project_finds_the_installed_library() {
    let cmake = readme_blocks("cmake", 1).remove(0);
    let dir = TempDir::new("c-cmake");
    let (prefix, app) = install_as_the_readme_says(dir.path(), "");
    std::fs::write(app.join("CMakeLists.txt"), &cmake).unwrap();
    let configure = |src: &Path, build: &Path, prefix: &Path| {
        Command::new("cmake")
            .arg("-S")
            .arg(src)
            .arg("-B")
            .arg(build)
            .arg(format!("-DCMAKE_PREFIX_PATH={}", prefix.display()))
            .output()
            .unwrap_or_else(|e| panic!("cmake: {e} (apt-get install cmake)"))
    };
    let check = |prefix: &Path, build: &Path| {
        let out = configure(&app, build, prefix);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        run(Command::new("cmake").arg("--build").arg(build));
        check_app(&build.join("app"), true);
        check_app(&build.join("app-static"), false);
    };
    check(&prefix, &dir.join("build"));
    // Moved: the same files under another prefix (the old one gone).
    let moved = dir.join("moved");
    std::fs::rename(&prefix, &moved).unwrap();
    check(&moved, &dir.join("build-moved"));
    // Versions: none and 0.1.0 accepted; 0.2 and 0.1.1 (newer than installed) refused.
    for (want, ok) in [
        ("", true),
        ("0.1.0", true),
        ("0.2", false),
        ("0.1.1", false),
    ] {
        let src = dir.join(format!("v{want}"));
        std::fs::create_dir(&src).unwrap();
        std::fs::write(
            src.join("CMakeLists.txt"),
            format!(
                "cmake_minimum_required(VERSION 3.16)\nproject(v C)\n\
                 find_package(brdftab {want} CONFIG REQUIRED)\n"
            ),
        )
        .unwrap();
        let out = configure(&src, &src.join("build"), &moved);
        assert_eq!(
            out.status.success(),
            ok,
            "find_package(brdftab {want}): {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// A copy of table file `good` with one bit of chunk 0 flipped (its checksum then fails).
fn corrupt_copy(good: &str, bad: &Path) {
    use brdftab::store::{Store, StoreOptions};
    let mut bytes = std::fs::read(good).unwrap();
    let st = Store::from_bytes("t", bytes.clone(), StoreOptions::default()).unwrap();
    let raw = st.single().unwrap().raw_chunk(0).unwrap().to_vec();
    let at = bytes.windows(raw.len()).position(|w| w == raw).unwrap();
    bytes[at + raw.len() / 2] ^= 0x10;
    std::fs::write(bad, bytes).unwrap();
}

#[test]
fn hostile_input_through_the_c_abi_is_an_error_or_zero_never_a_crash() {
    let dir = TempDir::new("c-hostile");
    let exe = dir.join("hostile_test");
    compile(
        "cc",
        &["-std=c11"],
        &Path::new(CRATE).join("tests/hostile_test.c"),
        &exe,
    );
    let table = bake_table(dir.path());
    let bad = dir.join("bad.btdb");
    corrupt_copy(&table, &bad);
    for good in [&table[..], r#"{"model":"ggx","alpha":0.3}"#] {
        let out = program(&exe).arg(good).arg(&bad).output().unwrap();
        assert!(
            out.status.success(),
            "{good}: {:?}\n{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// The child of the next test (run by it with `--ignored`): a panic inside the C boundary's
/// guard.
#[test]
#[ignore = "a child process of a_panic_caught_at_the_boundary_prints_nothing_on_stderr"]
fn quiet_panic_child() {
    assert!(std::env::var_os("BRDFTAB_QUIET_PANIC_CHILD").is_some());
    assert_eq!(brdftab_c::panic_for_tests(), -1);
    // SAFETY: brdftab_last_error returns a NUL-terminated string valid until the next call.
    let e = unsafe { std::ffi::CStr::from_ptr(brdftab_c::brdftab_last_error()) };
    assert!(e.to_string_lossy().contains("deliberate panic"), "{e:?}");
}

#[test]
fn a_panic_caught_at_the_boundary_prints_nothing_on_stderr() {
    let out = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "quiet_panic_child",
            "--ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .env("BRDFTAB_QUIET_PANIC_CHILD", "1")
        .env("RUST_BACKTRACE", "1")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("1 passed"), "{stdout}");
    assert!(
        !stderr.contains("panicked") && !stderr.contains("backtrace"),
        "{stderr}"
    );
}
