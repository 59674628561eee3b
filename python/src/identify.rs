//! `physid.load`, `physid.identify`, `physid.identify_arrays` and the `Identification` (`physid identify`).

use crate::convert::*;
use crate::data::{runs, runs_of};
use crate::errors::*;
use crate::robot::Robot;
use crate::work::*;
use api::Model;
use numpy::{IntoPyArray, PyArray1};
use physid::api;
use physid::api::data::ReadOptions;
use physid::api::identify::IdentifyOptions;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};

/// Reads data files (CSV, MCAP, rosbag2) for `robot` through physid's pipeline (gaps split into
/// runs, q̇ and q̈ derived where not logged, one cutoff for all files). Returns per file a dict:
/// `runs` (each with `t`, `q`, `qd`, `qdd`, `tau` arrays and `index`, each sample's index in the
/// file), `pipeline` (what was done, as `identify --json` reports it) and `notices`.
#[doc = include_str!("../keywords/load.txt")]
#[pyfunction]
#[pyo3(signature = (robot, data, *, topic = None, stamp = "log", cutoff = None, lock = None, only = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn load<'py>(
    py: Python<'py>,
    robot: &Robot,
    data: &Bound<'py, PyAny>,
    topic: Option<String>,
    stamp: &str,
    cutoff: Option<f64>,
    lock: Option<&Bound<'py, PyAny>>,
    only: Option<&Bound<'py, PyAny>>,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let m = &robot.model;
    let (files, memory) = runs("data", Some(data), &m.joint_names())?;
    let mut read = read_options(topic, stamp, cutoff, lock, only)?;
    read.memory = memory.into();
    let read = read.resolve(m).map_err(exception)?;
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let mut notices = api::data::bag_option_notices(&refs, &read).map_err(exception)?;
    let (model, owned) = (m.clone(), files.clone());
    let loaded = interruptible(py, move || {
        let refs: Vec<&Path> = owned.iter().map(PathBuf::as_path).collect();
        api::files::load_all(&refs, &model, &read)
    })?
    .map_err(exception)?;
    let mut out = vec![];
    for (path, l) in refs.iter().zip(&loaded) {
        let file_notes = api::data::file_notices(path, l);
        let d = PyDict::new(py);
        let mut runs = vec![];
        for r in &l.runs {
            let run = trajectory_dict(py, &r.trajectory)?;
            run.set_item("index", r.index.clone())?;
            runs.push(run);
        }
        d.set_item("file", path.to_path_buf())?;
        d.set_item("runs", runs)?;
        d.set_item("pipeline", plain(py, &l.report)?)?;
        d.set_item(
            "notices",
            file_notes.iter().map(|n| n.to_string()).collect::<Vec<_>>(),
        )?;
        notices.extend(file_notes);
        out.push(d);
    }
    warn(py, &notices)?;
    Ok(out)
}

/// What `identify` found (the report behind `physid identify`): `to_dict()` is its `--json`.
#[pyclass(frozen, module = "physid")]
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct Identification {
    report: api::identify::Identification,
    /// Wall time of the library's `identify` call (s).
    seconds: f64,
    model: Model,
    source: String,
    inputs: Vec<PathBuf>,
}

