//! Outputs written through a symbolic link replace the file the link points to, not the link
//! (as a shell's `>` does; databases already did, `tests/concurrency.rs`). Every single-file
//! writer renames a temporary file into place, and a rename onto a link replaced the link: the
//! file it pointed to kept its old content and the link became a file of its own.
#![cfg(unix)]

use brdftab::request::{ConvertSettings, convert};
use brdftab::testkit::TempDir;
use brdftab::{Brdf, progress::Silent};
use std::path::Path;

const SPEC: &str = r#"{"model": "lambert", "kd": 0.2}"#;

/// `link` → `target` (relative, into a subdirectory, so that the target's directory is not the
/// link's), with old content in the target — none for a table file, which a bake adds to.
fn linked(d: &TempDir, name: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    std::fs::create_dir_all(d.join("real")).unwrap();
    let target = d.join("real").join(name);
    if !name.ends_with(".btdb") {
        std::fs::write(&target, b"old").unwrap();
    }
    let link = d.join(name);
    std::os::unix::fs::symlink(Path::new("real").join(name), &link).unwrap();
    (link, target)
}

fn still_a_link(link: &Path) {
    assert!(
        std::fs::symlink_metadata(link).unwrap().is_symlink(),
        "{} was replaced by a file",
        link.display()
    );
}

#[test]
fn every_single_file_output_through_a_link_replaces_its_target() {
    let d = TempDir::new("output-links");
    let settings = ConvertSettings {
        pairs: Some(0),
        ..Default::default()
    };
    for name in ["t.btdb", "t.bsdf", "t.binary"] {
        let (link, target) = linked(&d, name);
        convert(SPEC, link.to_str().unwrap(), &settings, &Silent).unwrap();
        still_a_link(&link);
        let b = brdftab::open(target.to_str().unwrap()).unwrap();
        let mut f = [0f32; 3];
        b.eval(glam::DVec3::Z, glam::DVec3::new(0.3, 0.0, 0.9), &mut f);
        assert!(f.iter().all(|x| (x - 0.2).abs() < 2e-3), "{name}: {f:?}");
        // No temporary file left beside either name.
        for dir in [d.path().to_path_buf(), d.join("real")] {
            let stray: Vec<_> = std::fs::read_dir(&dir)
                .unwrap()
                .filter_map(|e| e.ok())
                .filter(|e| e.file_name().to_string_lossy().contains(".tmp."))
                .collect();
            assert!(stray.is_empty(), "{stray:?}");
        }
    }
    // A table exported to .npy through a link.
    let (link, target) = linked(&d, "v.npy");
    let store = brdftab::store::Store::open(d.join("real/t.btdb")).unwrap();
    let table = store.single().unwrap();
    let grid = table.grid().unwrap();
    let off = brdftab::store::tables::node_offset(&grid);
    brdftab::store::export::npy(&table, &link, Some(&off)).unwrap();
    still_a_link(&link);
    assert!(std::fs::read(&target).unwrap().starts_with(b"\x93NUMPY"));
}
