//! The one exception type, `meshtrace.MeshtraceError` (a `ValueError`), carrying the
//! command line's one-line message.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

pyo3::create_exception!(
    meshtrace,
    MeshtraceError,
    PyValueError,
    "An input or a request meshtrace cannot render: one line naming the file and the line, \
     field or JSON path at fault (the command line's message)."
);

/// `e` as a [`MeshtraceError`] whose message is the error and its causes on one line, as
/// the command line prints them after `error: `.
pub fn error(e: &(dyn std::error::Error + 'static)) -> PyErr {
    MeshtraceError::new_err(one_line(e))
}

/// A [`MeshtraceError`] with `message`.
pub fn message(message: impl Into<String>) -> PyErr {
    MeshtraceError::new_err(message.into())
}

/// The error and each cause that it does not already end with, joined by `: ` (the
/// command line's `one_line`).
fn one_line(e: &(dyn std::error::Error + 'static)) -> String {
    let mut line = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let text = c.to_string();
        if !line.ends_with(&text) {
            line.push_str(": ");
            line.push_str(&text);
        }
        cause = c.source();
    }
    line
}

/// Passes a scene's warnings to Python's `warnings` (a `UserWarning` each), as the command
/// line prints them after `warning: `.
pub fn warn_all(py: Python<'_>, warnings: &[String]) -> PyResult<()> {
    let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
    for w in warnings {
        PyErr::warn(py, &category, &std::ffi::CString::new(w.as_str())?, 1)?;
    }
    Ok(())
}
