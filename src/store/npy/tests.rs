//! Tests of the `.npy` header and reader: the exports' header reads back, other layouts and
//! dtypes are refused by name, and mutated or truncated files are refused, never a panic.

use super::*;

/// An `.npy` file of `version` with header dict `dict` (padded as numpy pads) and `data`.
fn npy(version: u8, dict: &str, data: &[u8]) -> Vec<u8> {
    let len_bytes = if version == 1 { 2 } else { 4 };
    let mut text = dict.to_owned();
    let unpadded = 8 + len_bytes + text.len() + 1;
    text.push_str(&" ".repeat(unpadded.next_multiple_of(64) - unpadded));
    text.push('\n');
    let mut out = MAGIC.to_vec();
    out.extend_from_slice(&[version, 0]);
    match len_bytes {
        2 => out.extend_from_slice(&(text.len() as u16).to_le_bytes()),
        _ => out.extend_from_slice(&(text.len() as u32).to_le_bytes()),
    }
    out.extend_from_slice(text.as_bytes());
    out.extend_from_slice(data);
    out
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn read(bytes: &[u8]) -> Result<(NpyHeader, Vec<f32>)> {
    let r = NpyReader::new("t.npy", bytes, bytes.len() as u64)?;
    let h = r.header().clone();
    Ok((h, r.read_f32()?))
}

/// The error of reading `bytes`: its message, which names the file, and its field and
/// offset.
fn refused(bytes: &[u8]) -> (String, Option<String>, Option<u64>) {
    match read(bytes) {
        Err(e @ Error::Format { .. }) => {
            let msg = e.to_string();
            assert!(msg.starts_with("t.npy: "), "{msg}");
            let Error::Format { field, offset, .. } = e else {
                unreachable!()
            };
            (msg, field, offset)
        }
        r => panic!("{r:?}"),
    }
}

const VALUES: [f32; 6] = [0.5, -1.0, 3.25e-7, 1e30, 0.0, f32::NAN];

#[test]
fn the_exports_header_reads_back() {
    let mut b = npy_header(&[2, 3]);
    b.extend(f32_bytes(&VALUES));
    let (h, v) = read(&b).unwrap();
    assert_eq!(
        (h.version, h.dtype, &h.shape[..]),
        ((1, 0), Dtype::F32, &[2, 3][..])
    );
    assert_eq!(h.data_offset, 128);
    assert_eq!(b.len(), 128 + 24);
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&v), bits(&VALUES));
}

#[test]
fn versions_key_orders_and_tuple_forms_read_alike() {
    let data = f32_bytes(&VALUES);
    for (version, dict) in [
        (
            1,
            "{'descr': '<f4', 'fortran_order': False, 'shape': (6,), }",
        ),
        (2, "{'shape': (6,), 'descr': '<f4', 'fortran_order': False}"),
        (
            3,
            "{\"fortran_order\": False, \"shape\": (6), \"descr\": \"<f4\"}",
        ),
        (
            1,
            "{ 'fortran_order':False,'shape':( 6 , ),'descr':'<f4' , }",
        ),
    ] {
        let (h, v) = read(&npy(version, dict, &data)).unwrap_or_else(|e| panic!("{dict}: {e}"));
        assert_eq!((h.version.0, &h.shape[..]), (version, &[6][..]), "{dict}");
        assert_eq!(v[..5], VALUES[..5], "{dict}");
    }
    for (dict, shape) in [
        (
            "{'descr': '<f4', 'fortran_order': False, 'shape': (1, 2, 3)}",
            vec![1, 2, 3],
        ),
        (
            "{'descr': '<f4', 'fortran_order': False, 'shape': (1, 2, 3,)}",
            vec![1, 2, 3],
        ),
        (
            "{'descr': '<f4', 'fortran_order': False, 'shape': (3, 0, 2)}",
            vec![3, 0, 2],
        ),
        (
            "{'descr': '<f4', 'fortran_order': False, 'shape': ()}",
            vec![],
        ),
    ] {
        let n: usize = shape.iter().product();
        let (h, v) = read(&npy(1, dict, &data[..4 * n])).unwrap();
        assert_eq!((h.shape, v.len()), (shape, n), "{dict}");
    }
}

