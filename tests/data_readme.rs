//! data/README.md is true of the files it lists: every row's bytes and SHA-256 are the file's,
//! every RGL row's "description field" is the description the file holds (colodur's read
//! "wall paint swatch" where the file says "wall paint sample swatch"), and every file of
//! data/rgl and data/merl has a row.

use sha2::{Digest, Sha256};
use std::path::Path;

const DIR: &str = env!("CARGO_MANIFEST_DIR");

/// The rows `| file | bytes | `sha256` | description or what |` of the README's tables.
fn rows() -> Vec<[String; 4]> {
    let text = std::fs::read_to_string(Path::new(DIR).join("data/README.md")).unwrap();
    text.lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| file ") && !l.starts_with("| ---"))
        .map(|l| {
            let cells: Vec<String> = l
                .trim_matches('|')
                .split(" | ")
                .map(|c| c.trim().to_owned())
                .collect();
            assert!(cells.len() >= 4, "row `{l}`");
            [
                cells[0].clone(),
                cells[1].clone(),
                cells[2].trim_matches('`').to_owned(),
                cells[3].clone(),
            ]
        })
        .collect()
}

#[test]
fn every_row_is_the_file_it_names() {
    let rows = rows();
    let mut listed = Vec::new();
    for [file, bytes, sha, description] in &rows {
        let sub = if file.ends_with(".bsdf") || file.starts_with("reference_eval") {
            "rgl"
        } else {
            "merl"
        };
        let path = Path::new(DIR).join("data").join(sub).join(file);
        let data = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(data.len().to_string(), *bytes, "{file}: bytes");
        assert_eq!(
            format!("{:x}", Sha256::digest(&data)),
            *sha,
            "{file}: sha256"
        );
        if file.ends_with(".bsdf") {
            let rgl = brdftab::measured::RglBrdf::open(&path).unwrap();
            assert_eq!(rgl.description(), description, "{file}: description field");
        }
        listed.push(format!("{sub}/{file}"));
    }
    for sub in ["rgl", "merl"] {
        for e in std::fs::read_dir(Path::new(DIR).join("data").join(sub)).unwrap() {
            let name = format!("{sub}/{}", e.unwrap().file_name().to_string_lossy());
            assert!(
                listed.contains(&name),
                "{name} has no row in data/README.md"
            );
        }
    }
    assert_eq!(listed.len(), 10, "{listed:?}");
}
