//! One request layer for every host: the settings of a bake, a conversion, a fit, an open and
//! a save (a table whose values a host made: [`save_table`], [`import_npy`]), as plain data
//! that deserialize from the same field names wherever they come from.
//!
//! The CLI's flags are these fields (`--target-error` is [`BakeSettings::target_error`]; with the
//! non-default feature `clap` the structs derive `clap::Args`, so the CLI parses into them
//! directly), Python's keyword arguments are these fields (`brdftab.bake(src, out,
//! target_error=0.005)`), and the C ABI takes them as a JSON object
//! (`{"target_error": 0.005}`). Each settings type validates once ([`BakeSettings::request`],
//! [`FitSettings::options`], [`OpenSettings::options`], [`SaveSettings::codec`]; a conversion's
//! own fields in [`convert`]) and turns into the library's typed request
//! ([`BakeRequest`](crate::bake::BakeRequest), [`FitOptions`](crate::fit::FitOptions),
//! [`OpenOptions`](crate::source::OpenOptions), a [`Codec`](crate::codec::Codec)); errors
//! name the field (`Error::InvalidArgument { name: "target_error", .. }`), and a host renders
//! that name in its own terms (the CLI as `--target-error`).
//!
//! ```
//! use brdftab::request::{self, BakeSettings};
//! let s: BakeSettings = request::from_json(r#"{"grid": "small", "codec": "f16"}"#)?;
//! let req = s.request(r#"{"model": "lambert", "kd": 0.5}"#)?;
//! assert_eq!(req.codec.quant.name(), "f16");
//! // An unknown field is an error that names it and the known ones.
//! let e = request::from_json::<BakeSettings>(r#"{"gird": "small"}"#).unwrap_err();
//! assert!(e.to_string().contains("gird"));
//! # Ok::<(), brdftab::Error>(())
//! ```

mod bake;
mod convert;
mod fit;
mod open;
mod save;
mod values;

pub use bake::{BakeSettings, bake};
pub use convert::{ConvertOutput, ConvertSettings, convert};
pub use fit::{FitSettings, fit};
pub use open::{OpenSettings, open};
pub use save::{SaveSettings, import_npy, save_table, save_table_with};
pub use values::{ErrorTarget, Names, Wavelengths};

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::error::{Error, Result};

/// Settings from a JSON object (`""` or `null`: the defaults). Unknown fields are errors naming
/// the field and listing the known ones; a wrong value names its field.
pub fn from_json<T: DeserializeOwned + Serialize + Default>(json: &str) -> Result<T> {
    if json.trim().is_empty() {
        return Ok(T::default());
    }
    let v: serde_json::Value = serde_json::from_str(json).map_err(|e| Error::Json {
        context: "settings".into(),
        source: e,
    })?;
    from_value(v)
}

/// Settings from a JSON value: an object of fields, or `null` for the defaults (see
/// [`from_json`]). Fields set to `null` keep their defaults.
pub fn from_value<T: DeserializeOwned + Serialize + Default>(v: serde_json::Value) -> Result<T> {
    let mut map = match v {
        serde_json::Value::Null => return Ok(T::default()),
        serde_json::Value::Object(m) => m,
        o => {
            return Err(Error::arg(
                "settings",
                format!("expected an object of fields, got {o}"),
            ));
        }
    };
    let known = field_names::<T>();
    if let Some(k) = map.keys().find(|k| !known.contains(k)) {
        return Err(Error::arg(
            k.as_str(),
            format!("unknown setting; the known ones are {}", known.join(", ")),
        ));
    }
    map.retain(|_, v| !v.is_null());
    serde_path_to_error::deserialize(serde_json::Value::Object(map)).map_err(|e| {
        let name = e.path().to_string();
        Error::arg(name, e.into_inner().to_string())
    })
}

/// The field names of a settings type: the keys of its serialized default (every field is
/// serialized, `None` as `null`).
pub fn field_names<T: Serialize + Default>() -> Vec<String> {
    match serde_json::to_value(T::default()) {
        Ok(serde_json::Value::Object(m)) => m.keys().cloned().collect(),
        _ => Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_settings_type_lists_its_fields_and_refuses_others() {
        assert!(field_names::<BakeSettings>().contains(&"target_error".to_string()));
        assert!(field_names::<ConvertSettings>().contains(&"theta_i".to_string()));
        assert!(field_names::<ConvertSettings>().contains(&"codec".to_string()));
        assert!(field_names::<FitSettings>().contains(&"max_theta_deg".to_string()));
        assert!(field_names::<OpenSettings>().contains(&"interp".to_string()));
        // A save's fields are the bake's fields of the same name.
        let bake = field_names::<BakeSettings>();
        assert!(
            field_names::<SaveSettings>()
                .iter()
                .all(|f| bake.contains(f))
        );
        assert_eq!(field_names::<SaveSettings>().len(), 7);
        let e = from_json::<FitSettings>(r#"{"strats": 3}"#).unwrap_err();
        assert!(matches!(e, Error::InvalidArgument { ref name, .. } if name == "strats"));
        let e = from_json::<BakeSettings>(r#"{"supersample": "two"}"#).unwrap_err();
        assert!(matches!(e, Error::InvalidArgument { ref name, .. } if name == "supersample"));
        assert!(from_json::<BakeSettings>("[1]").is_err());
        assert!(from_json::<BakeSettings>("{").is_err());
        assert_eq!(
            from_json::<BakeSettings>("").unwrap(),
            BakeSettings::default()
        );
        let s: BakeSettings = from_json(r#"{"grid": null, "force": true}"#).unwrap();
        assert!(s.force && s.grid.is_none());
    }
}
