//! Any bytes as a tensor file, through the `.bsdf` writer and back:
//!
//! 1. the container round trip — every field the reader accepted, written again with
//!    `TensorWriter` (its dtype, shape and bytes), must read back as the same field list
//!    with the same bytes;
//! 2. for a file the RGL reader accepts (at most 2^16 stored values: the fuzzer's time), the
//!    re-encoding `brdftab convert x.bsdf y.bsdf` runs — the file's own parameterization
//!    (`Parameterization::from_tensor`), `rgl_write::encode` of the file as the source — and
//!    what it wrote must read back: the tensor file and the RGL reader accept it, and its
//!    fields read back are the encoder's, field for field.
#![no_main]

use brdftab::Silent;
use brdftab::measured::RglBrdf;
use brdftab::measured::rgl_write::{Options, Parameterization, encode};
use brdftab::measured::tensor::{TensorFile, TensorWriter};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(t) = TensorFile::from_bytes("fuzz.bsdf", data.to_vec()) else { return };
    let mut w = TensorWriter::new();
    for f in t.fields() {
        let shape: Vec<u64> = f.shape.iter().map(|&d| d as u64).collect();
        w = w.raw(&f.name, f.dtype, &shape, t.raw(f).to_vec());
    }
    let back = TensorFile::from_bytes("back.bsdf", w.to_bytes()).expect("a written container reads back");
    assert_eq!(back.fields().len(), t.fields().len());
    for (a, b) in t.fields().iter().zip(back.fields()) {
        assert_eq!((&a.name, a.dtype, &a.shape), (&b.name, b.dtype, &b.shape));
        assert_eq!(t.raw(a), back.raw(b), "field `{}`", a.name);
    }

    let Ok(src) = RglBrdf::from_tensor(&t, None) else { return };
    let Ok(p) = Parameterization::from_tensor(&t) else { return };
    if p.values.1.len() > 1 << 16 || p.vndf.len() > 1 << 16 {
        return;
    }
    let opts = Options { parameterization: Some(p), ..Options::default() };
    let Ok(f) = encode(&src, &opts, &Silent) else { return };
    let bytes = f.to_bytes();
    let out = TensorFile::from_bytes("out.bsdf", bytes).expect("the writer's file reads back");
    if let Err(e) = RglBrdf::from_tensor(&out, None) {
        panic!("the RGL reader refuses what the writer wrote: {e}");
    }
    let get = |name: &str| out.to_f32(out.field(name).expect("written field")).expect("f32");
    assert_eq!(get("phi_i"), f.phi_i);
    assert_eq!(get("theta_i"), f.theta_i);
    assert_eq!(get("ndf"), f.ndf);
    assert_eq!(get("sigma"), f.sigma);
    assert_eq!(get("vndf"), f.vndf);
    let values = get(if f.wavelengths.is_some() { "spectra" } else { "rgb" });
    assert!(values.iter().zip(&f.values).all(|(a, b)| a.to_bits() == b.to_bits()));
    assert_eq!(out.raw(out.field("valid").expect("valid")), f.valid);
});
