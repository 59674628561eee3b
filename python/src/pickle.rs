//! Pickling and copying: every model and result reduces to its class name, physid's version
//! and its state in a binary form (MessagePack: self-describing, non-finite floats kept), and
//! is restored from them by `_restore`. So results go through `multiprocessing`, `joblib` and
//! caches, and `copy.deepcopy` gives an equal, independent object.

use crate::compare::Comparison;
use crate::diagnose::Diagnosis;
use crate::errors::*;
use crate::excite::Excitation;
use crate::experiment::Experiment;
use crate::floating::{FloatingIdentification, FloatingRobot};
use crate::identify::Identification;
use crate::robot::Robot;
use crate::simulate::Simulation;
use crate::sweep::Sweep;
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use serde::de::DeserializeOwned;

/// What `__reduce__` returns: `_restore` and its arguments (class, version, state).
pub(crate) type Reduced<'py> = (
    Bound<'py, PyAny>,
    (&'static str, &'static str, Bound<'py, PyBytes>),
);

/// `value` (of the class named `class`) reduced for pickle.
pub(crate) fn reduce<'py>(
    py: Python<'py>,
    class: &'static str,
    value: &impl serde::Serialize,
) -> PyResult<Reduced<'py>> {
    let state = rmp_serde::to_vec_named(value)
        .map_err(|e| exception(format!("pickling a physid.{class}: {e}")))?;
    let restore = py.import("physid._physid")?.getattr("_restore")?;
    Ok((restore, (class, VERSION, PyBytes::new(py, &state))))
}

/// physid's version, carried by every pickled state.
const VERSION: &str = env!("CARGO_PKG_VERSION");

/// A state of `class` read back.
fn state<T: DeserializeOwned>(class: &str, bytes: &[u8]) -> PyResult<T> {
    rmp_serde::from_slice(bytes).map_err(|e| {
        exception(format!(
            "unpickling a physid.{class}: its state does not read ({e})"
        ))
    })
}

/// Restores a pickled physid object: `class` its class, `version` the physid that pickled it
/// (only the same version reads it back), `bytes` its state.
#[pyfunction]
pub(crate) fn _restore(
    py: Python<'_>,
    class: &str,
    version: &str,
    bytes: &[u8],
) -> PyResult<PyObject> {
    if version != VERSION {
        return Err(exception(format!(
            "unpickling a physid.{class} pickled by physid {version}: this is physid {VERSION}, which reads only its own (pickle it again from its inputs)"
        )));
    }
    Ok(match class {
        "Robot" => Py::new(py, state::<Robot>(class, bytes)?)?.into_any(),
        "Identification" => Py::new(py, state::<Identification>(class, bytes)?)?.into_any(),
        "Diagnosis" => Py::new(py, state::<Diagnosis>(class, bytes)?)?.into_any(),
        "Simulation" => Py::new(py, state::<Simulation>(class, bytes)?)?.into_any(),
        "Excitation" => Py::new(py, state::<Excitation>(class, bytes)?)?.into_any(),
        "Experiment" => Py::new(py, state::<Experiment>(class, bytes)?)?.into_any(),
        "Sweep" => Py::new(py, state::<Sweep>(class, bytes)?)?.into_any(),
        "Comparison" => Py::new(py, state::<Comparison>(class, bytes)?)?.into_any(),
        "FloatingIdentification" => {
            Py::new(py, state::<FloatingIdentification>(class, bytes)?)?.into_any()
        }
        "FloatingRobot" => Py::new(py, state::<FloatingRobot>(class, bytes)?)?.into_any(),
        other => {
            return Err(exception(format!(
                "unpickling: physid has no class '{other}'"
            )))
        }
    })
}
