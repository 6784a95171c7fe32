//! Any text as a host's request: the first byte picks the entry, the rest (UTF-8) is its
//! input — the JSON settings of a bake, conversion, fit, open or save (`request::from_json`,
//! the C ABI's and Python's path) and then their one validation step, or one of the library's
//! string parsers behind the CLI's flags (grid, symmetry, wavelengths, error target, names, fit
//! parameters, channels, preset, interpolation, quantity, parameterization, slice, table names
//! and `DB#NAME` splits). Errors are fine; a panic is not, and neither is a value that does
//! not survive its own round trip (settings accepted, written as JSON and read back must be
//! equal; a parsed symmetry or parameterization printed and parsed again must be equal).
#![no_main]

use brdftab::bake::{GridChoice, SymmetryChoice};
use brdftab::request::{
    BakeSettings, ConvertSettings, ErrorTarget, FitSettings, Names, OpenSettings, SaveSettings,
    Wavelengths, from_json,
};
use brdftab::table::{Quantity, param::Param, symmetry::Symmetry};
use libfuzzer_sys::fuzz_target;
use serde::Serialize;
use serde::de::DeserializeOwned;

const SOURCE: &str = r#"{"model":"lambert","kd":0.5}"#;

/// Settings accepted from `text` are written back as JSON and must read back equal.
fn settings<T>(text: &str) -> Option<T>
where
    T: DeserializeOwned + Serialize + Default + PartialEq + std::fmt::Debug,
{
    let v = from_json::<T>(text).ok()?;
    let json = serde_json::to_string(&v).expect("settings serialize");
    let back = from_json::<T>(&json);
    assert!(
        back.as_ref().is_ok_and(|b| *b == v),
        "{text:?} -> {v:?} -> {json} -> {back:?}"
    );
    Some(v)
}

fn reparse<T>(text: &str)
where
    T: std::str::FromStr + std::fmt::Display + PartialEq + std::fmt::Debug,
{
    if let Ok(v) = text.parse::<T>() {
        let shown = v.to_string();
        let back = shown.parse::<T>();
        assert!(
            back.as_ref().is_ok_and(|b| *b == v),
            "{text:?} -> {v:?} -> {shown:?} -> parsed again differently"
        );
    }
}

fuzz_target!(|data: &[u8]| {
    let [pick, rest @ ..] = data else { return };
    let Ok(text) = std::str::from_utf8(rest) else { return };
    match pick % 16 {
        0 => {
            if let Some(s) = settings::<BakeSettings>(text) {
                let _ = s.request(SOURCE);
            }
        }
        1 => {
            if let Some(s) = settings::<ConvertSettings>(text) {
                let _ = s.bake.request(SOURCE);
            }
        }
        2 => {
            if let Some(s) = settings::<FitSettings>(text) {
                let _ = s.options();
                let _ = s.fresnel();
            }
        }
        3 => {
            if let Some(s) = settings::<OpenSettings>(text) {
                let _ = s.options();
            }
        }
        4 => {
            if let Some(s) = settings::<SaveSettings>(text) {
                let _ = s.codec();
            }
        }
        5 => {
            let _ = text.parse::<GridChoice>();
        }
        6 => {
            let _ = text.parse::<SymmetryChoice>();
        }
        7 => {
            if let Ok(w) = text.parse::<Wavelengths>() {
                let _ = w.channels();
            }
        }
        8 => {
            let _ = text.parse::<ErrorTarget>();
        }
        9 => {
            let _ = text.parse::<Names>();
        }
        10 => {
            let _ = text.parse::<brdftab::fit::ParamRequest>();
        }
        11 => {
            if let Ok(c) = text.parse::<brdftab::Channels>() {
                let _ = c.validate();
            }
        }
        12 => {
            let _ = text.parse::<brdftab::Preset>();
            let _ = text.parse::<brdftab::Interp>();
            let _ = text.parse::<Quantity>();
        }
        13 => {
            reparse::<Symmetry>(text);
            reparse::<Param>(text);
        }
        14 => {
            for axes in [4, 5] {
                if let Ok(s) = brdftab::store::export::Slice::parse(text, axes) {
                    assert!(s.x < axes && s.y < axes && s.x != s.y && s.fixed.len() == axes);
                }
            }
        }
        _ => {
            let _ = brdftab::store::name::check("name", text);
            let _ = brdftab::store::name::parse_source("source", text);
            let _ = brdftab::store::name::parse_input("output", text);
            let _ = brdftab::store::name::path_of(text);
            let _ = brdftab::store::db::split_source(text);
            let _ = brdftab::classify(text);
        }
    }
});
