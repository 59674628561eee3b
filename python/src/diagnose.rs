//! `physid.diagnose` and its `Diagnosis` (`physid diagnose`).

use crate::convert::*;
use crate::data::runs_of;
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
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct Diagnosis {
    diagnosis: api::diagnose::Diagnosis,
    standing: Option<Vec<String>>,
    notices: Vec<Notice>,
    inputs: Vec<PathBuf>,
}

#[pymethods]
impl Diagnosis {
    /// Pickles (and copies) as its state in physid's binary form.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<crate::pickle::Reduced<'py>> {
        crate::pickle::reduce(py, "Diagnosis", self)
    }

    /// The notebook's view: the report as one scoped fragment (its style applies to it
    /// alone), plots inline.
    fn _repr_html_(&self) -> PyResult<String> {
        let plots = api::diagnose::report::plots(&self.diagnosis).map_err(exception)?;
        Ok(api::diagnose::report::html_fragment(
            &self.diagnosis,
            &plots,
        ))
    }

    /// The verdict (e.g. `explained`, `partially_explained`, `unexplained`, `no_effect`).
    #[getter]
    fn verdict(&self) -> String {
        api::files::serde_name(&self.diagnosis.verdict)
    }

    /// The summary sentence.
    #[getter]
    fn summary(&self) -> String {
        self.diagnosis.summary.clone()
    }

    /// The effects found, in the order they were selected (kind names; `effects()` has their
    /// magnitudes).
    #[getter]
    fn effect_kinds(&self) -> Vec<String> {
        self.diagnosis
            .effects
            .iter()
            .map(|e| e.kind.name().to_string())
            .collect()
    }

    /// The effects found and their magnitudes, one row per effect and joint (a pandas
    /// DataFrame), those of the selection on the run's own data first, then those the ladder
    /// explained the description's gap with (a payload's mass, CoM and inertia as `payload`
    /// rows; `bodies` has them as values): `effect` (kind), `evidence` (`cross_validation`,
    /// `description`), `param` (its grid value: Stribeck velocity in
    /// rad/s, cogging harmonic; 0 otherwise), `magnitude` (what the value is), `joint` (or
    /// `robot`), `value` and its standard error `se` in `unit`, `identifiable` (the fraction of
    /// the effect not absorbed by the rigid-body parameters: near 0, the value means nothing),
    /// `ambiguous_with` (kinds the data cannot tell apart from it, comma-separated).
    #[pyo3(signature = (backend = "pandas"))]
    fn effects<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        let rows = pyo3::types::PyList::empty(py);
        let d = &self.diagnosis;
        for e in d.effects.iter().chain(&d.described_effects) {
            let ambiguous: Vec<&str> = e.ambiguous_with.iter().map(|k| k.name()).collect();
            for m in &e.magnitudes {
                let row = PyDict::new(py);
                row.set_item("effect", e.kind.name())?;
                row.set_item("evidence", api::files::serde_name(&e.evidence))?;
                row.set_item("param", e.param)?;
                row.set_item("magnitude", &e.magnitude_name)?;
                row.set_item("joint", &m.joint)?;
                row.set_item("value", m.value)?;
                row.set_item("se", m.se)?;
                row.set_item("unit", &m.unit)?;
                row.set_item("identifiable", m.identifiable)?;
                row.set_item("ambiguous_with", ambiguous.join(","))?;
                rows.append(row)?;
            }
        }
        let columns = [
            "effect",
            "evidence",
            "param",
            "magnitude",
            "joint",
            "value",
            "se",
            "unit",
            "identifiable",
            "ambiguous_with",
        ];
        records(py, rows.into_any(), &columns, backend)
    }

    /// The ladder of explanations from the description (how the diagnosis reads a description
    /// with a stated uncertainty or its identification's information), one row per rung (a
    /// pandas DataFrame): `step` (`description as given`, `+ payload on lwr_7_link`, …), `kind`
    /// (the effect kind, `payload` for a body change; None for the fixed rungs), `param`,
    /// `overall` (held-out RMS over the joints, N m, with this step and those before it in),
    /// `reduction` (of the held-out mean square by this step), `t` (its block t statistic),
    /// `mass` (kg, the mass a body-change step adds as weighed at it; NaN otherwise),
    /// `alternatives` (explanations tied with it, `; `-separated), then the held-out RMS per
    /// joint (N m), one column per joint. No rows when the diagnosis ran without a ladder.
    #[pyo3(signature = (backend = "pandas"))]
    fn ladder<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        let d = &self.diagnosis;
        let rows = pyo3::types::PyList::empty(py);
        let ladder = d.ladder.iter();
        for (rung, mass) in ladder.flat_map(|l| l.rungs.iter().zip(l.rung_masses())) {
            let row = PyDict::new(py);
            row.set_item("step", &rung.step)?;
            row.set_item("kind", rung.kind.map(|k| k.name()))?;
            row.set_item("param", rung.param)?;
            row.set_item("overall", rung.overall)?;
            row.set_item("reduction", rung.reduction)?;
            row.set_item("t", rung.t)?;
            row.set_item("mass", mass.unwrap_or(f64::NAN))?;
            row.set_item("alternatives", rung.alternatives().join("; "))?;
            for (joint, rms) in d.joints.iter().zip(&rung.rms) {
                row.set_item(joint, rms)?;
            }
            rows.append(row)?;
        }
        let mut columns = vec![
            "step",
            "kind",
            "param",
            "overall",
            "reduction",
            "t",
            "mass",
            "alternatives",
        ];
        columns.extend(d.joints.iter().map(String::as_str));
        records(py, rows.into_any(), &columns, backend)
    }

    /// The body changes the ladder found (`physid.BodyChange` values: body, mass and its
    /// standard error, centre of mass, whether it reads as a payload), in the order found;
    /// empty without a ladder.
    #[getter]
    fn bodies<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let found = match &self.diagnosis.ladder {
            Some(l) => plain(py, &l.bodies)?,
            None => pyo3::types::PyList::empty(py).into_any(),
        };
        py.import("physid.results")?
            .getattr("body_changes")?
            .call1((found,))
    }

    /// The payload the diagnosis names (the first body change that reads as one): a
    /// `physid.BodyChange` with `body`, `mass` (kg), `mass_se`, `com` (m, body frame); `None`
    /// when it names none.
    #[getter]
    fn payload<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        for b in self.bodies(py)?.try_iter()? {
            let b = b?;
            if b.getattr("payload")?.extract::<bool>()? {
                return Ok(Some(b));
            }
        }
        Ok(None)
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
        api::diagnose::report::text(&self.diagnosis)
    }

    /// The Markdown report (`report.md`).
    fn markdown(&self) -> String {
        api::diagnose::report::markdown(&self.diagnosis)
    }

    /// The self-contained HTML report (`report.html`), plots inline.
    fn html(&self) -> PyResult<String> {
        let plots = api::diagnose::report::plots(&self.diagnosis).map_err(exception)?;
        Ok(api::diagnose::report::html(&self.diagnosis, &plots))
    }

    /// Writes the report folder (`report.html`, `report.md`, `report.json`, SVG plots), as
    /// `physid diagnose --report`; never into a folder that is or holds an input.
    fn write_report(&self, path: PathBuf) -> PyResult<()> {
        api::files::check_result_dir(&path, &self.inputs).map_err(exception)?;
        api::diagnose::report::write(&path, &self.diagnosis).map_err(exception)
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
#[doc = include_str!("../keywords/diagnose.txt")]
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
    let roles = [
        ("data", Some(data)),
        ("validate", validate),
        ("baseline_data", baseline_data),
    ];
    let ([files, validate, baseline], memory) = runs_of(roles, &robot.model.joint_names())?;
    let mut o = api::diagnose::DiagnoseOptions::new(files);
    (o.validate, o.baseline_data) = (validate, baseline);
    o.read = read_options(topic, stamp, cutoff, lock, only)?;
    o.read.memory = memory.into();
    o.holdout = holdout;
    o.diagnosis = api::diagnose::Options {
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
    inputs.extend(api::files::robot_files(&robot.source, &[]));
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