#[test]
fn float64_is_converted_and_values_beyond_float32_are_refused() {
    let x = [0.1f64, -2.5, 1e-40, f64::INFINITY, 3.0e38];
    let data: Vec<u8> = x.iter().flat_map(|x| x.to_le_bytes()).collect();
    let dict = "{'descr': '<f8', 'fortran_order': False, 'shape': (5,), }";
    let (h, v) = read(&npy(1, dict, &data)).unwrap();
    assert_eq!(h.dtype, Dtype::F64);
    assert_eq!(h.data_offset, 128);
    assert_eq!(v, x.map(|x| x as f32));
    let mut big = data.clone();
    big[16..24].copy_from_slice(&1e300f64.to_le_bytes());
    let (msg, field, offset) = refused(&npy(1, dict, &big));
    assert_eq!(
        (field.as_deref(), offset),
        (Some("data"), Some(128 + 16)),
        "{msg}"
    );
    assert!(
        msg.contains("element 2") && msg.contains("float32"),
        "{msg}"
    );
}

#[test]
fn other_layouts_and_dtypes_are_refused_by_name() {
    let data = f32_bytes(&VALUES);
    for (dict, field, words) in [
        (
            "{'descr': '<f4', 'fortran_order': True, 'shape': (2, 3), }",
            "fortran_order",
            "Fortran",
        ),
        (
            "{'descr': '>f4', 'fortran_order': False, 'shape': (2, 3), }",
            "descr",
            "big-endian `>f4`",
        ),
        (
            "{'descr': '<i4', 'fortran_order': False, 'shape': (2, 3), }",
            "descr",
            "dtype `<i4`",
        ),
        (
            "{'descr': '<f2', 'fortran_order': False, 'shape': (2, 3), }",
            "descr",
            "dtype `<f2`",
        ),
        (
            "{'descr': [('a', '<f4')], 'fortran_order': False, 'shape': (6,), }",
            "header",
            "expected a string",
        ),
        (
            "{'descr': '<f4', 'fortran_order': False, 'shape': (-2, 3), }",
            "shape",
            "negative",
        ),
        (
            "{'descr': '<f4', 'fortran_order': False, 'shape': (99999999999999999999999, 3), }",
            "shape",
            "overflows",
        ),
        (
            "{'descr': '<f4', 'fortran_order': False, 'shape': 6, }",
            "header",
            "expected a string",
        ),
        (
            "{'descr': '<f4', 'fortran_order': False, }",
            "shape",
            "missing",
        ),
        (
            "{'descr': '<f4', 'fortran_order': False, 'shape': (6,), 'extra': 1}",
            "header",
            "unknown key `extra`",
        ),
        (
            "{'descr': '<f4', 'descr': '<f4', 'fortran_order': False, 'shape': (6,)}",
            "descr",
            "twice",
        ),
        (
            "{'descr': '<f4', 'fortran_order': False, 'shape': (6,)} x",
            "header",
            "after the header",
        ),
        (
            "{'descr': '<f4' 'fortran_order': False, 'shape': (6,)}",
            "header",
            "expected `,` or `}`",
        ),
    ] {
        let (msg, f, offset) = refused(&npy(1, dict, &data));
        assert_eq!(f.as_deref(), Some(field), "{dict}: {msg}");
        assert!(msg.contains(words), "{dict}: {msg}");
        assert!(offset.is_some_and(|o| o >= 10), "{dict}: {msg}");
    }
}

/// A shape whose product overflows, or one far larger than the file, is refused from the
/// header and the file's size alone: nothing is allocated for it.
#[test]
fn a_shape_the_file_cannot_hold_is_refused_before_allocating() {
    let data = f32_bytes(&VALUES);
    let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (4294967296, 4294967296, 16), }";
    let (msg, field, _) = refused(&npy(1, dict, &data));
    assert_eq!(field.as_deref(), Some("shape"), "{msg}");
    assert!(msg.contains("overflows"), "{msg}");
    let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (100000, 100000, 100), }";
    let b = npy(1, dict, &data);
    let (msg, field, offset) = refused(&b);
    assert_eq!(
        (field.as_deref(), offset),
        (Some("data"), Some(b.len() as u64)),
        "{msg}"
    );
    assert!(
        msg.contains("needs 4000000000000 bytes") && msg.contains("holds 24"),
        "{msg}"
    );
}

