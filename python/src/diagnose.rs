//! `physid.diagnose` and its `Diagnosis` (`physid diagnose`).

use crate::convert::*;
use crate::errors::*;
use crate::robot::Robot;
use crate::work::*;
use physid::api;
use physid::api::data::Notice;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// A diagnosis of the gap between a robot description and its runs (`physid diagnose`):
/// `to_dict()` is its `--json`; in a notebook it shows itself as the HTML report, plots inline.
#[pyclass(frozen, module = "physid")]
pub(crate) struct Diagnosis {
    diagnosis: physid::diagnose::Diagnosis,
    standing: Option<Vec<String>>,
    notices: Vec<Notice>,
    inputs: Vec<PathBuf>,
}

#[pymethods]
impl Diagnosis {
    /// The verdict (e.g. `explained`, `partially_explained`, `unexplained`, `no_effect`).
    #[getter]
    fn verdict(&self) -> String {
        physid::io::serde_name(&self.diagnosis.verdict)
    }

    /// The summary sentence.
    #[getter]
    fn summary(&self) -> String {
        self.diagnosis.summary.clone()
    }

    /// The effects found, in the order they were selected (kind names).
    #[getter]
    fn effects(&self) -> Vec<String> {
        self.diagnosis
            .effects
            .iter()
            .map(|e| e.kind.name().to_string())
            .collect()
    }

    /// In "what changed" mode, the baseline's standing effects taken out of the data.
    #[getter]
    fn standing(&self) -> Option<Vec<String>> {
        self.standing.clone()
    }

    /// The notes and warnings, as `physid diagnose` prints them.
    #[getter]
    fn notices(&self) -> Vec<String> {
        notice_texts(&self.notices)
    }

    /// The gap per joint: validation RMS (N m) of the description as given, the re-identified
    /// nominal model, after every effect found, and the noise floor — a pandas DataFrame.
    #[pyo3(signature = (backend = "pandas"))]
    fn gap<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        let g = &self.diagnosis.gap;
        let cols = PyDict::new(py);
        cols.set_item(
            "joint",
            g.iter().map(|g| g.joint.clone()).collect::<Vec<_>>(),
        )?;
        cols.set_item(
            "description",
            g.iter().map(|g| g.description).collect::<Vec<_>>(),
        )?;
        cols.set_item("nominal", g.iter().map(|g| g.nominal).collect::<Vec<_>>())?;
        for (i, e) in self.diagnosis.how_far_effects().iter().enumerate() {
            cols.set_item(
                format!("+ {}", e.kind.name()),
                g.iter().map(|g| g.after[i]).collect::<Vec<_>>(),
            )?;
        }
        cols.set_item(
            "noise_floor",
            g.iter().map(|g| g.noise_floor).collect::<Vec<_>>(),
        )?;
        frame(py, cols.into_any(), backend)
    }

    /// The report as `physid diagnose --json` prints it.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, "diagnose", &self.diagnosis)
    }

    /// The report as `physid diagnose` prints it on a terminal (the same sections as the
    /// Markdown, condensed, the summary last).
    fn text(&self) -> String {
        physid::diagnose::report::text(&self.diagnosis)
    }

    /// The Markdown report (`report.md`).
    fn markdown(&self) -> String {
        physid::diagnose::report::markdown(&self.diagnosis)
    }

    /// The self-contained HTML report (`report.html`), plots inline.
    fn html(&self) -> PyResult<String> {
        let plots = physid::diagnose::report::plots(&self.diagnosis).map_err(exception)?;
        Ok(physid::diagnose::report::html(&self.diagnosis, &plots))
    }

    fn _repr_html_(&self) -> PyResult<String> {
        self.html()
    }

    /// Writes the report folder (`report.html`, `report.md`, `report.json`, SVG plots), as
    /// `physid diagnose --report`; never into a folder that is or holds an input.
    fn write_report(&self, path: PathBuf) -> PyResult<()> {
        physid::io::check_result_dir(&path, &self.inputs).map_err(exception)?;
        physid::diagnose::report::write(&path, &self.diagnosis).map_err(exception)
    }

    fn __repr__(&self) -> String {
        format!(
            "Diagnosis('{}', {}: {})",
            self.diagnosis.robot,
            self.verdict(),
            self.diagnosis.summary
        )
    }
}

/// Diagnoses the gap between `robot` (the description) and its runs as `physid diagnose` does,
/// its flags as keyword arguments: `data`, `validate`, `baseline_data` (paths), `constraints`,
/// `holdout`, `description_uncertainty`, `payload_any_body`, `topic`, `stamp`, `cutoff`, `lock`,
/// `only`; `description_information=False` is `--no-description-information`. Warnings are raised as `physid.PhysidWarning`; Ctrl-C interrupts it.
#[pyfunction]
#[pyo3(signature = (robot, data, *, validate = None, baseline_data = None,
    constraints = "consistent", holdout = 0.3, description_uncertainty = None,
    payload_any_body = false, topic = None, stamp = "log", cutoff = None, lock = None,
    only = None, description_information = true))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn diagnose<'py>(
    py: Python<'py>,
    robot: &Robot,
    data: &Bound<'py, PyAny>,
    validate: Option<&Bound<'py, PyAny>>,
    baseline_data: Option<&Bound<'py, PyAny>>,
    constraints: &str,
    holdout: f64,
    description_uncertainty: Option<f64>,
    payload_any_body: bool,
    topic: Option<String>,
    stamp: &str,
    cutoff: Option<f64>,
    lock: Option<&Bound<'py, PyAny>>,
    only: Option<&Bound<'py, PyAny>>,
    description_information: bool,
) -> PyResult<Diagnosis> {
    let mut o = api::diagnose::DiagnoseOptions::new(paths("data", Some(data))?);
    o.validate = paths("validate", validate)?;
    o.baseline_data = paths("baseline_data", baseline_data)?;
    o.read = read_options(topic, stamp, cutoff, lock, only)?;
    o.holdout = holdout;
    o.diagnosis = physid::diagnose::Options {
        constraints: constraints
            .parse()
            .map_err(|e| exception(format!("--constraints: {e}")))?,
        description_uncertainty,
        every_body: payload_any_body,
        ..Default::default()
    };
    let mut early = vec![];
    if description_information && robot.as_file {
        early = api::information::apply(&robot.source, &robot.model, &mut o.diagnosis)
            .map_err(api_error)?;
    }
    warn(py, &early)?;
    let mut inputs: Vec<PathBuf> = o.files().iter().map(|p| p.to_path_buf()).collect();
    inputs.extend(physid::io::robot_files(&robot.source, &[]));
    let model = robot.model.clone();
    let (outcome, notices) = interruptible(py, move || {
        let mut notices = vec![];
        let outcome = api::diagnose::diagnose_files(&model, &o, &mut |n| notices.push(n.clone()));
        (outcome, notices)
    })?;
    warn(py, &notices)?;
    let outcome = outcome.map_err(api_error)?;
    let notices = early.into_iter().chain(notices).collect();
    Ok(Diagnosis {
        diagnosis: outcome.diagnosis,
        standing: outcome.standing,
        notices,
        inputs,
    })
}