#[pymethods]
impl Identification {
    /// Pickles (and copies) as its state in physid's binary form.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<crate::pickle::Reduced<'py>> {
        crate::pickle::reduce(py, "Identification", self)
    }

    /// The notebook's view: the fit's set and errors, each body's π and consistency margins.
    fn _repr_html_(&self) -> String {
        use crate::notebook::{card, number, table};
        let r = &self.report;
        let rows: Vec<Vec<String>> = (r.identified.bodies.iter())
            .map(|b| {
                let c = &b.consistency;
                let com = |k: usize| number(b.pi[k] / b.pi[0]);
                vec![
                    b.name.clone(),
                    number(b.pi[0]),
                    format!("({}, {}, {})", com(1), com(2), com(3)),
                    number(c.min_eig_pseudo),
                    c.trace_jq.map_or("–".into(), number),
                    if c.consistent() { "yes" } else { "no" }.into(),
                ]
            })
            .collect();
        let header = [
            "body",
            "m (kg)",
            "CoM (m)",
            "min eig J",
            "tr(JQ)",
            "consistent",
        ];
        let mut facts = vec![
            ("constraints", r.set.name().to_string()),
            (
                "constraints hold",
                r.identified.constraints_hold.to_string(),
            ),
            ("train RMS", format!("{} N m", number(r.train.rms_overall))),
        ];
        if let Some(v) = &r.validation {
            facts.push(("validation RMS", format!("{} N m", number(v.rms_overall))));
        }
        card(
            &format!("Identification of '{}'", self.model.name()),
            &facts,
            &[("bodies", table(&header, &rows))],
        )
    }

    /// θ as identified: the model's parameters, then the effect terms' coefficients.
    #[getter]
    fn theta<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.report
            .identified
            .theta
            .as_slice()
            .to_vec()
            .into_pyarray(py)
    }

    /// The names of θ's entries.
    #[getter]
    fn parameter_names(&self) -> Vec<String> {
        api::identify::theta_names(&self.model, &self.report.terms)
    }

    /// The constraint set identified under.
    #[getter]
    fn constraints(&self) -> &'static str {
        self.report.set.name()
    }

    /// Whether the constraint set's matrix inequalities hold at the answer.
    #[getter]
    fn constraints_hold(&self) -> bool {
        self.report.identified.constraints_hold
    }

    /// RMS torque error over all fitted joints on the training samples (N m).
    #[getter]
    fn train_rms(&self) -> f64 {
        self.report.train.rms_overall
    }

    /// RMS torque error on the held-out samples (N m), `None` when nothing was held out.
    #[getter]
    fn validation_rms(&self) -> Option<f64> {
        self.report.validation.as_ref().map(|v| v.rms_overall)
    }

    /// Wall time of the library's own `identify` call (s): reading, fit, scores; what the
    /// Python call adds is the rest of its wall time.
    #[getter]
    fn seconds(&self) -> f64 {
        self.seconds
    }

    /// The notes and warnings, as `physid identify` prints them.
    #[getter]
    fn notices(&self) -> Vec<String> {
        notice_texts(&self.report.notices)
    }

    /// Each body's (and rotor's) identified π and its consistency margins, one row per body:
    /// a pandas DataFrame (`name`, `m`, `hx` … `Izz`, `min_eig_I`, `min_eig_J`, `tr_JQ`,
    /// `consistent`).
    #[pyo3(signature = (backend = "pandas"))]
    fn bodies<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        let b = &self.report.identified.bodies;
        let cols = PyDict::new(py);
        cols.set_item("name", b.iter().map(|b| b.name.clone()).collect::<Vec<_>>())?;
        for (k, key) in api::PARAM_NAMES.iter().enumerate() {
            cols.set_item(*key, b.iter().map(|b| b.pi[k]).collect::<Vec<_>>())?;
        }
        let c = |f: fn(&api::ConsistencyReport) -> Option<f64>| {
            b.iter().map(|b| f(&b.consistency)).collect::<Vec<_>>()
        };
        cols.set_item("min_eig_I", c(|c| Some(c.min_eig_spatial)))?;
        cols.set_item("min_eig_J", c(|c| Some(c.min_eig_pseudo)))?;
        cols.set_item("tr_JQ", c(|c| c.trace_jq))?;
        let consistent: Vec<bool> = b.iter().map(|b| b.consistency.consistent()).collect();
        cols.set_item("consistent", consistent)?;
        frame(py, cols.into_any(), backend)
    }

    /// One row per joint: `joint`, `viscous` (N m s/rad), `coulomb` (N m), then one column per
    /// identified term with a value per joint, named by its kind, in the unit of its magnitude
    /// (`torque_offset` in N m for `friction="…,offset"`; `to_dict()["effects"]` states the
    /// units), and the RMS torque errors `train_rms` and `validation_rms` (N m; NaN for a
    /// locked joint or nothing held out).
    #[pyo3(signature = (backend = "pandas"))]
    fn joints<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        let r = &self.report;
        let n = self.model.dof();
        let cols = PyDict::new(py);
        let names: Vec<String> = self.model.joint_names();
        cols.set_item("joint", names)?;
        cols.set_item("viscous", r.identified.viscous.clone())?;
        cols.set_item("coulomb", r.identified.coulomb.clone())?;
        for t in r.terms.iter().filter(|t| t.magnitudes.len() == n) {
            cols.set_item(t.kind.name(), t.magnitudes.clone())?;
        }
        let rms = |v: Option<&Vec<Option<f64>>>| -> Vec<f64> {
            (0..n)
                .map(|j| v.and_then(|v| v[j]).unwrap_or(f64::NAN))
                .collect()
        };
        cols.set_item("train_rms", rms(Some(&r.train.rms)))?;
        cols.set_item("validation_rms", rms(r.validation.as_ref().map(|v| &v.rms)))?;
        frame(py, cols.into_any(), backend)
    }

    /// The report as `physid identify --json` prints it.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, "identify", &self.report.json(&self.model))
    }

    /// Writes the identified model as URDF (the robot's own URDF with only `<inertial>` and
    /// `<dynamics>` changed, plus the sidecar `<name>.physid.toml`); never over an input.
    fn write_urdf(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let sidecar = api::files::sidecar_path(&path);
        let mut inputs: Vec<PathBuf> = self.inputs.clone();
        inputs.extend(api::files::robot_files(&self.source, &[]));
        let refs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
        api::files::check_outputs(&[&path, &sidecar], &refs).map_err(exception)?;
        let notices = self
            .report
            .write_urdf(&path, &self.source, &self.model)
            .map_err(exception)?;
        warn(py, &notices)
    }

    /// Writes the identified model as MJCF for MuJoCo (rotors as joint armature), never over
    /// an input.
    fn write_mjcf(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let identified = self.report.model(&self.model).map_err(api_error)?;
        let mut inputs: Vec<PathBuf> = self.inputs.clone();
        inputs.extend(api::files::robot_files(&self.source, &[]));
        let notices = api::export::write_mjcf(&identified, &path, &inputs).map_err(api_error)?;
        warn(py, &notices)
    }

    fn __repr__(&self) -> String {
        let v = self
            .validation_rms()
            .map_or(String::new(), |v| format!(", validation RMS {v:.4} N m"));
        format!(
            "Identification('{}', {}, constraints hold: {}, train RMS {:.4} N m{v})",
            self.model.name(),
            self.report.set.name(),
            if self.report.identified.constraints_hold {
                "True"
            } else {
                "False"
            },
            self.report.train.rms_overall
        )
    }
}

