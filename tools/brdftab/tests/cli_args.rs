//! Arguments as the user typed them: errors name flags (`--max-depth`, not `max_depth`), usage
//! says what is required, negative numbers reach the range checks, and a flag that would do
//! nothing in the chosen mode is refused rather than ignored.

mod common;

use brdftab::testkit::TempDir;
use common::{Run, brdftab};

const LAMBERT: &str = r#"{"model": "lambert", "kd": 0.5}"#;

/// Exit 1, `error:` first, no panic, nothing on stdout, and every needle in stderr.
fn refused(o: &Run, needles: &[&str]) {
    assert_eq!(o.code, 1, "stderr: {}", o.stderr);
    assert!(o.stderr.starts_with("error:"), "stderr: {}", o.stderr);
    assert!(!o.stderr.contains("panicked"), "stderr: {}", o.stderr);
    assert!(o.stdout.is_empty(), "stdout: {}", o.stdout);
    for n in needles {
        assert!(o.stderr.contains(n), "`{n}` not in: {}", o.stderr);
    }
}

#[test]
fn library_argument_errors_name_the_flag_or_value_the_user_typed() {
    let d = TempDir::new("args-names");
    let png = d.file("r.png");
    let render = |extra: &[&str]| {
        let args = ["render", LAMBERT, "-o", &png, "--size", "8x8"];
        brdftab(&[&args[..], extra].concat())
    };
    // Fields of the preview's options, named by the library as `max_depth`, `spp`, `threads`.
    refused(&render(&["--max-depth", "0"]), &["`--max-depth`"]);
    refused(&render(&["--spp", "0"]), &["`--spp`"]);
    refused(&render(&["--threads", "0"]), &["`--threads`"]);
    refused(&render(&["--mode", "bogus"]), &["`--mode`"]);
    // A settings field of a nested subcommand (`db add`).
    let db = d.file("lib.btdb");
    let o = brdftab(&[
        "db",
        "add",
        &db,
        LAMBERT,
        "--name",
        "a",
        "--preset",
        "small",
        "--target-error",
        "1%",
    ]);
    refused(&o, &["`--target-error`"]);
    // A positional value: `convert`'s OUTPUT onto its input.
    let t = d.file("t.btdb");
    assert!(brdftab(&["bake", LAMBERT, "-o", &t, "--preset", "small"]).ok);
    refused(
        &brdftab(&["convert", &t, &t, "--pairs", "0"]),
        &["`OUTPUT`", "is the input"],
    );
    // `fit`'s model, and an open setting.
    refused(
        &brdftab(&["fit", LAMBERT, "--model", "bogus"]),
        &["`--model`"],
    );
    refused(
        &brdftab(&["eval", LAMBERT, "--interp", "bogus"]),
        &["`--interp`"],
    );
    // A value clap parses names its flag once: `--wavelengths abc` also said "invalid
    // argument `wavelengths`" after clap's "for '--wavelengths'".
    let o = brdftab(&["eval", LAMBERT, "--wavelengths", "400,abc"]);
    refused(&o, &["--wavelengths", "`abc` is not a number"]);
    assert_eq!(o.stderr.matches("wavelengths").count(), 1, "{}", o.stderr);
    // `bench --pairs 0` spoke of "repeats", which is no flag.
    let o = brdftab(&["bench", LAMBERT, "--pairs", "0"]);
    refused(&o, &["`--pairs`"]);
    assert!(!o.stderr.contains("repeats"), "{}", o.stderr);
}

#[test]
fn the_top_level_help_says_what_the_tool_does() {
    // The `Cli` doc comment, not the tools crate's Cargo description ("The brdftab application:
    // the `brdftab` CLI, the preview renderer, ..."), which a bare `about` put there.
    let o = brdftab(&["--help"]);
    assert!(o.ok, "{}", o.stderr);
    assert!(
        o.stdout.starts_with(
            "Tabulated BRDFs: analytic models, dense compressed tables, measured data\n"
        ),
        "{}",
        o.stdout
    );
}

