//! Paths into a spec's JSON form (`terms[1].m`): parsing them and finding the value they name.

use serde_json::Value as Json;

use crate::error::{Error, Result};

/// One segment of a parameter path: a field name with an optional array index (`terms[1]`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct Segment {
    key: String,
    index: Option<usize>,
}

/// Parses `terms[1].m` into segments.
pub(super) fn parse_path(path: &str) -> Result<Vec<Segment>> {
    let bad = |msg: &str| Error::arg("params", format!("`{path}`: {msg}"));
    if path.trim().is_empty() {
        return Err(bad("empty parameter path"));
    }
    path.split('.')
        .map(|seg| {
            let (key, index) = match seg.split_once('[') {
                None => (seg, None),
                Some((k, rest)) => {
                    let i = rest
                        .strip_suffix(']')
                        .and_then(|i| i.parse::<usize>().ok())
                        .ok_or_else(|| bad("expected `name[index]`"))?;
                    (k, Some(i))
                }
            };
            if key.is_empty() || !key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                return Err(bad("expected field names like `kd` or `terms[1].m`"));
            }
            Ok(Segment {
                key: key.to_string(),
                index,
            })
        })
        .collect()
}

/// The JSON value at `path` and the name of the model that owns its last field.
pub(super) fn lookup<'a>(root: &'a mut Json, path: &str) -> Result<(&'a mut Json, String, String)> {
    let segs = parse_path(path)?;
    let missing = |what: String| Error::arg("params", format!("`{path}`: {what}"));
    let mut cur = root;
    let mut model = String::new();
    let mut last = String::new();
    for s in &segs {
        let obj = cur
            .as_object_mut()
            .ok_or_else(|| missing(format!("`{}` is not inside an object", s.key)))?;
        if let Some(Json::String(m)) = obj.get("model") {
            model = m.clone();
        }
        cur = obj
            .get_mut(&s.key)
            .ok_or_else(|| missing(format!("no field `{}` in model `{model}`", s.key)))?;
        if let Some(i) = s.index {
            let arr = cur
                .as_array_mut()
                .ok_or_else(|| missing(format!("`{}` is not a list", s.key)))?;
            let n = arr.len();
            cur = arr
                .get_mut(i)
                .ok_or_else(|| missing(format!("index {i} out of range (`{}` has {n})", s.key)))?;
        }
        last = s.key.clone();
    }
    Ok((cur, model, last))
}
