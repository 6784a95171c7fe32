//! The tensor container's unit tests: every dtype decodes, and every truncation, unknown dtype,
//! out-of-range shape or offset and non-finite value is an error naming where it is.

use super::*;
use crate::error::Error;

fn sample() -> Vec<u8> {
    let h = [
        half::f16::from_f32(1.5).to_bits(),
        half::f16::from_f32(-2.0).to_bits(),
    ];
    TensorWriter::new()
        .u8("a", &[3], &[1, 2, 255])
        .raw("b", Dtype::I8, &[2], vec![0xff, 0x7f])
        .raw("c", Dtype::U16, &[1], 65535u16.to_le_bytes().to_vec())
        .raw("d", Dtype::I16, &[1], (-300i16).to_le_bytes().to_vec())
        .raw(
            "e",
            Dtype::U32,
            &[1],
            4_000_000_000u32.to_le_bytes().to_vec(),
        )
        .raw("f", Dtype::I32, &[1], (-7i32).to_le_bytes().to_vec())
        .raw("g", Dtype::U64, &[1], (1u64 << 40).to_le_bytes().to_vec())
        .raw(
            "h",
            Dtype::I64,
            &[1],
            (-(1i64 << 40)).to_le_bytes().to_vec(),
        )
        .raw(
            "i",
            Dtype::F16,
            &[2],
            h.iter().flat_map(|x| x.to_le_bytes()).collect(),
        )
        .f32("j", &[2, 1], &[0.25, -1.0])
        .raw("k", Dtype::F64, &[1], 1e300f64.to_le_bytes().to_vec())
        .to_bytes()
}

#[test]
fn every_dtype_decodes() {
    let t = TensorFile::from_bytes("mem", sample()).unwrap();
    let v = |n: &str| t.to_f64(t.field(n).unwrap()).unwrap();
    assert_eq!(v("a"), [1.0, 2.0, 255.0]);
    assert_eq!(v("b"), [-1.0, 127.0]);
    assert_eq!(v("c"), [65535.0]);
    assert_eq!(v("d"), [-300.0]);
    assert_eq!(v("e"), [4e9]);
    assert_eq!(v("f"), [-7.0]);
    assert_eq!(v("g"), [(1u64 << 40) as f64]);
    assert_eq!(v("h"), [-((1u64 << 40) as f64)]);
    assert_eq!(v("i"), [1.5, -2.0]);
    assert_eq!(v("j"), [0.25, -1.0]);
    assert_eq!(v("k"), [1e300]);
    assert_eq!(t.field("j").unwrap().shape, [2, 1]);
    // 1e300 does not fit in f32.
    assert!(t.to_f32(t.field("k").unwrap()).is_err());
}

#[test]
fn every_truncation_is_an_error() {
    let bytes = sample();
    for n in 0..bytes.len() {
        let r = TensorFile::from_bytes("mem", bytes[..n].to_vec());
        assert!(
            matches!(r, Err(Error::Format { .. })),
            "prefix {n} accepted"
        );
    }
}

#[test]
fn unknown_dtype_names_field_and_offset() {
    let mut b = TensorWriter::new().f32("x", &[1], &[1.0]).to_bytes();
    // header: 12 magic + 2 version + 4 count + 2 len + 1 name + 2 ndim = 23 → dtype
    b[23] = 12;
    let e = TensorFile::from_bytes("t.bsdf", b).unwrap_err().to_string();
    assert!(
        e.contains("t.bsdf") && e.contains("`x`") && e.contains("at byte 23"),
        "{e}"
    );
    assert!(e.contains("unknown dtype"), "{e}");
}

#[test]
fn shape_and_offset_past_the_end_are_errors() {
    // Shape claims more data than exists.
    let b = TensorWriter::new()
        .raw("x", Dtype::F32, &[1000], vec![0; 8])
        .to_bytes();
    let e = TensorFile::from_bytes("m", b).unwrap_err().to_string();
    assert!(e.contains("past the end"), "{e}");
    // Overflowing shape product.
    let b = TensorWriter::new()
        .raw("x", Dtype::F64, &[u64::MAX / 2, 4], vec![0; 8])
        .to_bytes();
    let e = TensorFile::from_bytes("m", b).unwrap_err().to_string();
    assert!(e.contains("overflows"), "{e}");
    // Offset far past the end.
    let mut b = TensorWriter::new().f32("x", &[1], &[1.0]).to_bytes();
    b[24..32].copy_from_slice(&u64::MAX.to_le_bytes());
    let e = TensorFile::from_bytes("m", b).unwrap_err().to_string();
    assert!(e.contains("past the end") && e.contains("`x`"), "{e}");
    // Absurd field count.
    let mut b = TensorWriter::new().f32("x", &[1], &[1.0]).to_bytes();
    b[14..18].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(TensorFile::from_bytes("m", b).is_err());
}

#[test]
fn nan_is_an_error_with_the_element_offset() {
    let b = TensorWriter::new()
        .f32("x", &[3], &[1.0, f32::NAN, 2.0])
        .to_bytes();
    let t = TensorFile::from_bytes("m", b).unwrap();
    let f = t.field("x").unwrap();
    let e = t.to_f32(f).unwrap_err().to_string();
    assert!(e.contains(&format!("at byte {}", f.offset + 4)), "{e}");
}

#[test]
fn bad_magic_and_version() {
    let mut b = TensorWriter::new().to_bytes();
    b[12] = 2;
    assert!(
        TensorFile::from_bytes("m", b.clone())
            .unwrap_err()
            .to_string()
            .contains("version")
    );
    b[0] = b'x';
    assert!(
        TensorFile::from_bytes("m", b)
            .unwrap_err()
            .to_string()
            .contains("magic")
    );
}
