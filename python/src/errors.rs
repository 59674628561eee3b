//! Library errors raised as Python exceptions, library warnings as `physid.PhysidWarning`.

use physid::api::data::Notice;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// A library error as a Python `ValueError` with its message.
pub(crate) fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A library entry point's error as a Python `ValueError` with the CLI's message (an invalid
/// option named as its flag).
pub(crate) fn api_error<E: physid::options::OptionError + std::error::Error>(e: E) -> PyErr {
    if let Some(message) = e.flag_message() {
        return PyValueError::new_err(message);
    }
    // The message and its causes, as the CLI's "Caused by" lines, on one line (a cause the
    // message already quotes, as an I/O error's "path: reason", once).
    let mut message = e.to_string();
    let mut cause = std::error::Error::source(&e);
    while let Some(c) = cause {
        let text = c.to_string();
        if !message.ends_with(&text) {
            message = format!("{message}: {text}");
        }
        cause = c.source();
    }
    PyValueError::new_err(message)
}

/// Raises each warning among `notices` as a Python `physid.PhysidWarning` (notes are kept in
/// the result only).
pub(crate) fn warn(py: Python<'_>, notices: &[Notice]) -> PyResult<()> {
    let category = py.import("physid")?.getattr("PhysidWarning")?;
    for n in notices.iter().filter(|n| n.warning) {
        PyErr::warn(py, &category, &std::ffi::CString::new(n.text.clone())?, 1)?;
    }
    Ok(())
}
