//! A scene given as a Python dictionary in the scene file's layout (`docs/scene-format.md`):
//! turned into TOML text that the scene-file parser reads, and that parser's syntax errors
//! (a line of that text) turned back into the dictionary's key path (`objects[1].mesh`).

use crate::errors;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};

/// The TOML text of `d`, a scene dictionary; an error names the key path of a value TOML
/// cannot hold (`None`, an object of another type).
pub fn to_toml(d: &Bound<'_, PyDict>) -> PyResult<String> {
    let table = table(d, "")?;
    toml::to_string(&table).map_err(|e| errors::message(format!("scene dict: {e}")))
}

fn table(d: &Bound<'_, PyDict>, at: &str) -> PyResult<toml::Table> {
    let mut t = toml::Table::new();
    for (k, v) in d.iter() {
        let key: String = k.extract().map_err(|_| {
            errors::message(format!("scene dict: {}: keys must be strings", shown(at)))
        })?;
        let path = if at.is_empty() {
            key.clone()
        } else {
            format!("{at}.{key}")
        };
        t.insert(key, value(&v, &path)?);
    }
    Ok(t)
}

/// The TOML value of `v`, at key path `at` for messages.
pub fn value(v: &Bound<'_, PyAny>, at: &str) -> PyResult<toml::Value> {
    // bool before int: Python's bool is an int.
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return Ok(toml::Value::Integer(v.extract()?));
    }
    if v.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(v.extract()?));
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        return Ok(toml::Value::Table(table(d, at)?));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let items = v
            .try_iter()?
            .enumerate()
            .map(|(i, item)| value(&item?, &format!("{at}[{i}]")))
            .collect::<PyResult<Vec<_>>>()?;
        return Ok(toml::Value::Array(items));
    }
    // NumPy scalars and arrays, and os.PathLike paths.
    if let Ok(path) = v.extract::<std::path::PathBuf>() {
        return Ok(toml::Value::String(path.display().to_string()));
    }
    if v.hasattr("tolist")? {
        return value(&v.call_method0("tolist")?, at);
    }
    if v.hasattr("__index__")? {
        return Ok(toml::Value::Integer(v.extract()?));
    }
    if v.hasattr("__float__")? {
        return Ok(toml::Value::Float(v.extract()?));
    }
    let kind = v.get_type().name()?;
    Err(errors::message(format!(
        "scene dict: {}: a {kind} has no place in a scene (give a number, string, bool, list or dict)",
        shown(at)
    )))
}

fn shown(at: &str) -> &str {
    if at.is_empty() { "(top level)" } else { at }
}

/// The key path in `text` (as [`to_toml`] writes it) of line `line` (from 1): the table
/// header above it, with arrays of tables indexed, and the line's key.
pub fn key_at(text: &str, line: usize) -> String {
    let mut header = String::new();
    let mut counts: std::collections::HashMap<String, usize> = Default::default();
    let mut key = None;
    for (i, l) in text.lines().enumerate().take(line) {
        let l = l.trim();
        if let Some(name) = l.strip_prefix("[[").and_then(|n| n.strip_suffix("]]")) {
            let n = counts.entry(name.to_string()).or_insert(0);
            header = format!("{name}[{n}]");
            *n += 1;
            key = None;
        } else if let Some(name) = l.strip_prefix('[').and_then(|n| n.strip_suffix(']')) {
            header = indexed(name, &counts);
            key = None;
        } else if i + 1 == line {
            key = l.split_once(" = ").map(|(k, _)| k.trim().to_string());
        }
    }
    match (header.is_empty(), key) {
        (true, Some(k)) => k,
        (false, Some(k)) => format!("{header}.{k}"),
        (_, None) => header,
    }
}

/// A dotted table name whose prefixes that are arrays of tables get the index of their
/// current element (`objects.material` under the second `[[objects]]`: `objects[1].material`).
fn indexed(name: &str, counts: &std::collections::HashMap<String, usize>) -> String {
    let parts: Vec<&str> = name.split('.').collect();
    let mut out = String::new();
    for i in 0..parts.len() {
        if i > 0 {
            out.push('.');
        }
        out.push_str(parts[i]);
        if let Some(n) = counts.get(&parts[..=i].join(".")) {
            out.push_str(&format!("[{}]", n - 1));
        }
    }
    out
}