/// Every subcommand's help names each positional argument with a description, and speaks of
/// flags rather than the library's field names (`db rename --help` listed `<DB> <OLD> <NEW>`
/// bare; `bake --help` said "see target_error" where the flag is `--target-error`).
#[test]
fn every_help_describes_its_arguments_in_the_users_words() {
    let commands = "eval models bake export import info bench render slice convert albedo check \
                    demo accuracy fit sample pdf view db:add db:list db:rm db:rename db:verify";
    for cmd in commands.split_whitespace() {
        let cmd: Vec<&str> = cmd.split(':').collect();
        let o = brdftab(&[&cmd[..], &["--help"]].concat());
        assert!(o.ok, "{cmd:?}: {}", o.stderr);
        for field in [
            "target_error",
            "max_depth",
            "codec_tolerance",
            "symmetry_tolerance",
        ] {
            assert!(
                !o.stdout.contains(field),
                "{cmd:?} says `{field}`: {}",
                o.stdout
            );
        }
        let Some((_, args)) = o.stdout.split_once("Arguments:\n") else {
            continue;
        };
        // Short help: `  <SOURCE>  text`; long help (`slice`): the text on the next line.
        let lines: Vec<&str> = args
            .lines()
            .take_while(|l| !l.starts_with("Options:"))
            .collect();
        for (i, line) in lines.iter().enumerate() {
            let line = line.trim();
            if !line.starts_with(['<', '[']) {
                continue;
            }
            let end = line.find(['>', ']']).expect(line) + 1;
            let next = lines.get(i + 1).map_or("", |l| l.trim());
            let described = !line[end..].trim_start_matches("...").trim().is_empty()
                || !(next.is_empty() || next.starts_with(['<', '[']));
            assert!(described, "{cmd:?}: `{line}` has no help: {}", o.stdout);
        }
    }
}

#[test]
fn usage_says_what_is_required() {
    let o = brdftab(&["bake", "--help"]);
    assert!(o.ok, "{}", o.stderr);
    assert!(
        o.stdout
            .contains("Usage: brdftab bake [OPTIONS] --output <OUTPUT> <SOURCE>"),
        "{}",
        o.stdout
    );
    refused(&brdftab(&["bake", LAMBERT]), &["--output"]);
    // A database's tables are found by name: `db add` requires one, and its help says so
    // (it documented a default, a file's stem, that `db add` never used).
    let o = brdftab(&["db", "add", "--help"]);
    assert!(o.ok, "{}", o.stderr);
    assert!(
        o.stdout
            .contains("Usage: brdftab db add [OPTIONS] --name <NAME> <DB> <SOURCE>"),
        "{}",
        o.stdout
    );
    assert!(!o.stdout.contains("stem"), "{}", o.stdout);
    let d = TempDir::new("args-db-name");
    let o = brdftab(&["db", "add", &d.file("lib.btdb"), LAMBERT]);
    refused(&o, &["--name <NAME>"]);
    // `bench` times any SOURCE (its help said a table or a spec, but RGL and MERL files and
    // `DB#NAME` are timed too, as BENCHMARKS.md does) and says where --measured looks first.
    let o = brdftab(&["bench", "--help"]);
    assert!(o.ok, "{}", o.stderr);
    assert!(
        o.stdout
            .contains("Any SOURCE: a spec, a table (`FILE.btdb`, `DB#NAME`), a MERL or RGL")
            && o.stdout
                .contains("(default: $BRDFTAB_RGL_DIR, else the shipped data/rgl)"),
        "{}",
        o.stdout
    );
    // `bench` times SOURCE or, with --measured, the RGL files: not both.
    let o = brdftab(&["bench", LAMBERT, "--measured", "/no/such/dir"]);
    refused(&o, &["--measured"]);
    assert!(o.stderr.contains("cannot be used with"), "{}", o.stderr);
}

