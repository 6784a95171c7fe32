//! The storage commands end to end: bake to the brdftab format, info, db add/list/rm/verify,
//! eval DB#NAME, export.

mod common;

use brdftab::testkit::TempDir;
use common::{brdftab, brdftab_with_stdin};

#[test]
fn bake_info_db_eval_export() {
    let d = TempDir::new("cli-store");
    let p = |f: &str| d.file(f);
    let ct = r#"{"model": "cook_torrance", "m": 0.3}"#;

    let r = brdftab(&[
        "bake",
        ct,
        "-o",
        &p("ct.btdb"),
        "--preset",
        "small",
        "--codec",
        "log16:1e-3",
    ]);
    assert!(r.ok, "{}", r.stderr);
    let r = brdftab(&["info", &p("ct.btdb"), "--json"]);
    assert!(r.ok, "{}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v["format"], "btdb");
    assert_eq!(v["tables"][0]["codec"]["quant"], "log16");
    assert!(v["ratio_to_f32"].as_f64().unwrap() > 2.0);

    let db = p("lib.btdb");
    for (name, spec) in [("white", r#"{"model": "lambert", "kd": 0.5}"#), ("ct", ct)] {
        let r = brdftab(&["db", "add", &db, spec, "--name", name, "--preset", "small"]);
        assert!(r.ok, "{}", r.stderr);
    }
    let r = brdftab(&["db", "add", &db, ct, "--name", "ct", "--preset", "small"]);
    assert!(!r.ok && r.stderr.contains("--replace"), "{}", r.stderr);
    let r = brdftab(&["db", "list", &db, "--json"]);
    assert!(r.ok);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v.as_array().unwrap().len(), 2);
    let r = brdftab(&["db", "verify", &db]);
    assert!(r.ok && r.stdout.contains("ok"));

    let r = brdftab_with_stdin(&["eval", &format!("{db}#white")], "0 0.6 0.8 0 0 1\n");
    assert!(r.ok, "{}", r.stderr);
    let f: Vec<f32> = r
        .stdout
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    assert!(f.iter().all(|x| (x - 0.5).abs() < 1e-3), "{}", r.stdout);
    let r = brdftab(&["eval", &db]);
    assert!(!r.ok && r.stderr.contains("#NAME"), "{}", r.stderr);

    let r = brdftab(&[
        "export",
        &format!("{db}#ct"),
        "--npy",
        &p("ct.npy"),
        "--exr",
        &p("ct.exr"),
        "--slice",
        "3,2",
    ]);
    assert!(r.ok, "{}", r.stderr);
    assert!(
        std::fs::read(p("ct.npy"))
            .unwrap()
            .starts_with(b"\x93NUMPY")
    );

    let r = brdftab(&["db", "rm", &db, "white"]);
    assert!(r.ok);
    let r = brdftab(&["eval", &format!("{db}#white")]);
    assert!(!r.ok && r.stderr.contains("not found"), "{}", r.stderr);

    // A damaged file gives a typed error, not a panic.
    let mut b = std::fs::read(&db).unwrap();
    let n = b.len();
    b[n / 2] ^= 0x40;
    std::fs::write(p("bad.btdb"), &b).unwrap();
    let r = brdftab(&["db", "verify", &p("bad.btdb")]);
    assert!(
        !r.ok && r.stderr.starts_with("error:") && !r.stderr.contains("panicked"),
        "{}",
        r.stderr
    );
}

/// `DB#` with no name was a path: `bake -o x.btdb#` wrote a file of that name, and `info x.btdb#`
/// went looking for one. Both are argument errors now (the library's `store::name`), and no file
/// is written.
#[test]
fn an_empty_table_name_after_the_hash_is_an_argument_error() {
    let d = TempDir::new("cli-store-names");
    let out = format!("{}#", d.file("x.btdb"));
    let r = brdftab(&["bake", r#"{"model": "lambert", "kd": 0.5}"#, "-o", &out]);
    assert!(
        !r.ok && r.stderr.contains("no table name after `#`"),
        "{}",
        r.stderr
    );
    assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 0);
    let r = brdftab(&["info", &out]);
    assert!(
        !r.ok && r.stderr.contains("no table name after `#`"),
        "{}",
        r.stderr
    );
}

/// `info` and `export` say what the raw values are: a Ward table stores f_r cos θi cos θo (the
/// exported array was silently that, negative beyond the horizon), an adaptive model table is
/// multiplied by an albedo calibration at lookup, a plain preset table stores f_r.
#[test]
fn info_and_export_name_the_stored_quantity_and_calibration() {
    let d = TempDir::new("cli-quantity");
    let p = |f: &str| d.file(f);
    let cases = [
        (
            r#"{"model": "ward", "ks": 0.5, "alpha_x": 0.1, "alpha_y": 0.3}"#,
            "small",
            "fr_cos_cos",
            false,
            "f_r cos θi cos θo",
        ),
        (
            r#"{"model": "ggx", "alpha": 0.3}"#,
            "adaptive:24x12x7",
            "fr",
            true,
            "albedo calibration",
        ),
        (
            r#"{"model": "lambert", "kd": 0.5}"#,
            "small",
            "fr",
            false,
            "stores:   f_r\n",
        ),
    ];
    for (k, (spec, grid, quantity, calibrated, text)) in cases.into_iter().enumerate() {
        let t = p(&format!("t{k}.btdb"));
        let how = if grid == "small" {
            "--preset"
        } else {
            "--grid"
        };
        let r = brdftab(&["bake", spec, "-o", &t, how, grid]);
        assert!(r.ok, "{}", r.stderr);
        let r = brdftab(&["info", &t, "--json"]);
        let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
        assert_eq!(v["tables"][0]["quantity"], quantity, "{spec}: {}", r.stdout);
        assert_eq!(
            v["tables"][0]["calibrated"], calibrated,
            "{spec}: {}",
            r.stdout
        );
        let r = brdftab(&["info", &t]);
        assert!(r.stdout.contains(text), "{spec}: {}", r.stdout);
        let r = brdftab(&["export", &t, "--npy", &p(&format!("t{k}.npy"))]);
        assert!(
            r.ok && r.stderr.contains(&format!("stored values: {quantity}")),
            "{spec}: {}",
            r.stderr
        );
    }
}

/// A file named `a#b.btdb` (or a `.bsdf` in `scan#2/`) was split as DB#NAME (table `b.btdb` of a
/// database `a`): `eval` said `a: no such file`, `info` that it was no raw table. The whole
/// string names a file, so it is that file; and a convert from `p#w.bsdf` names its table `p_w`.
#[test]
fn files_with_a_hash_in_their_names_open_as_files() {
    let d = TempDir::new("cli-store-hash");
    let lambert = r#"{"model": "lambert", "kd": 0.5}"#;
    let plain = d.file("plain.btdb");
    let r = brdftab(&["bake", lambert, "-o", &plain, "--preset", "small"]);
    assert!(r.ok, "{}", r.stderr);
    std::fs::create_dir(d.join("scan#2")).unwrap();
    for f in ["a#b.btdb", "scan#2/x#y.btdb"] {
        let whole = d.file(f);
        std::fs::copy(&plain, &whole).unwrap();
        let r = brdftab_with_stdin(&["eval", &whole], "0 0 1 0 0 1\n");
        assert!(r.ok, "{f}: {}", r.stderr);
        assert!(r.stdout.starts_with("5e-1 "), "{f}: {}", r.stdout);
        let r = brdftab(&["info", &whole, "--json"]);
        assert!(r.ok, "{f}: {}", r.stderr);
    }
    // Relative to the working directory, as a user types it.
    let mut c = common::command(&["info", "a#b.btdb"]);
    c.current_dir(d.path());
    let r = common::run(c, "");
    assert!(r.ok, "{}", r.stderr);
    let rgl = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/rgl/paper_white_rgb.bsdf"
    );
    let hashed = d.file("scan#2/p#w.bsdf");
    std::fs::copy(rgl, &hashed).unwrap();
    let out = d.file("out.btdb");
    let r = brdftab(&[
        "convert", &hashed, &out, "--preset", "small", "--pairs", "1000",
    ]);
    assert!(r.ok, "{}", r.stderr);
    let r = brdftab(&["db", "list", &out]);
    assert!(
        r.ok && r.stdout.contains("p_w"),
        "{} {}",
        r.stdout,
        r.stderr
    );
}

#[test]
fn info_of_an_empty_database_says_it_holds_no_tables() {
    // It printed "0.0x smaller than f32": a ratio of no values.
    let d = TempDir::new("cli-store-empty");
    let db = d.file("empty.btdb");
    let lambert = r#"{"model": "lambert", "kd": 0.5}"#;
    let r = brdftab(&[
        "db", "add", &db, lambert, "--name", "x", "--preset", "small",
    ]);
    assert!(r.ok, "{}", r.stderr);
    let r = brdftab(&["db", "rm", &db, "x"]);
    assert!(r.ok, "{}", r.stderr);
    let r = brdftab(&["info", &db]);
    assert!(r.ok, "{}", r.stderr);
    assert!(
        r.stdout.contains("0 tables") && r.stdout.contains("(no tables)"),
        "{}",
        r.stdout
    );
    assert!(!r.stdout.contains("smaller than f32"), "{}", r.stdout);
}

/// `db rm` of a table that is not there said only `not found: table `x` in DB` where every
/// reader (`eval DB#x`, `info`, `export`) lists the tables DB holds; and `db rm` on a database
/// that does not exist created its lock file `.DB.lock` before failing, litter beside a file
/// that was never there.
#[test]
fn db_rm_names_what_the_database_holds_and_leaves_nothing_behind() {
    let d = TempDir::new("cli-store-rm");
    let db = d.file("lib.btdb");
    let lambert = r#"{"model": "lambert", "kd": 0.5}"#;
    let r = brdftab(&[
        "db", "add", &db, lambert, "--name", "white", "--preset", "small",
    ]);
    assert!(r.ok, "{}", r.stderr);
    let missing = format!("error: not found: table `nope` in {db} (has: white)\n");
    let r = brdftab(&["db", "rm", &db, "nope"]);
    assert_eq!((r.code, r.stderr.as_str()), (1, missing.as_str()));
    let r = brdftab_with_stdin(&["eval", &format!("{db}#nope")], "0 0 1 0 0 1\n");
    assert_eq!((r.code, r.stderr.as_str()), (1, missing.as_str()));
    let r = brdftab(&["db", "rm", &db, "white"]);
    assert!(r.ok, "{}", r.stderr);
    let r = brdftab(&["db", "rm", &db, "white"]);
    let empty = format!("error: not found: table `white` in {db} (it holds no table)\n");
    assert_eq!((r.code, r.stderr.as_str()), (1, empty.as_str()));

    let gone = d.file("gone.btdb");
    let r = brdftab(&["db", "rm", &gone, "white"]);
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert!(r.stderr.contains("gone.btdb: no such file"), "{}", r.stderr);
    let left: Vec<_> = std::fs::read_dir(d.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|f| f.contains("gone"))
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}

/// `db rename DB OLD NEW` (session 41): the table is read under its new name with the same
/// values; a taken NEW, a missing OLD and a missing DB are errors naming DB.
#[test]
fn db_rename_renames_and_refuses_taken_or_missing_names() {
    let d = TempDir::new("cli-store-rename");
    let db = d.file("lib.btdb");
    for (spec, name) in [
        (r#"{"model": "lambert", "kd": 0.5}"#, "white"),
        (r#"{"model": "lambert", "kd": 0.1}"#, "grey"),
    ] {
        let r = brdftab(&["db", "add", &db, spec, "--name", name, "--preset", "small"]);
        assert!(r.ok, "{}", r.stderr);
    }
    let eval = |name: &str| brdftab_with_stdin(&["eval", &format!("{db}#{name}")], "0 0 1 0 0 1\n");
    let white = eval("white").stdout;
    let r = brdftab(&["db", "rename", &db, "white", "snow"]);
    assert!(r.ok, "{}", r.stderr);
    assert_eq!(r.stderr, format!("renamed `white` to `snow` in {db}\n"));
    assert_eq!(eval("snow").stdout, white);
    let r = brdftab(&["db", "list", &db]);
    assert!(
        r.stdout.find("snow") < r.stdout.find("grey") && !r.stdout.contains("white"),
        "{}",
        r.stdout
    );

    let r = brdftab(&["db", "rename", &db, "snow", "grey"]);
    let taken = format!("error: {db} already holds a table `grey`\n");
    assert_eq!((r.code, r.stderr.as_str()), (1, taken.as_str()));
    let r = brdftab(&["db", "rename", &db, "white", "x"]);
    let missing = format!("error: not found: table `white` in {db} (has: snow, grey)\n");
    assert_eq!((r.code, r.stderr.as_str()), (1, missing.as_str()));
    let r = brdftab(&["db", "rename", &db, "snow", "a#b"]);
    assert!(
        r.code == 1 && r.stderr.contains("contains `#`"),
        "{}",
        r.stderr
    );
    let gone = d.file("gone.btdb");
    let r = brdftab(&["db", "rename", &gone, "a", "b"]);
    assert!(
        r.code == 1 && r.stderr.contains("gone.btdb: no such file"),
        "{}",
        r.stderr
    );
}

/// `bake SOURCE -o lib.btdb` over a database of several tables replaced the whole library with
/// one table, silently (`convert SOURCE lib.btdb` adds a table instead); `import -o lib.btdb`
/// too. A database of several tables is now refused as such an output, before the work; a
/// one-table file is still replaced as any output is.
#[test]
fn a_one_table_file_is_not_written_over_a_database() {
    let d = TempDir::new("cli-store-over-db");
    let db = d.file("lib.btdb");
    let spec = |kd: f64| format!(r#"{{"model": "lambert", "kd": {kd}}}"#);
    for (name, kd) in [("white", 0.5), ("grey", 0.2)] {
        let r = brdftab(&[
            "db",
            "add",
            &db,
            &spec(kd),
            "--name",
            name,
            "--preset",
            "small",
        ]);
        assert!(r.ok, "{}", r.stderr);
    }
    let before = std::fs::read(&db).unwrap();
    let r = brdftab(&["bake", &spec(0.1), "-o", &db, "--preset", "small"]);
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert_eq!(
        r.stderr,
        format!(
            "error: invalid argument `--output`: {db} is a database of 2 tables: a one-table \
             file written there would drop them all (write {db}#NAME to add a table, or remove \
             the file first)\n"
        )
    );
    let npy = d.file("white.npy");
    let white = format!("{db}#white");
    assert!(brdftab(&["export", &white, "--npy", &npy]).ok);
    let r = brdftab(&["import", &npy, "--like", &white, "-o", &db]);
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert!(
        r.stderr.contains("is a database of 2 tables"),
        "{}",
        r.stderr
    );
    assert_eq!(std::fs::read(&db).unwrap(), before, "the database changed");
    // One table: a file baked before is replaced.
    let one = d.file("one.btdb");
    for kd in [0.1, 0.3] {
        let r = brdftab(&["bake", &spec(kd), "-o", &one, "--preset", "small"]);
        assert!(r.ok, "{}", r.stderr);
    }
    let r = brdftab_with_stdin(&["eval", &one], "0 0 1 0 0 1\n");
    assert!(r.stdout.starts_with("3e-1 "), "{}", r.stdout);
}