/// Identifies `robot` from data files as `physid identify` does, its flags as keyword
/// arguments: `data` (a path or list: CSV, MCAP, rosbag2), `validate_data`, `train` and
/// `validate` (`"a:b"`, `(a, b)` or `range(a, b)`), `constraints`, `friction`, `effects`,
/// `effects_from`, `prior_weight`, `eps`, `regularizer`, `topic`, `stamp`, `cutoff`, `lock`,
/// `only`, `allow_few_samples`, `mass_bounds` (`(lo, hi)`: each body's mass within lo..hi times
/// the description's, `0 <= lo <= 1 <= hi`), `total_mass` (`(lo, hi)` kg: the robot's moving
/// mass, links and rotors). Warnings are raised as `physid.PhysidWarning`;
/// the GIL is released while it runs.
#[doc = include_str!("../keywords/identify.txt")]
#[pyfunction]
#[pyo3(signature = (robot, data, *, validate_data = None, train = None, validate = None,
    constraints = None, friction = None, effects = None, effects_from = None,
    prior_weight = 1e-6, eps = 1e-6, regularizer = "euclidean", topic = None, stamp = "log",
    cutoff = None, lock = None, only = None, allow_few_samples = false, mass_bounds = None,
    total_mass = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn identify<'py>(
    py: Python<'py>,
    robot: &Robot,
    data: &Bound<'py, PyAny>,
    validate_data: Option<&Bound<'py, PyAny>>,
    train: Option<&Bound<'py, PyAny>>,
    validate: Option<&Bound<'py, PyAny>>,
    constraints: Option<&str>,
    friction: Option<&Bound<'py, PyAny>>,
    effects: Option<&Bound<'py, PyAny>>,
    effects_from: Option<PathBuf>,
    prior_weight: f64,
    eps: f64,
    regularizer: &str,
    topic: Option<String>,
    stamp: &str,
    cutoff: Option<f64>,
    lock: Option<&Bound<'py, PyAny>>,
    only: Option<&Bound<'py, PyAny>>,
    allow_few_samples: bool,
    mass_bounds: Option<(f64, f64)>,
    total_mass: Option<(f64, f64)>,
) -> PyResult<Identification> {
    let m = &robot.model;
    let mut o = training_runs(m, data, validate_data)?;
    o.train = sample_range("--train", train)?;
    o.validate = sample_range("--validate", validate)?;
    set_model_options(&mut o, m, constraints, (friction, effects), &effects_from)?;
    o.prior_weight = prior_weight;
    o.eps = eps;
    o.regularizer = regularizer
        .parse()
        .map_err(|e| exception(format!("--regularizer: {e}")))?;
    o.read = ReadOptions {
        memory: o.read.memory.clone(),
        ..read_options(topic, stamp, cutoff, lock, only)?
    };
    o.allow_few_samples = allow_few_samples;
    o.mass_bounds = mass_bounds.map(|(lo, hi)| api::identify::MassBounds { lo, hi });
    o.total_mass = total_mass.map(|(lo, hi)| api::identify::TotalMass { lo, hi });
    // For `write_urdf`'s sidecar: one more pass over the training samples.
    o.information = true;
    let mut inputs: Vec<PathBuf> = o.data.iter().chain(&o.validate_data).cloned().collect();
    inputs.extend(effects_from);
    let model = m.clone();
    let (report, seconds) = interruptible(py, move || {
        let start = std::time::Instant::now();
        let report = api::identify::identify(&model, &o);
        (report, start.elapsed().as_secs_f64())
    })?;
    let report = report.map_err(api_error)?;
    warn(py, &report.notices)?;
    Ok(Identification {
        report,
        seconds,
        model: m.clone(),
        source: robot.source.clone(),
        inputs,
    })
}