/// `convert` takes its output as `bake` and `render` do (`-o OUTPUT`) as well as positionally:
/// the same file either way, one of them required, not both.
#[test]
fn convert_takes_its_output_positionally_or_as_bake_does() {
    let d = TempDir::new("args-convert-o");
    let (a, b) = (d.file("a.bsdf"), d.file("b.bsdf"));
    let small = [
        "--theta-i",
        "2",
        "--resolution",
        "8",
        "--ndf-resolution",
        "16",
    ];
    let run = |out: &[&str]| {
        brdftab(&[&["convert", LAMBERT][..], out, &small, &["--pairs", "0"]].concat())
    };
    assert!(run(&[&a]).ok);
    let o = run(&["-o", &b]);
    assert!(o.ok, "{}", o.stderr);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    refused(&run(&[&a, "--output", &b]), &["cannot be used with"]);
    refused(&run(&[]), &["OUTPUT"]);
}

#[test]
fn negative_numbers_reach_the_range_checks() {
    let d = TempDir::new("args-negative");
    let png = d.file("s.png");
    // clap read `-10` as a flag `-1`: "unexpected argument".
    let o = brdftab(&[
        "slice",
        LAMBERT,
        "--kind",
        "polar",
        "--theta-in",
        "-10",
        "-o",
        &png,
        "--size",
        "8",
    ]);
    refused(&o, &["`--theta-in`", "above the horizon"]);
    let o = brdftab(&[
        "slice", LAMBERT, "--kind", "polar", "--phi-in", "-30", "-o", &png, "--size", "8",
    ]);
    assert!(o.ok, "{}", o.stderr);
    // Flags the library's settings structs derive take them too.
    let t = d.file("t.btdb");
    let bake = |extra: &[&str]| {
        let args = ["bake", LAMBERT, "-o", &t, "--preset", "small"];
        brdftab(&[&args[..], extra].concat())
    };
    refused(&bake(&["--level", "-1"]), &["`--level`", "1..=22"]);
    refused(
        &bake(&["--symmetry-tolerance", "-1"]),
        &["`--symmetry-tolerance`"],
    );
}

#[test]
fn flags_of_another_mode_are_refused_not_ignored() {
    let d = TempDir::new("args-modes");
    let png = d.file("x.png");
    let render = |extra: &[&str]| {
        let args = ["render", LAMBERT, "-o", &png, "--size", "8x8", "--spp", "1"];
        brdftab(&[&args[..], extra].concat())
    };
    refused(&render(&["--compare-seed", "3"]), &["--compare"]);
    refused(
        &render(&["--mode", "lit", "--max-depth", "3"]),
        &["`--max-depth`", "path"],
    );
    // The lit sphere's one bounce does sample (light, BRDF or both): --sampling is used.
    let o = render(&["--mode", "lit", "--sampling", "brdf"]);
    assert!(o.ok, "{}", o.stderr);
    // ... but BRDF sampling never reaches a point light: the image lacked the light asked for.
    refused(
        &render(&["--light", "point", "--sampling", "brdf"]),
        &["`--light`", "point light"],
    );
    let slice = |extra: &[&str]| {
        let args = ["slice", LAMBERT, "-o", &png, "--size", "8"];
        brdftab(&[&args[..], extra].concat())
    };
    refused(
        &slice(&["--kind", "polar", "--phi-d", "30"]),
        &["`--phi-d`", "halfdiff"],
    );
    refused(&slice(&["--theta-in", "30"]), &["`--theta-in`", "polar"]);
    refused(
        &slice(&["--kind", "halfdiff", "--phi-in", "30"]),
        &["`--phi-in`", "polar"],
    );
    assert!(slice(&["--kind", "halfdiff", "--phi-d", "30"]).ok);
    assert!(slice(&["--kind", "polar", "--theta-in", "30", "--phi-in", "10"]).ok);
    // `demo --plausibility` bakes nothing: the bake's flags were ignored (`--preset huge`
    // exited 0), and a bad preset was refused only after the plausibility table was printed.
    for extra in [
        &["--preset", "small"][..],
        &["--preset", "huge"],
        &["--quick"],
        &["--rgl", "data/rgl"],
        &["--out", &d.file("demo")],
    ] {
        let o = brdftab(&[&["demo", "--plausibility"][..], extra].concat());
        refused(&o, &["--plausibility", extra[0]]);
    }
    refused(
        &brdftab(&["demo", "--preset", "huge", "--out", &d.file("demo")]),
        &["`--preset`", "huge"],
    );
}

