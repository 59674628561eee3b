//! `physid.simulate` and its `Simulation` (`physid simulate`).

use crate::convert::*;
use crate::errors::*;
use crate::robot::Robot;
use crate::work::*;
use numpy::{IntoPyArray, PyArrayMethods};
use physid::api;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};

/// A simulated excitation experiment (`physid simulate`), its log written: `to_dict()` is its
/// `--json`; the signals as numpy arrays.
#[pyclass(frozen, module = "physid")]
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct Simulation {
    run: api::simulate::Simulation,
    out: PathBuf,
}

#[pymethods]
impl Simulation {
    /// Pickles (and copies) as its state in physid's binary form.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<crate::pickle::Reduced<'py>> {
        crate::pickle::reduce(py, "Simulation", self)
    }

    /// The notebook's view: the scenario, its samples and engine, the log written.
    fn _repr_html_(&self) -> String {
        crate::notebook::card(
            &format!("Simulation of {}", self.run.path.display()),
            &[
                ("robot", self.run.model.name().to_string()),
                ("samples", self.run.recording.truth.len().to_string()),
                ("engine", self.run.engine_name().to_string()),
                ("log", self.out.display().to_string()),
            ],
            &[],
        )
    }

    /// The true signals: state, accelerations and the torque the actuators delivered (`tau`),
    /// with its parts `friction` (the true friction torque) and `effects` (the injected
    /// physical effects' torque), `(samples, n)` N m each.
    #[getter]
    fn truth<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let rec = &self.run.recording;
        let d = trajectory_dict(py, &rec.truth)?;
        let (s, n) = (rec.truth.len(), rec.truth.joint_names.len());
        d.set_item(
            "friction",
            rec.friction.clone().into_pyarray(py).reshape([s, n])?,
        )?;
        d.set_item(
            "effects",
            rec.effects.clone().into_pyarray(py).reshape([s, n])?,
        )?;
        Ok(d)
    }

    /// What the robot logs: encoder positions, the controller's velocity, the logged torque.
    #[getter]
    fn measured<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        trajectory_dict(py, &self.run.recording.measured)
    }

    /// The offline-processed signals: the identification input (what `--csv` writes).
    #[getter]
    fn processed<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        trajectory_dict(py, &self.run.recording.processed)
    }

    /// The scenario's robot, the ground truth.
    #[getter]
    fn robot(&self) -> Robot {
        Robot {
            model: self.run.model.clone(),
            source: self.run.path.to_string_lossy().into_owned(),
            as_file: false,
            notices: vec![],
        }
    }

    /// The report as `physid simulate --json` prints it.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, "simulate", &self.run.report(&self.out))
    }

    fn __repr__(&self) -> String {
        format!(
            "Simulation('{}', {} samples, engine {}, written to {})",
            self.run.path.display(),
            self.run.recording.truth.len(),
            self.run.engine_name(),
            self.out.display()
        )
    }
}

/// Simulates a scenario's excitation experiment and logs it to MCAP at `out` (and the
/// processed samples as CSV at `csv`), as `physid simulate` does: `engine` (`"physid"` or
/// `"rapier"`), `duration` (s) and `seed` override the scenario's. `progress`, if given, is
/// called with the fraction done (0 to 1, at most every percent), e.g. to drive a tqdm bar.
/// Outputs never replace an input (the scenario, its robot's files). Ctrl-C stops the run (within a percent of it) and nothing is written.
#[doc = include_str!("../keywords/simulate.txt")]
#[pyfunction]
#[pyo3(signature = (scenario, out, *, csv = None, engine = None, duration = None, seed = None,
    progress = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn simulate(
    py: Python<'_>,
    scenario: PathBuf,
    out: PathBuf,
    csv: Option<PathBuf>,
    engine: Option<&str>,
    duration: Option<f64>,
    seed: Option<u64>,
    progress: Option<PyObject>,
) -> PyResult<Simulation> {
    let callback = progress;
    let engine = engine_of(engine)?;
    let files = api::files::scenario_files(&scenario);
    let inputs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let outputs: Vec<&Path> = std::iter::once(out.as_path())
        .chain(csv.as_deref())
        .collect();
    api::files::check_outputs(&outputs, &inputs).map_err(exception)?;
    let opts = api::simulate::SimulateOptions {
        engine,
        duration,
        seed,
    };
    let (path, log, table) = (scenario.clone(), out.clone(), csv.clone());
    let work = move |cancel: Cancel, progress: Progress<f64>| {
        let stop = || is_cancelled(&cancel);
        let mut shown = -1.0;
        let mut report = |f: f64| {
            if f - shown >= 0.01 || f >= 1.0 {
                shown = f;
                let _ = progress.send(f);
            }
        };
        api::simulate::simulate_until(&path, &opts, &mut report, &stop).and_then(|run| {
            if stop() {
                return Err(api::ApiError::Cancelled);
            }
            run.write_mcap(&log)?;
            if let Some(c) = &table {
                if stop() {
                    return Err(api::ApiError::Cancelled);
                }
                run.write_csv(c)?;
            }
            Ok(run)
        })
    };
    let result = reporting(py, work, |py, f: f64| match &callback {
        Some(cb) => cb.call1(py, (f,)).map(drop),
        None => Ok(()),
    })?;
    let run = result.map_err(api_error)?;
    Ok(Simulation { run, out })
}

/// `simulate`'s `engine` keyword (`None`: the scenario's own).
pub(crate) fn engine_of(engine: Option<&str>) -> PyResult<Option<api::simulate::Engine>> {
    match engine {
        None => Ok(None),
        Some("physid") => Ok(Some(api::simulate::Engine::Physid)),
        Some("rapier") => Ok(Some(api::simulate::Engine::Rapier)),
        Some(other) => Err(exception(format!(
            "--engine: '{other}' is not one of physid, rapier"
        ))),
    }
}