#[test]
fn truncated_files_bad_magic_and_unknown_versions_are_refused() {
    let dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }";
    let whole = npy(1, dict, &f32_bytes(&VALUES));
    assert_eq!(whole.len(), 128 + 24);
    for (cut, field) in [
        (0, "magic"),
        (5, "magic"),
        (7, "version"),
        (9, "header length"),
        (40, "header"),
        (127, "header"),
        (128, "data"),
        (whole.len() - 1, "data"),
    ] {
        let (msg, f, offset) = refused(&whole[..cut]);
        assert_eq!(f.as_deref(), Some(field), "cut at {cut}: {msg}");
        assert!(offset.is_some(), "cut at {cut}: {msg}");
    }
    let mut longer = whole.clone();
    longer.extend_from_slice(&[0, 0, 0, 0]);
    let (msg, field, offset) = refused(&longer);
    assert_eq!(
        (field.as_deref(), offset),
        (Some("data"), Some(whole.len() as u64))
    );
    assert!(msg.contains("4 bytes after"), "{msg}");
    let mut magic = whole.clone();
    magic[1] = b'n';
    let (msg, field, offset) = refused(&magic);
    assert_eq!(
        (field.as_deref(), offset),
        (Some("magic"), Some(0)),
        "{msg}"
    );
    let mut v = whole.clone();
    v[6] = 4;
    let (msg, field, offset) = refused(&v);
    assert_eq!(
        (field.as_deref(), offset),
        (Some("version"), Some(6)),
        "{msg}"
    );
    assert!(msg.contains("4.0"), "{msg}");
    // A header length beyond the bound, and one beyond the file.
    let mut long = npy(2, dict, &f32_bytes(&VALUES));
    long[8..12].copy_from_slice(&(1u32 << 30).to_le_bytes());
    let (msg, field, _) = refused(&long);
    assert_eq!(field.as_deref(), Some("header length"), "{msg}");
    long[8..12].copy_from_slice(&4000u32.to_le_bytes());
    let (msg, field, _) = refused(&long);
    assert_eq!(field.as_deref(), Some("header"), "{msg}");
    assert!(msg.contains("truncated"), "{msg}");
    let mut utf = npy(
        3,
        "{'descr': '<f4', 'fortran_order': False, 'shape': (6,), }",
        &f32_bytes(&VALUES),
    );
    utf[20] = 0xff;
    let (msg, field, _) = refused(&utf);
    assert_eq!(field.as_deref(), Some("header"), "{msg}");
}

/// Random mutants of valid files — bytes flipped, overwritten, cut and inserted, in the
/// header and the data — are read or refused with a format error, never a panic; what is
/// read holds exactly the elements its shape says.
#[test]
fn mutants_are_read_or_refused_never_a_panic() {
    let dicts = [
        (
            1,
            "{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }",
        ),
        (
            2,
            "{'shape': (3, 2), 'fortran_order': False, 'descr': '<f8'}",
        ),
        (3, "{'descr': '<f4', 'fortran_order': False, 'shape': (6,)}"),
    ];
    let mut rng = crate::rng::Pcg32::new(7);
    let (mut read_ok, mut refused) = (0, 0);
    for k in 0..30_000 {
        let (version, dict) = dicts[k % dicts.len()];
        let data = if dict.contains("<f8") {
            VALUES
                .iter()
                .flat_map(|&x| (x as f64).to_le_bytes())
                .collect()
        } else {
            f32_bytes(&VALUES)
        };
        let mut b = npy(version, dict, &data);
        for _ in 0..1 + rng.below(3) {
            let at = rng.below(b.len() as u32) as usize;
            match rng.below(4) {
                0 => b[at] ^= 1 << rng.below(8),
                1 => b[at] = b"0123456789(),' -:{}TF"[rng.below(21) as usize],
                2 => b.truncate(at),
                _ => b.insert(at, rng.below(256) as u8),
            }
            if b.is_empty() {
                break;
            }
        }
        match read(&b) {
            Ok((h, v)) => {
                assert_eq!(v.len(), h.elements());
                read_ok += 1;
            }
            Err(Error::Format { .. }) => refused += 1,
            Err(e) => panic!("mutant {k}: {e}"),
        }
    }
    assert!(
        read_ok > 1000 && refused > 10_000,
        "{read_ok} read, {refused} refused"
    );
}

#[test]
fn a_file_reads_by_its_path() {
    let d = crate::testkit::TempDir::new("npy-read");
    let p = d.join("a.npy");
    let mut b = npy_header(&[3, 2]);
    b.extend(f32_bytes(&VALUES));
    std::fs::write(&p, &b).unwrap();
    let (shape, v) = read_f32(&p).unwrap();
    assert_eq!((shape, v[..5].to_vec()), (vec![3, 2], VALUES[..5].to_vec()));
    std::fs::write(&p, &b[..b.len() - 2]).unwrap();
    let e = read_f32(&p).unwrap_err().to_string();
    assert!(e.contains("a.npy") && e.contains("truncated"), "{e}");
    assert!(matches!(
        read_f32(d.join("none.npy")),
        Err(Error::NotFound(_))
    ));
    assert!(read_f32(d.path()).is_err());
}