#[test]
fn an_exposure_that_is_no_number_is_refused() {
    // NaN or infinite stops wrote an all-black PNG and succeeded.
    let d = TempDir::new("args-exposure");
    let png = d.file("x.png");
    for x in ["nan", "inf", "-inf"] {
        let e = format!("--exposure={x}");
        let o = brdftab(&[
            "render", LAMBERT, "-o", &png, "--size", "8x8", "--spp", "1", &e,
        ]);
        refused(&o, &["`--exposure`"]);
        assert!(!std::path::Path::new(&png).exists(), "{x}: written");
    }
    let o = brdftab(&[
        "render",
        LAMBERT,
        "-o",
        &png,
        "--size",
        "8x8",
        "--spp",
        "1",
        "--exposure",
        "-2",
    ]);
    assert!(o.ok, "{}", o.stderr);
}

#[test]
fn bench_measured_prints_no_line_that_looks_like_an_error() {
    // Its column legend began `error: relative RMSE ...`, the CLI's error format.
    let rgl = brdftab::measured::data::rgl_dir().expect("data/rgl ships");
    let d = TempDir::new("args-bench");
    std::fs::copy(
        rgl.join("paper_white_rgb.bsdf"),
        d.join("paper_white_rgb.bsdf"),
    )
    .unwrap();
    let dir = d.path().to_str().unwrap();
    let o = brdftab(&["bench", "--measured", dir, "--pairs", "1000"]);
    assert!(o.ok, "{}", o.stderr);
    assert!(o.stdout.contains("paper_white_rgb"), "{}", o.stdout);
    // The table's speed on a renderer's f32 directions is reported beside the exact pairs'.
    assert!(o.stdout.contains("table ns, f32 pairs"), "{}", o.stdout);
    assert!(
        !o.stdout.lines().any(|l| l.starts_with("error")),
        "{}",
        o.stdout
    );
    refused(
        &brdftab(&["bench", "--measured", dir, "--pairs", "3"]),
        &["`--pairs`"],
    );
}

/// A usage error was clap's block — `error: ...`, a blank line, the usage, `For more
/// information, try '--help'.` — where every other error of the CLI is one line `error: ...`
/// that a script can read. Now one line too, keeping clap's message, its tip and the usage.
#[test]
fn usage_errors_are_one_line() {
    let out = "x.btdb";
    for (args, needles) in [
        (
            vec![
                "bake", LAMBERT, "-o", out, "--preset", "small", "--preset", "large",
            ],
            &[
                "'--preset <PRESET>' cannot be used multiple times",
                "usage: brdftab bake",
            ][..],
        ),
        (
            vec!["db", "add", "lib.btdb", LAMBERT],
            &["required arguments were not provided: --name <NAME>"][..],
        ),
        (
            vec!["export", "t.btdb", "-o", "t.npy"],
            &["unexpected argument '-o'", "tip:"][..],
        ),
        (
            vec!["db", "list", "x.btdb", "--json", "--json"],
            &["'--json' cannot be used"][..],
        ),
        (
            vec!["db"],
            &["a subcommand is required", "usage: brdftab db <COMMAND>"][..],
        ),
        (vec![], &["a subcommand is required"][..]),
        (
            vec!["bake", LAMBERT, "-o", out, "--calibrate", "maybe"],
            &["invalid value 'maybe'", "[possible values: true, false]"][..],
        ),
    ] {
        let o = brdftab(&args);
        refused(&o, needles);
        assert_eq!(o.stderr.lines().count(), 1, "{args:?}: {}", o.stderr);
        assert!(!o.stderr.contains("For more information"), "{}", o.stderr);
    }
}
