//! The JSON form of a spec: internally tagged (`{"model": "lambert", ...}`), with errors that
//! name the field path.

use serde::{Deserialize, Serialize};

use super::ModelSpec;

// The JSON form is internally tagged (`{"model": "lambert", "kd": ..}`), but serde's internally
// tagged enums buffer their content and lose the field path of errors. So the derive on
// `ModelSpec` (in mod.rs) makes the externally tagged form (`{"lambert": {"kd": ..}}`) available
// as inherent functions (`remote = "Self"`), and these impls convert at the top level. Errors
// carry the field path as "at `terms[1].ks`: message", merged across nested sums.
#[cfg(test)]
thread_local! {
    /// How many times this thread serialized a spec (the work-bound test of nested sums).
    pub(super) static SERIALIZED: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

impl Serialize for ModelSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::Error as _;
        #[cfg(test)]
        SERIALIZED.with(|n| n.set(n.get() + 1));
        let ext =
            ModelSpec::serialize(self, serde_json::value::Serializer).map_err(S::Error::custom)?;
        let mut out = serde_json::Map::new();
        out.insert(
            "model".into(),
            serde_json::Value::String(self.name().into()),
        );
        if let serde_json::Value::Object(o) = ext
            && let Some((_, serde_json::Value::Object(fields))) = o.into_iter().next()
        {
            out.extend(fields);
        }
        serde_json::Value::Object(out).serialize(s)
    }
}

impl<'de> Deserialize<'de> for ModelSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let v = serde_json::Value::deserialize(d)?;
        let serde_json::Value::Object(mut o) = v else {
            return Err(D::Error::custom("at `model`: a spec must be a JSON object"));
        };
        let name = match o.remove("model") {
            Some(serde_json::Value::String(s)) => s,
            Some(other) => {
                return Err(D::Error::custom(format!(
                    "at `model`: expected a model name, got {other}"
                )));
            }
            None => return Err(D::Error::custom("at `model`: missing field `model`")),
        };
        let mut ext = serde_json::Map::new();
        ext.insert(name, serde_json::Value::Object(o));
        let mut track = serde_path_to_error::Track::new();
        let de = serde_path_to_error::Deserializer::new(serde_json::Value::Object(ext), &mut track);
        ModelSpec::deserialize(de).map_err(|e: serde_json::Error| {
            // The tracked path starts with the variant name (`lambert.kd`): drop it.
            let path = track.path().to_string();
            let path = path.split_once('.').map(|(_, p)| p).unwrap_or("");
            let msg = e.to_string();
            // A nested spec (a term of a sum) reports "at `inner`: msg": join the paths.
            let (inner, msg) = match msg.strip_prefix("at `").and_then(|r| r.split_once("`: ")) {
                Some((p, m)) => (p.to_string(), m.to_string()),
                None => (String::new(), msg),
            };
            let full = match (path.is_empty(), inner.is_empty()) {
                (true, true) => "model".to_string(),
                (false, true) => path.to_string(),
                (true, false) => inner,
                (false, false) => format!("{path}.{inner}"),
            };
            D::Error::custom(format!("at `{full}`: {msg}"))
        })
    }
}
