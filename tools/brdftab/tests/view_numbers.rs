//! `brdftab view` on measured data: a table baked from a measured file beside it.

mod common;

use brdftab::testkit::TempDir;
use common::brdftab;
use common::viewer::{get, get_json, start};

#[test]
fn a_measured_table_is_paired_with_its_file_beside_the_database() {
    let d = TempDir::new("view-measured");
    let dir = brdftab::measured::data::rgl_dir().expect("data/rgl ships with brdftab");
    let bsdf = d.file("paper_white_rgb.bsdf");
    std::fs::copy(dir.join("paper_white_rgb.bsdf"), &bsdf).unwrap();
    let db = d.file("m.btdb");
    let r = brdftab(&[
        "db", "add", &db, &bsdf, "--name", "paper", "--preset", "small",
    ]);
    assert!(r.ok, "{}", r.stderr);
    {
        let v = start(&[&db, &bsdf]);
        let list = get_json(&v, "/api/materials");
        assert_eq!(
            (list[0]["kind"].as_str(), list[1]["kind"].as_str()),
            (Some("table"), Some("rgl"))
        );
        assert_eq!(list[0]["provenance"]["kind"], "measured");
        assert_eq!(list[0]["has_source"], true);
        let c = get_json(&v, "/api/compare?m=0");
        assert!(c["weight"].as_str().unwrap().contains("80°"), "{c}");
        assert!(c["rel_rmse"].as_f64().unwrap() < 0.2, "{c}");
        get_json(&v, "/api/polar?m=0&of=source&n=5");
    }
    // Without the file beside it, the table is shown alone.
    std::fs::remove_file(&bsdf).unwrap();
    let v = start(&[&db]);
    assert_eq!(get_json(&v, "/api/materials")[0]["has_source"], false);
    assert_eq!(get(&v, "/api/compare?m=0").0, 404);
    assert_eq!(get(&v, "/api/polar?m=0&of=source").0, 404);
}
