//! Python values in and out: arguments (SOURCE and OUTPUT strings or paths, `wavelengths=`,
//! keyword arguments as the request layer's settings) to the library's values, and the
//! library's serde results back to Python objects.
//!
//! Why a module: every function and method takes or returns some of these, and each conversion
//! decides which bad value is a `TypeError` and which a `ValueError`; one place keeps them alike.

use brdftab::Channels;
use brdftab::source;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::errors::{Error, lib_err};

/// A SOURCE, OUTPUT or other path argument as the library takes one (a file name need not be
/// UTF-8: SOURCEs since session 41, every other path since session 42): a `str` (a spec, a
/// path, `DB#NAME`), `bytes`, or an `os.PathLike` of either, as `os.fspath` gives them. A `str`
/// is encoded as `os.fsencode` does, so a file name of undecodable bytes (which Python holds
/// with surrogate escapes) reaches the library as those bytes; anything else is a `TypeError`.
/// (A path that was not UTF-8 was a `ValueError`, bytes a `TypeError`.)
pub(crate) fn path_arg(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<std::ffi::OsString> {
    use pyo3::types::{PyBytes, PyString};
    let os = obj.py().import("os")?;
    let path = if obj.is_instance_of::<PyString>() || obj.is_instance_of::<PyBytes>() {
        obj.clone()
    } else if obj.hasattr("__fspath__")? {
        os.call_method1("fspath", (obj,))?
    } else {
        return Err(PyTypeError::new_err(format!(
            "{what}: expected a str, bytes or an os.PathLike, got {}",
            obj.get_type().name()?
        )));
    };
    let bytes = match path.is_instance_of::<PyString>() {
        true => os.call_method1("fsencode", (path,))?,
        false => path,
    };
    let bytes = bytes.downcast::<PyBytes>()?.as_bytes();
    #[cfg(unix)]
    return Ok(<std::ffi::OsStr as std::os::unix::ffi::OsStrExt>::from_bytes(bytes).to_owned());
    #[cfg(not(unix))]
    String::from_utf8(bytes.to_vec())
        .map(Into::into)
        .map_err(|_| PyValueError::new_err(format!("{what}: a path that is not UTF-8")))
}

/// `wavelengths=`: None, a comma-separated string, or a sequence of numbers (nm).
pub(crate) fn channels_of(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Channels>> {
    let Some(o) = obj else { return Ok(None) };
    if o.is_none() {
        return Ok(None);
    }
    if let Ok(s) = o.extract::<String>() {
        return source::parse_wavelengths(&s).map(Some).map_err(lib_err);
    }
    let nm: Vec<f64> = o.extract().map_err(|_| {
        PyTypeError::new_err("wavelengths: expected a sequence of numbers (nm) or a string")
    })?;
    Channels::wavelengths(nm).map(Some).map_err(lib_err)
}

pub(crate) fn wavelengths_of(c: &Option<Channels>) -> Option<Vec<f64>> {
    match c {
        Some(Channels::Wavelengths(w)) => Some(w.clone()),
        _ => None,
    }
}

/// Keyword arguments as settings of the request layer ([`brdftab::request`]): the same field
/// names and the same validation as the CLI's flags and the C ABI's JSON. An unknown keyword is
/// a `TypeError`, as Python's own; a value of the wrong type a `TypeError` naming the field,
/// any other bad value a `ValueError` naming it.
pub(crate) fn settings_of<T>(options: Option<&Bound<'_, PyDict>>) -> PyResult<T>
where
    T: serde::de::DeserializeOwned + serde::Serialize + Default,
{
    let Some(opts) = options else {
        return Ok(T::default());
    };
    let known = brdftab::request::field_names::<T>();
    let mut map = serde_json::Map::new();
    for (k, v) in opts.iter() {
        let key: String = k.extract()?;
        if !known.contains(&key) {
            return Err(PyTypeError::new_err(format!(
                "unexpected keyword argument '{key}'"
            )));
        }
        map.insert(key.clone(), json_of(&key, &v)?);
    }
    brdftab::request::from_value(serde_json::Value::Object(map)).map_err(|e| match e {
        brdftab::Error::InvalidArgument { ref msg, .. } if msg.starts_with("invalid type") => {
            PyTypeError::new_err(e.to_string())
        }
        e => lib_err(e),
    })
}

/// A Python value as JSON for the request layer: None, bools, ints, floats, strings, and lists,
/// tuples, dicts and numpy arrays or scalars of those (through `tolist`).
fn json_of(key: &str, v: &Bound<'_, PyAny>) -> PyResult<serde_json::Value> {
    use pyo3::types::{PyBool, PyFloat, PyInt, PyList, PyString};
    use serde_json::Value;
    if v.is_none() {
        return Ok(Value::Null);
    }
    if v.is_instance_of::<PyBool>() {
        return Ok(Value::Bool(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return match v.extract::<i64>() {
            Ok(i) => Ok(Value::from(i)),
            Err(_) => Ok(Value::from(v.extract::<u64>().map_err(|_| {
                PyValueError::new_err(format!("{key}: integer out of range"))
            })?)),
        };
    }
    if v.is_instance_of::<PyFloat>() {
        let x: f64 = v.extract()?;
        return serde_json::Number::from_f64(x)
            .map(Value::Number)
            .ok_or_else(|| PyValueError::new_err(format!("{key}: {x}: expected a finite number")));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut m = serde_json::Map::new();
        for (k, x) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| PyTypeError::new_err(format!("{key}: keys must be strings")))?;
            let inner = json_of(&format!("{key}.{k}"), &x)?;
            m.insert(k, inner);
        }
        return Ok(Value::Object(m));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        return v
            .try_iter()?
            .enumerate()
            .map(|(i, x)| json_of(&format!("{key}[{i}]"), &x?))
            .collect::<PyResult<Vec<_>>>()
            .map(Value::Array);
    }
    if v.hasattr("tolist")? {
        let t = v.call_method0("tolist")?;
        if !t.is(v) {
            return json_of(key, &t);
        }
    }
    Err(PyTypeError::new_err(format!(
        "{key}: unsupported type {}",
        v.get_type().name()?
    )))
}

/// Gives back in `d[key]` the exact name of a path the library's JSON shows lossily (a file
/// name that is not UTF-8 has U+FFFD there): the first of `candidates` whose lossy form is the
/// value, as the `str` `os.fsdecode` gives (surrogate escapes), so that a path handed back in a
/// report opens. A value no candidate shows stays as it is.
pub(crate) fn exact_path(
    d: &Bound<'_, PyAny>,
    key: &str,
    candidates: &[&std::ffi::OsStr],
) -> PyResult<()> {
    let Ok(shown) = d.get_item(key).and_then(|v| v.extract::<String>()) else {
        return Ok(());
    };
    if let Some(c) = candidates.iter().find(|c| c.to_string_lossy() == shown) {
        d.set_item(key, c)?;
    }
    Ok(())
}

/// The file part of a path that may be `DB#NAME` (split by the library's output rule), or the
/// path itself where that rule refuses it.
pub(crate) fn file_part(path: &std::ffi::OsStr) -> &std::ffi::OsStr {
    brdftab::store::name::parse_output_os("output", path).map_or(path, |(p, _)| p.as_os_str())
}

/// A serde_json value as a Python object (through `json.loads`: dicts, lists, floats, ...).
pub(crate) fn to_py(py: Python<'_>, v: &serde_json::Value) -> PyResult<Py<PyAny>> {
    let s = serde_json::to_string(v).map_err(|e| Error::new_err(e.to_string()))?;
    Ok(py.import("json")?.call_method1("loads", (s,))?.unbind())
}

pub(crate) fn ser<T: serde::Serialize>(py: Python<'_>, x: &T) -> PyResult<Py<PyAny>> {
    let v = serde_json::to_value(x).map_err(|e| Error::new_err(e.to_string()))?;
    to_py(py, &v)
}
