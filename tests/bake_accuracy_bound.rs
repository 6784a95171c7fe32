//! A bake whose accuracy report asks for more pairs than the report compares fails before it
//! writes: it wrote the table (replacing an old one) and then returned the error.

use brdftab::Error;
use brdftab::bake::{BakeRequest, BakeTarget};
use brdftab::table::presets::Preset;
use brdftab::testkit::TempDir;

#[test]
fn too_many_accuracy_pairs_write_nothing() {
    let d = TempDir::new("accuracy-bound");
    let file = d.file("t.btdb");
    let spec = r#"{"model": "ggx", "alpha": 0.3}"#;
    let pairs = brdftab::analysis::accuracy::MAX_SAMPLES / 3 + 1;
    let e = BakeRequest::new(spec)
        .preset(Preset::Small)
        .accuracy(pairs)
        .run(&BakeTarget::file(&file))
        .unwrap_err();
    assert!(
        matches!(&e, Error::InvalidArgument { name, .. } if name == "pairs"),
        "{e}"
    );
    assert!(!std::path::Path::new(&file).exists());
    // An old table there stays as it was.
    BakeRequest::new(r#"{"model": "lambert", "kd": 0.5}"#)
        .preset(Preset::Small)
        .run(&BakeTarget::file(&file))
        .unwrap();
    let before = std::fs::read(&file).unwrap();
    let e = BakeRequest::new(spec)
        .preset(Preset::Small)
        .accuracy(usize::MAX)
        .run(&BakeTarget::file(&file))
        .unwrap_err();
    assert!(
        matches!(&e, Error::InvalidArgument { name, .. } if name == "pairs"),
        "{e}"
    );
    assert_eq!(std::fs::read(&file).unwrap(), before);
}
