//! Library errors raised as Python exceptions (`physid.Error` and its subclasses, which are
//! also the built-in exceptions of their kind: python/physid/errors.py), library warnings as
//! `physid.PhysidWarning`. Messages name options as the caller spells them: keywords here,
//! where the library's own messages name the CLI's flags.

use physid::api::data::Notice;
use physid::api::{ApiError, IdentError, IoError, OptionError};
use pyo3::prelude::*;
use std::collections::HashSet;
use std::error::Error as StdError;
use std::path::PathBuf;
use std::sync::Mutex;

pyo3::import_exception!(physid.errors, InputError);
pyo3::import_exception!(physid.errors, MissingFileError);
pyo3::import_exception!(physid.errors, SolverError);

/// Any error of the library (or a message) as the Python exception of its kind: a missing file
/// as `physid.MissingFileError` (a `FileNotFoundError` whose `filename` is the path), the solver
/// stopping as `physid.SolverError`, anything else as `physid.InputError`; the message and its
/// causes on one line, options named as keywords.
pub(crate) fn exception(e: impl Into<Box<dyn StdError + Send + Sync>>) -> PyErr {
    let e: Box<dyn StdError + Send + Sync> = e.into();
    let e: &(dyn StdError + 'static) = e.as_ref();
    let message = in_keywords(&with_causes(e));
    if let Some(path) = missing_file(e, &message) {
        // As Python's own: "[Errno 2] No such file or directory: 'PATH'", `filename` the path.
        let errno = 2; // ENOENT
        let reason = "No such file or directory";
        return MissingFileError::new_err((errno, reason, path.to_string_lossy().into_owned()));
    }
    if solver_failed(e) {
        return SolverError::new_err(message);
    }
    InputError::new_err(message)
}

/// A library entry point's error as [`exception`] does, an option out of its range named as
/// its keyword.
pub(crate) fn api_error<E: OptionError + StdError + Send + Sync + 'static>(e: E) -> PyErr {
    match e.keyword_message() {
        Some(message) => InputError::new_err(message),
        None => exception(e),
    }
}

/// The message and its causes, as the CLI's "Caused by" lines, on one line (a cause the
/// message already quotes, as an I/O error's "path: reason", once).
fn with_causes(e: &(dyn StdError + 'static)) -> String {
    let mut message = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let text = c.to_string();
        if !message.contains(&text) {
            message = format!("{message}: {text}");
        }
        cause = c.source();
    }
    message
}

/// The path of a file that was not found, anywhere in `e`'s chain of causes: named by the
/// error that carries it, or else as `message` quotes it before the operating system's reason
/// (`…: PATH: No such file or directory (os error 2)`).
fn missing_file(e: &(dyn StdError + 'static), message: &str) -> Option<PathBuf> {
    let not_found = |s: &std::io::Error| s.kind() == std::io::ErrorKind::NotFound;
    let mut cause = Some(e);
    while let Some(c) = cause {
        let typed = match (c.downcast_ref::<ApiError>(), c.downcast_ref::<IoError>()) {
            (Some(ApiError::Io(IoError::Fs { path, source })), _)
            | (Some(ApiError::Fs { path, source, .. }), _)
            | (_, Some(IoError::Fs { path, source })) => Some((path, source)),
            _ => None,
        };
        if let Some((path, source)) = typed {
            return not_found(source).then(|| path.clone());
        }
        if let Some(os) = c.downcast_ref::<std::io::Error>().filter(|s| not_found(s)) {
            let quoted = message.split(&format!(": {os}")).next()?;
            let path = quoted.rsplit(": ").next()?;
            return Some(PathBuf::from(path));
        }
        cause = c.source();
    }
    None
}

/// Whether the cone solver stopped without an answer, anywhere in `e`'s chain of causes.
fn solver_failed(e: &(dyn StdError + 'static)) -> bool {
    let mut cause = Some(e);
    while let Some(c) = cause {
        let stopped = matches!(
            c.downcast_ref::<ApiError>(),
            Some(ApiError::Ident(IdentError::SolverFailed { .. }))
        ) || matches!(
            c.downcast_ref::<IdentError>(),
            Some(IdentError::SolverFailed { .. })
        );
        if stopped {
            return true;
        }
        cause = c.source();
    }
    false
}

/// `message` with the CLI's flags (`--baseline-data`) named as this package's keywords
/// (`baseline_data`; `--no-description-information` as `description_information=False`).
pub(crate) fn in_keywords(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(at) = rest.find("--") {
        let (before, flag) = rest.split_at(at);
        out.push_str(before);
        let name_len = flag[2..]
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
            .unwrap_or(flag.len() - 2);
        let name = flag[2..2 + name_len].trim_end_matches('-');
        let starts_a_word = before.chars().last().is_none_or(|c| !c.is_alphanumeric());
        if name.is_empty() || !starts_a_word || !name.starts_with(|c: char| c.is_ascii_lowercase())
        {
            out.push_str("--");
            rest = &flag[2..];
            continue;
        }
        out.push_str(&keyword(name));
        rest = &flag[2 + name.len()..];
    }
    out.push_str(rest);
    out
}

/// The keyword of the CLI's flag `--name` (scripts/python_keywords.py keeps its own exceptions,
/// NEGATED and FLAG, for the generated keyword documentation).
fn keyword(name: &str) -> String {
    match name {
        "no-description-information" => "description_information=False".into(),
        "no-rotors" => "no_rotors=True".into(),
        "payload-any-body" => "payload_any_body=True".into(),
        other => other.replace('-', "_"),
    }
}

/// Warnings already issued by this process (their text), for [`warn_once`].
static WARNED: Mutex<Option<HashSet<String>>> = Mutex::new(None);

/// Raises each warning among `notices` as a Python `physid.PhysidWarning` (notes are kept in
/// the result only).
pub(crate) fn warn(py: Python<'_>, notices: &[Notice]) -> PyResult<()> {
    for n in notices.iter().filter(|n| n.warning) {
        issue(py, &n.text)?;
    }
    Ok(())
}

/// [`warn`], each text once per process: a robot description's warnings (they name its file)
/// are issued the first time it is loaded, not on every load of the same file.
pub(crate) fn warn_once(py: Python<'_>, notices: &[Notice]) -> PyResult<()> {
    for n in notices.iter().filter(|n| n.warning) {
        let first = WARNED
            .lock()
            .map(|mut w| w.get_or_insert_with(HashSet::new).insert(n.text.clone()))
            .unwrap_or(true);
        if first {
            issue(py, &n.text)?;
        }
    }
    Ok(())
}

/// Notes and warnings as a result lists them (`warning: …`, `note: …`), options as keywords.
pub(crate) fn notice_texts(notices: &[Notice]) -> Vec<String> {
    notices
        .iter()
        .map(|n| in_keywords(&n.to_string()))
        .collect()
}

/// Issues `text` as a `physid.PhysidWarning`, options as keywords.
fn issue(py: Python<'_>, text: &str) -> PyResult<()> {
    let category = py.import("physid.errors")?.getattr("PhysidWarning")?;
    let text = std::ffi::CString::new(in_keywords(text))?;
    PyErr::warn(py, &category, &text, 1)
}
