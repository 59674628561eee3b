//! Keyword arguments read into the library's options, and results handed to Python (JSON values, DataFrames, dicts of arrays).

use crate::errors::*;
use api::Trajectory;
use numpy::{IntoPyArray, PyArrayMethods};
use physid::api;
use physid::api::data::ReadOptions;
use physid::api::identify::SampleRange;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::path::PathBuf;

/// A JSON value (as physid writes it, with its schema) as Python objects.
pub(crate) fn to_python<'py>(
    py: Python<'py>,
    schema: &str,
    value: &impl serde::Serialize,
) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(&api::files::versioned(schema, value)).map_err(exception)?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A value as Python objects through its JSON form (no schema tag).
pub(crate) fn plain<'py>(
    py: Python<'py>,
    value: &impl serde::Serialize,
) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(exception)?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A list of paths from a path or a sequence of paths (`str` or `os.PathLike`).
pub(crate) fn paths(what: &str, v: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<PathBuf>> {
    let Some(v) = v else { return Ok(vec![]) };
    if let Ok(one) = v.extract::<PathBuf>() {
        return Ok(vec![one]);
    }
    v.extract::<Vec<PathBuf>>()
        .map_err(|_| exception(format!("{what}: give a path or a list of paths")))
}

/// A list of names from `"a,b"` or `["a", "b"]`.
pub(crate) fn names(v: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(v) = v else { return Ok(vec![]) };
    if let Ok(s) = v.extract::<String>() {
        return Ok(s.split(',').map(|x| x.trim().to_string()).collect());
    }
    v.extract::<Vec<String>>()
}

/// A sample range from `"a:b"`, `(a, b)` or `range(a, b)` (`None`: the file's end).
pub(crate) fn sample_range(
    what: &str,
    v: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<SampleRange>> {
    let Some(v) = v else { return Ok(None) };
    if let Ok(s) = v.extract::<String>() {
        return SampleRange::parse(&s, what).map(Some).map_err(exception);
    }
    if let Ok((a, b)) = v.extract::<(Option<usize>, Option<usize>)>() {
        return Ok(Some(SampleRange { start: a, end: b }));
    }
    if v.is_instance_of::<pyo3::types::PyRange>() {
        let (a, b, step): (usize, usize, isize) = (
            v.getattr("start")?.extract()?,
            v.getattr("stop")?.extract()?,
            v.getattr("step")?.extract()?,
        );
        if step == 1 {
            return Ok(Some(SampleRange {
                start: Some(a),
                end: Some(b),
            }));
        }
    }
    Err(exception(format!(
        "{what}: give \"a:b\", (a, b) or range(a, b) of sample indices (non-negative, step 1)"
    )))
}

/// How files are read, from the keyword arguments shared by `load` and `identify`.
pub(crate) fn read_options(
    topic: Option<String>,
    stamp: &str,
    cutoff: Option<f64>,
    lock: Option<&Bound<'_, PyAny>>,
    only: Option<&Bound<'_, PyAny>>,
) -> PyResult<ReadOptions> {
    Ok(ReadOptions {
        topic,
        stamp: stamp
            .parse()
            .map_err(|e| exception(format!("--stamp: {e}")))?,
        cutoff,
        lock: names(lock)?,
        only: names(only)?,
        memory: Default::default(),
    })
}

/// The DataFrame library a table is returned in: `"pandas"` (the default) or `"polars"`.
pub(crate) fn frames<'py>(py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyModule>> {
    let extra = match backend {
        "pandas" => "the package's extra 'tables'",
        "polars" => "the package's extra 'polars'",
        other => {
            return Err(exception(format!(
                "backend: '{other}' is not one of pandas, polars"
            )))
        }
    };
    py.import(backend).map_err(|_| {
        pyo3::exceptions::PyImportError::new_err(format!(
            "tables as {backend} DataFrames: pip install {backend} ({extra})"
        ))
    })
}

/// A pandas DataFrame of `data` (a dict of columns or a list of records).
pub(crate) fn frame<'py>(
    py: Python<'py>,
    data: Bound<'py, PyAny>,
    backend: &str,
) -> PyResult<Bound<'py, PyAny>> {
    frames(py, backend)?.getattr("DataFrame")?.call1((data,))
}

/// A DataFrame of `backend` from `rows` (a list of dicts), its columns `columns` in that
/// order (so a table without rows still has them).
pub(crate) fn records<'py>(
    py: Python<'py>,
    rows: Bound<'py, PyAny>,
    columns: &[&str],
    backend: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let table = PyDict::new(py);
    for c in columns {
        let column = pyo3::types::PyList::empty(py);
        for row in rows.try_iter()? {
            column.append(row?.get_item(c)?)?;
        }
        table.set_item(c, column)?;
    }
    frame(py, table.into_any(), backend)
}

/// A trajectory's signals as a dict of numpy arrays: `t` (s), and `q`, `qd`, `qdd`, `tau` as
/// `(samples, n)` (`qdd` absent when unknown).
pub(crate) fn trajectory_dict<'py>(
    py: Python<'py>,
    tr: &Trajectory,
) -> PyResult<Bound<'py, PyDict>> {
    let (s, n) = (tr.t.len(), tr.joint_names.len());
    let d = PyDict::new(py);
    d.set_item("t", tr.t.clone().into_pyarray(py))?;
    for (key, v) in [("q", &tr.q), ("qd", &tr.qd), ("tau", &tr.tau)] {
        d.set_item(key, v.clone().into_pyarray(py).reshape([s, n])?)?;
    }
    if let Some(qdd) = &tr.qdd {
        d.set_item("qdd", qdd.clone().into_pyarray(py).reshape([s, n])?)?;
    }
    Ok(d)
}

/// A table written by the library as CSV text (or why it could not be made), read back as a
/// DataFrame of `backend`: the columns of the CLI's CSV.
pub(crate) fn table_of<'py>(
    py: Python<'py>,
    csv: Result<String, String>,
    backend: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let text = csv.map_err(exception)?;
    let module = frames(py, backend)?;
    let buffer = py
        .import("io")?
        .getattr("BytesIO")?
        .call1((PyBytes::new(py, text.as_bytes()),))?;
    module.getattr("read_csv")?.call1((buffer,))
}