/// Options naming `identify`'s runs: `data` and `validate_data` (paths or `physid.Data`), the
/// runs held in memory among them in the reading options.
fn training_runs(
    m: &api::Model,
    data: &Bound<'_, PyAny>,
    validate_data: Option<&Bound<'_, PyAny>>,
) -> PyResult<IdentifyOptions> {
    let roles = [("data", Some(data)), ("validate_data", validate_data)];
    let ([files, validate_files], memory) = runs_of(roles, &m.joint_names())?;
    let mut o = IdentifyOptions::new(files);
    o.validate_data = validate_files;
    o.read.memory = memory.into();
    Ok(o)
}

/// `identify`'s model keywords onto `o`: the constraint set, the friction and effect terms
/// (`(friction, effects)`), and the effects confirmed in a diagnosis report (`effects_from`).
pub(crate) fn set_model_options(
    o: &mut IdentifyOptions,
    m: &api::Model,
    constraints: Option<&str>,
    (friction, effects): (Option<&Bound<'_, PyAny>>, Option<&Bound<'_, PyAny>>),
    effects_from: &Option<PathBuf>,
) -> PyResult<()> {
    o.constraints = constraints
        .map(str::parse)
        .transpose()
        .map_err(|e| exception(format!("--constraints: {e}")))?;
    let friction = match friction {
        Some(f) => names(Some(f))?,
        None => vec!["viscous".into(), "coulomb".into()],
    };
    o.terms = api::identify::parse_terms(&friction, &names(effects)?).map_err(exception)?;
    if let Some(p) = effects_from {
        o.terms
            .extend(api::identify::confirmed_effects(p, m).map_err(exception)?);
    }
    Ok(())
}
