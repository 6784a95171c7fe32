//! The Fresnel term as a model spec names it ([`FresnelSpec`]) and its JSON forms.

use serde::{Deserialize, Serialize};

use crate::spectrum::Value;

/// The Fresnel term of a model spec, in JSON:
/// `"none"` (F = 1), `{"conductor": "Au"}` (named metal), `{"n": X, "k": X}` (complex index),
/// `{"eta": X}` (dielectric), `{"schlick": X}` (Schlick with F0 = X).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum FresnelSpec {
    /// F = 1.
    #[default]
    None,
    /// A named metal from [`crate::metals`].
    Conductor(String),
    /// A complex index n + k j.
    Complex {
        /// Real part n.
        n: Value,
        /// Extinction coefficient k.
        k: Value,
    },
    /// A dielectric of relative index eta.
    Dielectric(Value),
    /// Schlick's approximation with normal-incidence reflectance F0.
    Schlick(Value),
}

impl Serialize for FresnelSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        match self {
            FresnelSpec::None => s.serialize_str("none"),
            FresnelSpec::Conductor(name) => {
                let mut m = s.serialize_map(Some(1))?;
                m.serialize_entry("conductor", name)?;
                m.end()
            }
            FresnelSpec::Complex { n, k } => {
                let mut m = s.serialize_map(Some(2))?;
                m.serialize_entry("n", n)?;
                m.serialize_entry("k", k)?;
                m.end()
            }
            FresnelSpec::Dielectric(eta) => {
                let mut m = s.serialize_map(Some(1))?;
                m.serialize_entry("eta", eta)?;
                m.end()
            }
            FresnelSpec::Schlick(f0) => {
                let mut m = s.serialize_map(Some(1))?;
                m.serialize_entry("schlick", f0)?;
                m.end()
            }
        }
    }
}

impl<'de> Deserialize<'de> for FresnelSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Obj {
            conductor: Option<String>,
            n: Option<Value>,
            k: Option<Value>,
            eta: Option<Value>,
            schlick: Option<Value>,
        }
        let v = serde_json::Value::deserialize(d)?;
        match v {
            serde_json::Value::String(s) if s == "none" => Ok(FresnelSpec::None),
            serde_json::Value::Object(_) => {
                let o: Obj = serde_json::from_value(v).map_err(D::Error::custom)?;
                match o {
                    Obj {
                        conductor: Some(c),
                        n: None,
                        k: None,
                        eta: None,
                        schlick: None,
                    } => Ok(FresnelSpec::Conductor(c)),
                    Obj {
                        conductor: None,
                        n: Some(n),
                        k,
                        eta: None,
                        schlick: None,
                    } => Ok(FresnelSpec::Complex {
                        n,
                        k: k.unwrap_or(Value::Grey(0.0)),
                    }),
                    Obj {
                        conductor: None,
                        n: None,
                        k: None,
                        eta: Some(eta),
                        schlick: None,
                    } => Ok(FresnelSpec::Dielectric(eta)),
                    Obj {
                        conductor: None,
                        n: None,
                        k: None,
                        eta: None,
                        schlick: Some(f0),
                    } => Ok(FresnelSpec::Schlick(f0)),
                    _ => Err(D::Error::custom(
                        "expected exactly one of {\"conductor\": NAME}, {\"n\": X, \"k\": X}, {\"eta\": X}, {\"schlick\": X}",
                    )),
                }
            }
            other => Err(D::Error::custom(format!(
                "expected \"none\", {{\"conductor\": NAME}}, {{\"n\": X, \"k\": X}}, {{\"eta\": X}} or {{\"schlick\": X}}, got {other}"
            ))),
        }
    }
}
