//! Python values → TOML: a scenario or machine given as a dict becomes the TOML text the
//! file readers parse, so a dict is checked exactly as a file is (same keys, same errors).

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// `value` (a dict of the file's tables) as TOML text; `what` names it in errors.
pub fn dict_to_toml(value: &Bound<'_, PyAny>, what: &str) -> PyResult<String> {
    let dict = value
        .cast::<PyDict>()
        .map_err(|_| PyTypeError::new_err(format!("{what} must be a dict or a path")))?;
    let table = to_table(dict, "")?;
    toml::to_string(&table).map_err(|e| PyTypeError::new_err(format!("{what}: {e}")))
}

fn to_table(dict: &Bound<'_, PyDict>, prefix: &str) -> PyResult<toml::Table> {
    let mut table = toml::Table::new();
    for (k, v) in dict.iter() {
        let key: String = k.extract().map_err(|_| {
            PyTypeError::new_err(format!(
                "{}: keys must be strings, got {}",
                if prefix.is_empty() {
                    "the top level"
                } else {
                    prefix
                },
                k.repr().map(|r| r.to_string()).unwrap_or_default()
            ))
        })?;
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        table.insert(key, to_value(&v, &path)?);
    }
    Ok(table)
}

/// One value; `path` is its dotted key, for the error.
fn to_value(v: &Bound<'_, PyAny>, path: &str) -> PyResult<toml::Value> {
    // bool before int: Python's True is an int.
    if let Ok(b) = v.cast::<PyBool>() {
        return Ok(toml::Value::Boolean(b.is_true()));
    }
    if v.is_instance_of::<PyInt>() {
        return match v.extract::<i64>() {
            Ok(i) => Ok(toml::Value::Integer(i)),
            Err(_) => Err(PyTypeError::new_err(format!(
                "{path}: the integer does not fit in 64 bits"
            ))),
        };
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract::<f64>()?));
    }
    if let Ok(s) = v.cast::<PyString>() {
        return Ok(toml::Value::String(s.to_str()?.to_string()));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return Ok(toml::Value::Table(to_table(d, path)?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        return v
            .try_iter()?
            .enumerate()
            .map(|(i, item)| to_value(&item?, &format!("{path}[{i}]")))
            .collect::<PyResult<Vec<_>>>()
            .map(toml::Value::Array);
    }
    // A path object (pathlib.Path) is a path string; numpy scalars are numbers.
    if v.hasattr("__fspath__")? {
        let p = v.call_method0("__fspath__")?;
        return Ok(toml::Value::String(p.extract::<String>()?));
    }
    if v.hasattr("__index__")? {
        return to_value(&v.call_method0("__index__")?, path);
    }
    if v.hasattr("__float__")? {
        return Ok(toml::Value::Float(v.call_method0("__float__")?.extract()?));
    }
    Err(PyTypeError::new_err(format!(
        "{path}: expected a number, string, bool, list or dict, got {}",
        v.get_type().name()?
    )))
}
