//! The save and import unit tests: tables saved to files and databases, exports imported bit
//! for bit, and the errors that name their field.

use super::*;
use crate::bake::BakeRequest;
use crate::progress::Silent;
use crate::spectrum::Channels;
use crate::store::{Store, export};
use crate::table::{Mapping, Param, Symmetry};
use crate::testkit::TempDir;

fn lossless() -> SaveSettings {
    SaveSettings {
        codec: Some("f32".into()),
        ..SaveSettings::default()
    }
}

/// A small Cook-Torrance table (halfdiff, not packed).
fn ct() -> Table {
    BakeRequest::new(r#"{"model": "cook_torrance", "m": 0.3}"#)
        .grid("16x1x16x32".parse().unwrap())
        .table(&Silent)
        .unwrap()
        .0
}

/// A packed table: `inout` reciprocal, the triangle θi ≤ θo.
fn packed() -> Table {
    let g = Grid::with_sizes(
        Param::InOut,
        [8, 1, 8, 16],
        [Mapping::Uniform, Mapping::Uniform],
        Channels::Rgb,
        Symmetry {
            isotropic: true,
            reciprocal: true,
            bilateral: false,
        },
    )
    .unwrap();
    Table::from_fn(g, "packed", |i, a, out| {
        for (c, o) in out.iter_mut().enumerate() {
            *o = (a[0].cos() * a[2].cos()) as f32 * (1.0 + c as f32) + i[3] as f32 * 1e-3;
        }
    })
}

fn other(d: &str) -> store::Source {
    store::Source::Other {
        description: d.into(),
    }
}

/// The values of the stored table `source`.
fn stored(source: &str) -> Vec<f32> {
    source::open_table(source, &OpenOptions::default())
        .unwrap()
        .to_table()
        .unwrap()
        .into_parts()
        .1
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn a_table_saves_to_a_file_or_a_database_and_reports_its_info() {
    let d = TempDir::new("save-table");
    let t = ct();
    let file = d.file("ct.btdb");
    let info = save_table(&t, &file, other("edited"), &lossless()).unwrap();
    assert_eq!(info, store::info::file_info_at(&file, None).unwrap());
    let e = &info["tables"][0];
    assert_eq!(
        (&e["name"], &e["values"]),
        (&"ct".into(), &t.values().len().into())
    );
    assert_eq!(e["source"]["description"], "edited");
    assert_eq!(e["codec"]["quant"], "f32");
    assert_eq!(bits(&stored(&file)), bits(t.values()));
    // A second save replaces the file: one table, the new values.
    let doubled = t
        .with_values(t.values().iter().map(|x| 2.0 * x).collect())
        .unwrap();
    save_table(&doubled, &file, other("doubled"), &lossless()).unwrap();
    assert_eq!(Store::open(&file).unwrap().tables().len(), 1);
    assert_eq!(bits(&stored(&file)), bits(doubled.values()));

    let db = d.file("lib.btdb");
    let entry = format!("{db}#a");
    let info = save_table(&t, &entry, other("a"), &SaveSettings::default()).unwrap();
    assert_eq!(info["tables"][0]["codec"]["quant"], "log16");
    assert_eq!(info["tables"].as_array().unwrap().len(), 1);
    save_table(&t, format!("{db}#b"), other("b"), &lossless()).unwrap();
    let again = save_table(&doubled, &entry, other("a"), &lossless()).unwrap_err();
    assert!(matches!(again, Error::Duplicate { .. }), "{again}");
    let replace = SaveSettings {
        replace: true,
        ..lossless()
    };
    save_table(&doubled, &entry, other("a"), &replace).unwrap();
    assert_eq!(bits(&stored(&entry)), bits(doubled.values()));
    assert_eq!(Store::open(&db).unwrap().tables().len(), 2);
    let named = SaveSettings {
        name: Some("mine".into()),
        ..lossless()
    };
    let info = save_table(&t, d.file("x.btdb"), other("x"), &named).unwrap();
    assert_eq!(info["tables"][0]["name"], "mine");
    // Beside `DB#NAME`, a name setting may only repeat NAME, as in a bake: `Table.save(
    // "db#c", name="mine")` wrote table `c` and dropped `mine` without a word.
    let err = save_table(&t, format!("{db}#c"), other("c"), &named).unwrap_err();
    match err {
        Error::InvalidArgument { name, .. } => assert_eq!(name, "name"),
        e => panic!("{e}"),
    }
    assert_eq!(
        Store::open(&db).unwrap().tables().len(),
        2,
        "nothing written"
    );
    let same = SaveSettings {
        name: Some("c".into()),
        ..lossless()
    };
    let info = save_table(&t, format!("{db}#c"), other("c"), &same).unwrap();
    assert_eq!(info["tables"][0]["name"], "c");
}

#[test]
fn bad_settings_and_outputs_name_their_field() {
    let d = TempDir::new("save-bad");
    let t = ct();
    let out = d.file("t.btdb");
    for (json, field) in [
        (r#"{"codec": "zip"}"#, "codec"),
        (r#"{"codec": "log16:x"}"#, "codec"),
        (r#"{"level": 30}"#, "level"),
        (r#"{"name": ""}"#, "name"),
        (r#"{"name": "a#b"}"#, "name"),
    ] {
        let s: SaveSettings = super::super::from_json(json).unwrap();
        match save_table(&t, &out, other("x"), &s) {
            Err(Error::InvalidArgument { name, .. }) => assert_eq!(name, field, "{json}"),
            r => panic!("{json}: {r:?}"),
        }
    }
    match save_table(&t, format!("{out}#"), other("x"), &lossless()) {
        Err(Error::InvalidArgument { name, .. }) => assert_eq!(name, "output"),
        r => panic!("{r:?}"),
    }
    assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 0);
    // Values beyond f16 are the codec's error, and the old file stays as it was.
    save_table(&t, &out, other("x"), &lossless()).unwrap();
    let big = t.with_values(vec![1e6; t.values().len()]).unwrap();
    let f16 = SaveSettings {
        codec: Some("f16".into()),
        ..SaveSettings::default()
    };
    let e = save_table(&big, &out, other("x"), &f16).unwrap_err();
    assert!(matches!(e, Error::Encode { .. }), "{e}");
    assert_eq!(bits(&stored(&out)), bits(t.values()));
}

/// The `.npy` export of a stored table imported on its own grid is the table, bit for bit:
/// a plain table, and a packed one whose export fills the unstored nodes with NaN.
#[test]
fn an_exported_table_imports_bit_for_bit() {
    let d = TempDir::new("save-import");
    for (k, t) in [ct(), packed()].into_iter().enumerate() {
        let like = d.file(&format!("t{k}.btdb"));
        save_table(&t, &like, other("x"), &lossless()).unwrap();
        let st = Store::open(&like).unwrap().single().unwrap();
        let g = st.grid().unwrap();
        let off = tables::node_offset(&g);
        let npy = d.join(format!("t{k}.npy"));
        export::npy(&st, &npy, Some(&off)).unwrap();
        let (_, exported) = store::npy::read_f32(&npy).unwrap();
        assert_eq!(exported.iter().any(|x| x.is_nan()), g.layout().packed);
        let out = d.file(&format!("back{k}.btdb"));
        let info = import_npy(&npy, &like, &out, &lossless(), true).unwrap();
        let e = &info["tables"][0];
        assert_eq!(
            e["source"]["description"],
            format!("values from t{k}.npy on the grid of {like}")
        );
        assert_eq!(e["symmetry"], st.header().symmetry);
        assert_eq!(bits(&stored(&out)), bits(t.values()), "table {k}");
        let back = Store::open(&out).unwrap().single().unwrap().grid().unwrap();
        assert_eq!(back, g);
    }
}

/// A calibrated table's export is its values before the factors, and the import keeps the
/// grid's calibration: lookups of the imported table are the original's.
#[test]
fn an_import_keeps_the_grids_calibration() {
    let d = TempDir::new("save-import-cal");
    let (t, _) = BakeRequest::new(r#"{"model": "ggx", "alpha": 0.3}"#)
        .grid("adaptive:24x12x7".parse().unwrap())
        .table(&Silent)
        .unwrap();
    assert!(t.grid().calibration().is_some());
    let like = d.file("g.btdb");
    save_table(&t, &like, other("x"), &lossless()).unwrap();
    let st = Store::open(&like).unwrap().single().unwrap();
    let npy = d.join("g.npy");
    export::npy(&st, &npy, None).unwrap();
    let out = d.file("back.btdb");
    let info = import_npy(&npy, &like, &out, &lossless(), true).unwrap();
    assert_eq!(info["tables"][0]["calibrated"], true);
    let back = Store::open(&out)
        .unwrap()
        .single()
        .unwrap()
        .to_table()
        .unwrap();
    assert_eq!(back.grid(), t.grid());
    assert_eq!(bits(back.values()), bits(t.values()));
    // Another material's values: without the like table's calibration, the grid is the
    // uncalibrated one and the values are stored as given.
    let other_out = d.file("other.btdb");
    let info = import_npy(&npy, &like, &other_out, &lossless(), false).unwrap();
    assert_eq!(info["tables"][0]["calibrated"], false);
    let back = Store::open(&other_out)
        .unwrap()
        .single()
        .unwrap()
        .to_table()
        .unwrap();
    assert_eq!(back.grid(), &t.grid().clone().without_calibration());
    assert_eq!(bits(back.values()), bits(t.values()));
}

fn f32_npy(path: &Path, shape: &[u64], values: &[f32]) {
    let mut b = store::npy::npy_header(shape);
    b.extend(values.iter().flat_map(|x| x.to_le_bytes()));
    std::fs::write(path, b).unwrap();
}

#[test]
fn bad_imports_say_what_and_where() {
    let d = TempDir::new("save-import-bad");
    let t = ct();
    let like = d.file("ct.btdb");
    save_table(&t, &like, other("x"), &lossless()).unwrap();
    let shape: Vec<u64> = t.shape().unwrap().iter().map(|&s| s as u64).collect();
    let npy = d.join("v.npy");
    let out = d.file("out.btdb");
    let arg = |e: Error| match e {
        Error::InvalidArgument { name, msg } => (name, msg),
        e => panic!("{e}"),
    };
    let fmt = |e: Error| match e {
        Error::Format {
            file,
            field,
            offset,
            msg,
        } => (file, field, offset, msg),
        e => panic!("{e}"),
    };
    f32_npy(&npy, &shape, t.values());
    let (none, nope) = (d.file("none.btdb"), format!("{like}#nope"));
    for src in [
        r#"{"model": "lambert", "kd": 0.5}"#,
        "paper.bsdf",
        "m.binary",
        none.as_str(),
        nope.as_str(),
    ] {
        let (name, msg) = arg(import_npy(&npy, src, &out, &lossless(), true).unwrap_err());
        assert_eq!(name, "like", "{src}: {msg}");
    }
    // Not a brdftab file.
    let (name, _) =
        arg(import_npy(&npy, npy.to_str().unwrap(), &out, &lossless(), true).unwrap_err());
    assert_eq!(name, "like");
    let (name, _) =
        arg(import_npy(&npy, &like, npy.to_str().unwrap(), &lossless(), true).unwrap_err());
    assert_eq!(name, "output");

    let mut wrong = shape.clone();
    wrong.swap(0, 3);
    f32_npy(&npy, &wrong, t.values());
    let (file, field, _, msg) = fmt(import_npy(&npy, &like, &out, &lossless(), true).unwrap_err());
    assert_eq!(
        (file.as_str(), field.as_deref()),
        (npy.to_str().unwrap(), Some("shape"))
    );
    assert!(msg.contains(&format!("{:?}", t.shape().unwrap())), "{msg}");

    let mut v = t.values().to_vec();
    v[100] = f32::NAN;
    f32_npy(&npy, &shape, &v);
    let (_, field, offset, msg) =
        fmt(import_npy(&npy, &like, &out, &lossless(), true).unwrap_err());
    let h = NpyReader::open(&npy).unwrap().header().clone();
    assert_eq!(
        (field.as_deref(), offset),
        (Some("data"), Some(h.data_offset + 400))
    );
    assert!(msg.contains("NaN"), "{msg}");

    f32_npy(&npy, &shape, t.values());
    let b = std::fs::read(&npy).unwrap();
    std::fs::write(&npy, &b[..b.len() - 3]).unwrap();
    let (_, field, _, msg) = fmt(import_npy(&npy, &like, &out, &lossless(), true).unwrap_err());
    assert!(
        field.as_deref() == Some("data") && msg.contains("truncated"),
        "{msg}"
    );
    // Nothing was written.
    assert!(!Path::new(&out).exists());
}
