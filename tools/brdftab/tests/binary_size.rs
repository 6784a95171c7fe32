//! DESIGN.md's rule for the `brdftab` binary: argument parsing and printing only, one file per
//! subcommand group, under 2,000 lines in all and no file over 300. The binary's files are
//! main.rs and the modules it declares (`mod NAME;`, or `#[path = "..."] mod NAME;`).

use std::path::Path;

const DIR: &str = env!("CARGO_MANIFEST_DIR");

#[test]
fn the_binary_is_under_2000_lines_and_no_file_over_300() {
    let main = std::fs::read_to_string(Path::new(DIR).join("main.rs")).unwrap();
    let mut files = vec!["main.rs".to_owned()];
    let mut path_attr: Option<String> = None;
    for line in main.lines().map(str::trim) {
        if let Some(p) = line
            .strip_prefix("#[path = \"")
            .and_then(|r| r.strip_suffix("\"]"))
        {
            path_attr = Some(p.to_owned());
        } else if let Some(name) = line.strip_prefix("mod ").and_then(|r| r.strip_suffix(';')) {
            files.push(path_attr.take().unwrap_or_else(|| format!("{name}.rs")));
        }
    }
    assert!(
        files.len() > 10,
        "the walk found the subcommand files: {files:?}"
    );
    let mut total = 0;
    for f in &files {
        let text = std::fs::read_to_string(Path::new(DIR).join(f))
            .unwrap_or_else(|e| panic!("{f}: {e} (a module of main.rs in a directory?)"));
        let n = text.lines().count();
        assert!(
            n <= 300,
            "{f}: {n} lines (DESIGN.md: no file of the binary over 300)"
        );
        total += n;
    }
    assert!(
        total < 2000,
        "the binary's files hold {total} lines (DESIGN.md: under 2,000): {files:?}"
    );
}
