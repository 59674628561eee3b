//! `physid._physid`: the Python extension over physid's library entry points (`physid::api`).
//!
//! Arrays cross as numpy arrays of float64: joint quantities as `(samples, n)` (a 1-D array of
//! `n` is one sample), results likewise. Errors raise `ValueError` with the library's message;
//! long calls release the GIL.

use numpy::{IntoPyArray, PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn};
use physid::api;
use physid::api::data::{Notice, ReadOptions};
use physid::api::identify::{IdentifyOptions, SampleRange};
use physid::api::model::RobotOptions;
use physid::ident::{ConstraintSet, NormalEquations, Options};
use physid::model::{Model, RotorModel};
use physid::trajectory::Trajectory;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use std::path::{Path, PathBuf};

/// A library error as a Python `ValueError` with its message.
fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A library entry point's error as a Python `ValueError` with the CLI's message (an invalid
/// option named as its flag).
fn api_error<E: physid::options::OptionError + std::error::Error>(e: E) -> PyErr {
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

/// A JSON value (as physid writes it, with its schema) as Python objects.
fn to_python<'py>(
    py: Python<'py>,
    schema: &str,
    value: &impl serde::Serialize,
) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(&physid::io::versioned(schema, value)).map_err(value_error)?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A value as Python objects through its JSON form (no schema tag).
fn plain<'py>(py: Python<'py>, value: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(value_error)?;
    py.import("json")?.call_method1("loads", (text,))
}

/// Joint values given as an array-like, read once: sample-major, with their sample count and
/// whether they were one sample (shape `(n,)`, answered with one sample as pinocchio does).
struct Joints {
    values: Vec<f64>,
    samples: usize,
    one: bool,
}

/// An array-like of joint values as [`Joints`]: anything `numpy.asarray` reads as real numbers
/// (numpy arrays of any integer or float dtype, nested lists, pandas and polars frames), of
/// shape `(samples, n)` or one sample `(n,)`.
fn samples(name: &str, a: &Bound<'_, PyAny>, n: usize) -> PyResult<Joints> {
    let array = a.py().import("numpy")?.call_method1("asarray", (a,))?;
    let dtype = array.getattr("dtype")?;
    let kind: String = dtype.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "i" | "u" | "f") {
        return Err(PyTypeError::new_err(format!(
            "{name}: an array of real numbers is needed, not one of dtype {dtype}"
        )));
    }
    let array: PyReadonlyArrayDyn<'_, f64> =
        array.call_method1("astype", ("float64",))?.extract()?;
    let view = array.as_array();
    let shape = view.shape().to_vec();
    let (samples, one) = match shape[..] {
        [m] if m == n => (1, true),
        [s, m] if m == n => (s, false),
        _ => {
            return Err(value_error(format!(
            "{name} has shape {shape:?}: give (samples, {n}) or ({n},) for the robot's {n} joints"
        )))
        }
    };
    Ok(Joints {
        values: view.iter().copied().collect(),
        samples,
        one,
    })
}

/// Positions, velocities and accelerations as flat sample-major vectors, q's sample count (the
/// library checks that the others have as many), and whether q was one sample.
struct States {
    q: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
    samples: usize,
    one: bool,
}

fn states(
    q: &Bound<'_, PyAny>,
    qd: &Bound<'_, PyAny>,
    qdd: &Bound<'_, PyAny>,
    n: usize,
) -> PyResult<States> {
    let q = samples("q", q, n)?;
    Ok(States {
        qd: samples("qd", qd, n)?.values,
        qdd: samples("qdd", qdd, n)?.values,
        samples: q.samples,
        one: q.one,
        q: q.values,
    })
}

/// `values` shaped `(samples, rest…)`, or `(rest…)` for one sample given as one.
fn shaped<'py>(
    py: Python<'py>,
    values: Vec<f64>,
    samples: usize,
    one: bool,
    rest: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let shape: Vec<usize> = if one {
        rest.to_vec()
    } else {
        std::iter::once(samples)
            .chain(rest.iter().copied())
            .collect()
    };
    values.into_pyarray(py).reshape(shape)
}

/// A robot: the built-in leg (`"cheetah3"`), a URDF file, or a robot TOML file.
#[pyclass(frozen, module = "physid")]
struct Robot {
    model: Model,
    /// The robot as given (`cheetah3` or a file), for outputs that copy its URDF.
    source: String,
    /// The model is the dynamics `source` gives by itself (no rotor option changed it), so a
    /// scenario may name the file for it.
    as_file: bool,
}

#[pymethods]
impl Robot {
    /// Loads `robot` (`"cheetah3"`, a URDF or a robot TOML path); `rotor_model` (`"full"` or
    /// `"reflected"`), `no_rotors`, `ellipsoid_margin` (m), `package_dirs` and
    /// `no_geometry_ellipsoids` as the CLI's robot flags. The loader's warnings are issued as
    /// `PhysidWarning`.
    #[new]
    #[pyo3(signature = (robot, *, rotor_model = None, no_rotors = false, ellipsoid_margin = None,
        package_dirs = None, no_geometry_ellipsoids = false))]
    fn new(
        py: Python<'_>,
        robot: &Bound<'_, PyAny>,
        rotor_model: Option<&str>,
        no_rotors: bool,
        ellipsoid_margin: Option<f64>,
        package_dirs: Option<&Bound<'_, PyAny>>,
        no_geometry_ellipsoids: bool,
    ) -> PyResult<Self> {
        let robot: PathBuf = robot.extract().map_err(|_| {
            value_error("robot: give \"cheetah3\" or a path to a URDF or robot TOML")
        })?;
        let rotor_model = match rotor_model {
            None => None,
            Some("full") => Some(RotorModel::Full),
            Some("reflected") => Some(RotorModel::Reflected),
            Some(other) => {
                return Err(value_error(format!(
                    "--rotor-model: '{other}' is not one of full, reflected"
                )))
            }
        };
        let opts = RobotOptions {
            robot: robot.to_string_lossy().into_owned(),
            rotor_model,
            no_rotors,
            ellipsoid_margin,
            package_dirs: paths("package_dirs", package_dirs)?,
            no_geometry_ellipsoids,
        };
        let api::model::LoadedRobot { model, notices } =
            py.allow_threads(|| opts.load()).map_err(api_error)?;
        warn(py, &notices)?;
        Ok(Robot {
            model,
            source: opts.robot,
            as_file: rotor_model.is_none() && !no_rotors,
        })
    }

    /// Writes the robot as MJCF for MuJoCo (rotors as joint armature), never over an input;
    /// meshes MuJoCo cannot read are left out with a `PhysidWarning`.
    fn write_mjcf(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let inputs = physid::io::robot_files(&self.source, &[]);
        let notices = api::export::write_mjcf(&self.model, &path, &inputs).map_err(api_error)?;
        warn(py, &notices)
    }

    /// Writes the robot as URDF with its sidecar `<name>.physid.toml` (a URDF robot's own
    /// file with `<inertial>` and `<dynamics>` rewritten, else a new file), never over an
    /// input.
    fn write_urdf(&self, path: PathBuf) -> PyResult<()> {
        let robot = if self.as_file {
            self.source.as_str()
        } else {
            ""
        };
        let inputs = physid::io::robot_files(&self.source, &[]);
        api::export::write_urdf(&self.model, robot, &path, &inputs).map_err(api_error)
    }

    /// The robot's name.
    #[getter]
    fn name(&self) -> String {
        self.model.name().to_string()
    }

    /// Number of joints.
    #[getter]
    fn dof(&self) -> usize {
        self.model.dof()
    }

    /// Joint names, in the robot's order (the columns of every array).
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.model.joint_names()
    }

    /// The names of θ's entries (per body and rotor `m, hx, …, Izz`, then friction).
    #[getter]
    fn parameter_names(&self) -> Vec<String> {
        self.model.parameter_names()
    }

    /// The description's parameter vector θ.
    fn parameters<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.model.parameters().as_slice().to_vec().into_pyarray(py)
    }

    /// `τ = RNEA(q, q̇, q̈) + friction` (N m): `(samples, n)`, or `(n,)` for one sample given
    /// as `(n,)`. q (rad or m), q̇, q̈: array-likes of shape `(samples, n)` or `(n,)`.
    fn inverse_dynamics<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        qd: &Bound<'py, PyAny>,
        qdd: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let n = self.model.dof();
        let x = states(q, qd, qdd, n)?;
        let tau = py
            .allow_threads(|| api::dynamics::inverse_dynamics(&self.model, &x.q, &x.qd, &x.qdd))
            .map_err(value_error)?;
        shaped(py, tau, x.samples, x.one, &[n])
    }

    /// The joint-space mass matrix `H(q)` (kg m²): `(samples, n, n)`, or `(n, n)` for one
    /// sample given as `(n,)`.
    fn mass_matrix<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let n = self.model.dof();
        let q = samples("q", q, n)?;
        let h = py
            .allow_threads(|| api::dynamics::mass_matrices(&self.model, &q.values))
            .map_err(value_error)?;
        shaped(py, h, q.samples, q.one, &[n, n])
    }

    /// The regressor `Y(q, q̇, q̈)`, `Y θ = τ`: `(samples, n, p)`, or `(n, p)` for one sample
    /// given as `(n,)`.
    fn regressor<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        qd: &Bound<'py, PyAny>,
        qdd: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let (n, p) = (self.model.dof(), self.model.layout().len);
        let x = states(q, qd, qdd, n)?;
        let y = py
            .allow_threads(|| api::dynamics::regressors(&self.model, &x.q, &x.qd, &x.qdd))
            .map_err(value_error)?;
        shaped(py, y, x.samples, x.one, &[n, p])
    }

    /// The robot described: bodies, rotors, joints, gravity torque at rest (the JSON of
    /// `physid model --json`).
    fn describe<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, "model", &api::model::describe(&self.model))
    }

    fn __repr__(&self) -> String {
        format!(
            "Robot('{}', {} joints, {} parameters)",
            self.model.name(),
            self.model.dof(),
            self.model.layout().len
        )
    }
}

/// Samples given as arrays as a trajectory on a nominal 1 kHz clock, their lengths, sample
/// counts and finiteness checked (named by array, sample and joint).
fn array_trajectory(robot: &Robot, x: States, tau: Vec<f64>) -> PyResult<Trajectory> {
    let m = &robot.model;
    api::dynamics::samples(m, &x.q, &[("qd", &x.qd), ("qdd", &x.qdd), ("tau", &tau)])
        .map_err(value_error)?;
    let mut tr = Trajectory::new(robot.joint_names(), true);
    tr.t = (0..x.samples).map(|k| k as f64 * 1e-3).collect();
    tr.q = x.q;
    tr.qd = x.qd;
    tr.qdd = Some(x.qdd);
    tr.tau = tau;
    Ok(tr)
}

/// Identifies `robot`'s parameters θ from samples given as arrays (`(samples, n)` each, N m
/// for `tau`) under a constraint set (`none`, `semi`, `consistent`, `ellipsoid`; default: the
/// tightest the description supports), the description as the prior. Returns a dict: `theta`
/// (an array), `parameter_names`, `constraints`, `constraints_hold`, `objective`, `bodies`,
/// `friction`, `solver`.
#[pyfunction]
#[pyo3(signature = (robot, q, qd, qdd, tau, constraints = None, prior_weight = 1e-6))]
#[allow(clippy::too_many_arguments)]
fn identify_arrays<'py>(
    py: Python<'py>,
    robot: &Robot,
    q: &Bound<'py, PyAny>,
    qd: &Bound<'py, PyAny>,
    qdd: &Bound<'py, PyAny>,
    tau: &Bound<'py, PyAny>,
    constraints: Option<&str>,
    prior_weight: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let m = &robot.model;
    let n = m.dof();
    let given = constraints
        .map(|c| c.parse::<ConstraintSet>())
        .transpose()
        .map_err(value_error)?;
    let chosen = api::identify::constraint_set(given, m);
    let (set, because) = (chosen.set, chosen.because);
    let mut opts = Options::new(set);
    opts.prior_weight = prior_weight;
    opts.validate().map_err(value_error)?;
    let tr = array_trajectory(
        robot,
        states(q, qd, qdd, n)?,
        samples("tau", tau, n)?.values,
    )?;
    let s = tr.len();
    let identified = py
        .allow_threads(|| {
            let ne = NormalEquations::from_trajectory(m, &tr, 0..s);
            physid::ident::identify(m, &ne, &m.parameters(), &opts)
        })
        .map_err(value_error)?;
    let out = PyDict::new(py);
    out.set_item(
        "theta",
        identified.theta.as_slice().to_vec().into_pyarray(py),
    )?;
    out.set_item("parameter_names", m.parameter_names())?;
    out.set_item("constraints", set.name())?;
    out.set_item("constraints_default_because", because)?;
    out.set_item("constraints_hold", identified.constraints_hold)?;
    out.set_item("objective", identified.objective)?;
    out.set_item("samples", s)?;
    let rest = to_python(py, "identified", &identified)?;
    for key in ["bodies", "viscous", "coulomb", "solver"] {
        out.set_item(key, rest.get_item(key)?)?;
    }
    Ok(out)
}

/// Runs `work` on its own thread with the GIL released, checking for Ctrl-C (and any other
/// pending Python signal) every 50 ms: an interrupt raises `KeyboardInterrupt` at once, the
/// abandoned work finishing in the background with its result dropped. For work that writes
/// files, use [`cancellable`].
fn interruptible<T: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce() -> T + Send + 'static,
) -> PyResult<T> {
    cancellable(py, move |_| work())
}

/// A flag set when the call that started a work was interrupted: the work asks it between its
/// steps and before each write, and stops (nothing written after the exception was raised,
/// beyond a file whose writing had already begun).
type Cancel = std::sync::Arc<std::sync::atomic::AtomicBool>;

/// Whether `cancel` is set.
fn is_cancelled(cancel: &Cancel) -> bool {
    cancel.load(std::sync::atomic::Ordering::SeqCst)
}

/// [`interruptible`], the work handed the flag an interrupt sets ([`Cancel`]).
fn cancellable<T: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce(Cancel) -> T + Send + 'static,
) -> PyResult<T> {
    let cancel: Cancel = Default::default();
    let flag = cancel.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("physid".into())
        .spawn(move || {
            let _ = tx.send(work(flag));
        })
        .map_err(|e| value_error(format!("could not start a worker thread: {e}")))?;
    let mut rx = rx;
    loop {
        let tick = std::time::Duration::from_millis(50);
        let (got, back) = py.allow_threads(move || (rx.recv_timeout(tick), rx));
        rx = back;
        match got {
            Ok(out) => return Ok(out),
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                if let Err(interrupt) = py.check_signals() {
                    cancel.store(true, std::sync::atomic::Ordering::SeqCst);
                    return Err(interrupt);
                }
            }
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                return Err(pyo3::exceptions::PyRuntimeError::new_err(
                    "physid's worker thread panicked: please report this with its input",
                ))
            }
        }
    }
}

/// A list of paths from a path or a sequence of paths (`str` or `os.PathLike`).
fn paths(what: &str, v: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<PathBuf>> {
    let Some(v) = v else { return Ok(vec![]) };
    if let Ok(one) = v.extract::<PathBuf>() {
        return Ok(vec![one]);
    }
    v.extract::<Vec<PathBuf>>()
        .map_err(|_| value_error(format!("{what}: give a path or a list of paths")))
}

/// A list of names from `"a,b"` or `["a", "b"]`.
fn names(v: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<String>> {
    let Some(v) = v else { return Ok(vec![]) };
    if let Ok(s) = v.extract::<String>() {
        return Ok(s.split(',').map(|x| x.trim().to_string()).collect());
    }
    v.extract::<Vec<String>>()
}

/// A sample range from `"a:b"`, `(a, b)` or `range(a, b)` (`None`: the file's end).
fn sample_range(what: &str, v: Option<&Bound<'_, PyAny>>) -> PyResult<Option<SampleRange>> {
    let Some(v) = v else { return Ok(None) };
    if let Ok(s) = v.extract::<String>() {
        return SampleRange::parse(&s, what).map(Some).map_err(value_error);
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
    Err(value_error(format!(
        "{what}: give \"a:b\", (a, b) or range(a, b) of sample indices (non-negative, step 1)"
    )))
}

/// How files are read, from the keyword arguments shared by `load` and `identify`.
fn read_options(
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
            .map_err(|e| value_error(format!("--stamp: {e}")))?,
        cutoff,
        lock: names(lock)?,
        only: names(only)?,
    })
}

/// Raises each warning among `notices` as a Python `physid.PhysidWarning` (notes are kept in
/// the result only).
fn warn(py: Python<'_>, notices: &[Notice]) -> PyResult<()> {
    let category = py.import("physid")?.getattr("PhysidWarning")?;
    for n in notices.iter().filter(|n| n.warning) {
        PyErr::warn(py, &category, &std::ffi::CString::new(n.text.clone())?, 1)?;
    }
    Ok(())
}

/// Reads data files (CSV, MCAP, rosbag2) for `robot` through physid's pipeline (gaps split into
/// runs, q̇ and q̈ derived where not logged, one cutoff for all files). Returns per file a dict:
/// `runs` (each with `t`, `q`, `qd`, `qdd`, `tau` arrays and `index`, each sample's index in the
/// file), `pipeline` (what was done, as `identify --json` reports it) and `notices`.
#[pyfunction]
#[pyo3(signature = (robot, data, *, topic = None, stamp = "log", cutoff = None, lock = None, only = None))]
#[allow(clippy::too_many_arguments)]
fn load<'py>(
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
    let files = paths("data", Some(data))?;
    let read = read_options(topic, stamp, cutoff, lock, only)?
        .resolve(m)
        .map_err(value_error)?;
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let mut notices = api::data::bag_option_notices(&refs, &read).map_err(value_error)?;
    let (model, owned) = (m.clone(), files.clone());
    let loaded = interruptible(py, move || {
        let refs: Vec<&Path> = owned.iter().map(PathBuf::as_path).collect();
        physid::io::load_all(&refs, &model, &read)
    })?
    .map_err(value_error)?;
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
struct Identification {
    report: api::identify::Identification,
    /// Wall time of the library's `identify` call (s).
    seconds: f64,
    model: Model,
    source: String,
    inputs: Vec<PathBuf>,
}

#[pymethods]
impl Identification {
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
        self.report.notices.iter().map(|n| n.to_string()).collect()
    }

    /// Each body's (and rotor's) identified π and its consistency margins, one row per body:
    /// a pandas DataFrame (`name`, `m`, `hx` … `Izz`, `min_eig_I`, `min_eig_J`, `tr_JQ`,
    /// `consistent`).
    #[pyo3(signature = (backend = "pandas"))]
    fn bodies<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        let b = &self.report.identified.bodies;
        let cols = PyDict::new(py);
        cols.set_item("name", b.iter().map(|b| b.name.clone()).collect::<Vec<_>>())?;
        for (k, key) in physid::spatial::PARAM_NAMES.iter().enumerate() {
            cols.set_item(*key, b.iter().map(|b| b.pi[k]).collect::<Vec<_>>())?;
        }
        let c = |f: fn(&physid::spatial::ConsistencyReport) -> Option<f64>| {
            b.iter().map(|b| f(&b.consistency)).collect::<Vec<_>>()
        };
        cols.set_item("min_eig_I", c(|c| Some(c.min_eig_spatial)))?;
        cols.set_item("min_eig_J", c(|c| Some(c.min_eig_pseudo)))?;
        cols.set_item("tr_JQ", c(|c| c.trace_jq))?;
        let consistent: Vec<bool> = b.iter().map(|b| b.consistency.consistent()).collect();
        cols.set_item("consistent", consistent)?;
        frame(py, cols.into_any(), backend)
    }

    /// One row per joint: `joint`, `viscous` (N m s/rad), `coulomb` (N m) and the RMS torque
    /// errors `train_rms` and `validation_rms` (N m; NaN for a locked joint or nothing held out).
    #[pyo3(signature = (backend = "pandas"))]
    fn joints<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        let r = &self.report;
        let n = self.model.dof();
        let cols = PyDict::new(py);
        let names: Vec<String> = self.model.joint_names();
        cols.set_item("joint", names)?;
        cols.set_item("viscous", r.identified.viscous.clone())?;
        cols.set_item("coulomb", r.identified.coulomb.clone())?;
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
        let sidecar = physid::io::sidecar_path(&path);
        let mut inputs: Vec<PathBuf> = self.inputs.clone();
        inputs.extend(physid::io::robot_files(&self.source, &[]));
        let refs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
        physid::io::check_outputs(&[&path, &sidecar], &refs).map_err(value_error)?;
        let notices = self
            .report
            .write_urdf(&path, &self.source, &self.model)
            .map_err(value_error)?;
        warn(py, &notices)
    }

    /// Writes the identified model as MJCF for MuJoCo (rotors as joint armature), never over
    /// an input.
    fn write_mjcf(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let identified = self.report.model(&self.model).map_err(api_error)?;
        let mut inputs: Vec<PathBuf> = self.inputs.clone();
        inputs.extend(physid::io::robot_files(&self.source, &[]));
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

/// The pandas module, or an ImportError that says how to get it.
/// The DataFrame library a table is returned in: `"pandas"` (the default) or `"polars"`.
fn frames<'py>(py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyModule>> {
    let extra = match backend {
        "pandas" => "the package's extra 'tables'",
        "polars" => "the package's extra 'polars'",
        other => {
            return Err(value_error(format!(
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
fn frame<'py>(
    py: Python<'py>,
    data: Bound<'py, PyAny>,
    backend: &str,
) -> PyResult<Bound<'py, PyAny>> {
    frames(py, backend)?.getattr("DataFrame")?.call1((data,))
}

/// Identifies `robot` from data files as `physid identify` does, its flags as keyword
/// arguments: `data` (a path or list: CSV, MCAP, rosbag2), `validate_data`, `train` and
/// `validate` (`"a:b"`, `(a, b)` or `range(a, b)`), `constraints`, `friction`, `effects`,
/// `effects_from`, `prior_weight`, `eps`, `regularizer`, `topic`, `stamp`, `cutoff`, `lock`,
/// `only`, `allow_few_samples`, `mass_bounds` (`(lo, hi)`: each body's mass within lo..hi times
/// the description's, `0 <= lo <= 1 <= hi`), `total_mass` (`(lo, hi)` kg: the robot's moving
/// mass, links and rotors). Warnings are raised as `physid.PhysidWarning`;
/// the GIL is released while it runs.
#[pyfunction]
#[pyo3(signature = (robot, data, *, validate_data = None, train = None, validate = None,
    constraints = None, friction = None, effects = None, effects_from = None,
    prior_weight = 1e-6, eps = 1e-6, regularizer = "euclidean", topic = None, stamp = "log",
    cutoff = None, lock = None, only = None, allow_few_samples = false, mass_bounds = None,
    total_mass = None))]
#[allow(clippy::too_many_arguments)]
fn identify<'py>(
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
    let mut o = IdentifyOptions::new(paths("data", Some(data))?);
    o.validate_data = paths("validate_data", validate_data)?;
    o.train = sample_range("--train", train)?;
    o.validate = sample_range("--validate", validate)?;
    set_model_options(&mut o, m, constraints, (friction, effects), &effects_from)?;
    o.prior_weight = prior_weight;
    o.eps = eps;
    o.regularizer = regularizer
        .parse()
        .map_err(|e| value_error(format!("--regularizer: {e}")))?;
    o.read = read_options(topic, stamp, cutoff, lock, only)?;
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

/// `identify`'s model keywords onto `o`: the constraint set, the friction and effect terms
/// (`(friction, effects)`), and the effects confirmed in a diagnosis report (`effects_from`).
fn set_model_options(
    o: &mut IdentifyOptions,
    m: &physid::model::Model,
    constraints: Option<&str>,
    (friction, effects): (Option<&Bound<'_, PyAny>>, Option<&Bound<'_, PyAny>>),
    effects_from: &Option<PathBuf>,
) -> PyResult<()> {
    o.constraints = constraints
        .map(str::parse)
        .transpose()
        .map_err(|e| value_error(format!("--constraints: {e}")))?;
    let friction = match friction {
        Some(f) => names(Some(f))?,
        None => vec!["viscous".into(), "coulomb".into()],
    };
    o.terms = api::identify::parse_terms(&friction, &names(effects)?).map_err(value_error)?;
    if let Some(p) = effects_from {
        o.terms
            .extend(api::identify::confirmed_effects(p, m).map_err(value_error)?);
    }
    Ok(())
}

/// A diagnosis of the gap between a robot description and its runs (`physid diagnose`):
/// `to_dict()` is its `--json`; in a notebook it shows itself as the HTML report, plots inline.
#[pyclass(frozen, module = "physid")]
struct Diagnosis {
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
        self.notices.iter().map(|n| n.to_string()).collect()
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
        let plots = physid::diagnose::report::plots(&self.diagnosis).map_err(value_error)?;
        Ok(physid::diagnose::report::html(&self.diagnosis, &plots))
    }

    fn _repr_html_(&self) -> PyResult<String> {
        self.html()
    }

    /// Writes the report folder (`report.html`, `report.md`, `report.json`, SVG plots), as
    /// `physid diagnose --report`; never into a folder that is or holds an input.
    fn write_report(&self, path: PathBuf) -> PyResult<()> {
        physid::io::check_result_dir(&path, &self.inputs).map_err(value_error)?;
        physid::diagnose::report::write(&path, &self.diagnosis).map_err(value_error)
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
fn diagnose<'py>(
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
            .map_err(|e| value_error(format!("--constraints: {e}")))?,
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

/// A trajectory's signals as a dict of numpy arrays: `t` (s), and `q`, `qd`, `qdd`, `tau` as
/// `(samples, n)` (`qdd` absent when unknown).
fn trajectory_dict<'py>(py: Python<'py>, tr: &Trajectory) -> PyResult<Bound<'py, PyDict>> {
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

/// A simulated excitation experiment (`physid simulate`), its log written: `to_dict()` is its
/// `--json`; the signals as numpy arrays.
#[pyclass(frozen, module = "physid")]
struct Simulation {
    run: api::simulate::Simulation,
    out: PathBuf,
}

#[pymethods]
impl Simulation {
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

/// A worker pool of `threads` threads (none or 0: all cores), never more than the machine's
/// cores. Results do not depend on it.
fn thread_pool(threads: Option<usize>) -> PyResult<rayon::ThreadPool> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let workers = threads.filter(|&t| t > 0).unwrap_or(cores).min(cores);
    rayon::ThreadPoolBuilder::new()
        .num_threads(workers)
        .thread_name(|i| format!("physid-rayon-{i}"))
        .build()
        .map_err(value_error)
}

/// A designed excitation (`physid excite`): the design, the scenario that runs it, its check
/// in simulation against the robot's limits.
#[pyclass(frozen, module = "physid")]
struct Excitation {
    inner: api::excite::Excitation,
    out: Option<PathBuf>,
    notices: Vec<Notice>,
}

#[pymethods]
impl Excitation {
    /// The scenario's text (TOML): the base's tables as they were, the design as its
    /// `[excitation]`; `physid.simulate` and `physid.experiment` run it once written.
    #[getter]
    fn scenario(&self) -> &str {
        &self.inner.scenario
    }

    /// Every simulated peak inside the robot's limits (`None`: not checked).
    #[getter]
    fn within_limits(&self) -> Option<bool> {
        self.inner.within_limits()
    }

    /// The scenario file written (`None`: none asked for, or the check failed).
    #[getter]
    fn written(&self) -> Option<PathBuf> {
        self.inner.written.clone()
    }

    /// The design's objective value (`log det F / r` for d-optimal), its condition number,
    /// and how many parameter combinations it makes identifiable, as a dict.
    #[getter]
    fn design<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        plain(py, &self.inner.design)
    }

    /// Notes and warnings (the loader's, rate limits defaulted), also raised as
    /// `PhysidWarning`s.
    #[getter]
    fn notices(&self) -> Vec<String> {
        self.notices.iter().map(|n| n.text.clone()).collect()
    }

    /// The designed reference trajectory at `rate` Hz (default 1000) over the run: `t` (s),
    /// `q`, `qd`, `qdd` (`(samples, n)`, rad, rad/s, rad/s²; `tau` zero), to send to a
    /// controller.
    #[pyo3(signature = (rate = 1000.0))]
    fn reference<'py>(&self, py: Python<'py>, rate: f64) -> PyResult<Bound<'py, PyDict>> {
        if !(rate.is_finite() && rate > 0.0 && rate <= 1e5) {
            return Err(value_error(format!(
                "--rate must be a sample rate in (0, 100000] Hz, got {rate}"
            )));
        }
        let e = &self.inner;
        let tr =
            api::excite::reference_trajectory(&e.model, &e.design.series, e.options.duration, rate);
        trajectory_dict(py, &tr)
    }

    /// Per joint, the limits as the simulated robot used them (peak over the run / its own
    /// limit) as a pandas DataFrame; empty when not checked.
    #[pyo3(signature = (backend = "pandas"))]
    fn limits<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        let rows: Vec<&api::excite::SimulatedUse> = self
            .inner
            .check
            .iter()
            .flat_map(|c| c.joints.iter())
            .collect();
        frame(py, plain(py, &rows)?, backend)
    }

    /// The report as `physid excite --json` prints it.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, "excite", &self.inner.json(self.out.clone()))
    }

    fn __repr__(&self) -> String {
        format!(
            "Excitation({} harmonics at {} Hz, {} = {:.4}, within limits: {}{})",
            self.inner.options.harmonics,
            self.inner.options.base_frequency,
            physid::io::serde_name(&self.inner.design.objective),
            self.inner.design.value,
            self.inner
                .within_limits()
                .map_or("not checked".to_string(), |w| w.to_string()),
            self.inner
                .written
                .as_ref()
                .map_or(String::new(), |p| format!(", written to {}", p.display()))
        )
    }
}

/// The design's objective from its CLI spelling.
fn objective(name: &str) -> PyResult<physid::sim::design::Objective> {
    use physid::sim::design::Objective;
    match name {
        "d-optimal" => Ok(Objective::DOptimal),
        "e-optimal" => Ok(Objective::EOptimal),
        "condition" => Ok(Objective::Condition),
        other => Err(value_error(format!(
            "--objective: '{other}' is not one of d-optimal, e-optimal, condition"
        ))),
    }
}

/// Where a design starts: exactly one of a robot and a base scenario.
fn excite_from(
    robot: Option<&Bound<'_, PyAny>>,
    scenario: Option<PathBuf>,
) -> PyResult<api::excite::ExciteFrom> {
    use api::excite::ExciteFrom;
    match (robot, scenario) {
        (Some(_), Some(_)) => Err(value_error(
            "give a robot or a base scenario, not both (the scenario names its robot)",
        )),
        (None, Some(s)) => Ok(ExciteFrom::Scenario(s)),
        (Some(r), None) => {
            if let Ok(robot) = r.downcast::<Robot>() {
                // The written scenario names the robot's file, so the design must be for what
                // that file gives.
                let robot = robot.get();
                if !robot.as_file {
                    return Err(value_error(format!(
                        "excite designs for a robot file as a scenario names it: this Robot ('{}') was loaded with rotor options or comes from a simulation; give its file (or a Robot loaded without options)",
                        robot.source
                    )));
                }
                return Ok(ExciteFrom::Robot(robot.source.clone()));
            }
            Ok(ExciteFrom::Robot(
                r.extract::<PathBuf>()?.to_string_lossy().into_owned(),
            ))
        }
        (None, None) => Err(value_error("give a robot (or scenario=, a base scenario)")),
    }
}

/// Designs a Fourier excitation that carries the most information about `robot`'s
/// identifiable parameters within its limits (`physid excite`): `robot` is `"cheetah3"`, a
/// URDF or robot TOML path, or a `Robot`; or `scenario` a base scenario whose robot,
/// simulation, sensors and processing are kept. Keywords are the CLI's flags. The design is
/// simulated to check the robot's limits (`check=False` skips it); the scenario (`out`) and
/// the reference trajectory (`csv`, `mcap`) are written only when it stays within them, never
/// over an input. Ctrl-C stops it: nothing is written after the interrupt.
#[pyfunction]
#[pyo3(signature = (robot = None, *, scenario = None, duration = 20.0, harmonics = 5,
    base_frequency = 0.5, objective = "d-optimal", seed = 1, iterations = 1000, starts = 4,
    margin = 0.15, max_acceleration = None, max_jerk = None, ramp = None, samples = 200,
    rate = 1000.0, out = None, csv = None, mcap = None, check = true, threads = None))]
#[allow(clippy::too_many_arguments)]
fn excite(
    py: Python<'_>,
    robot: Option<&Bound<'_, PyAny>>,
    scenario: Option<PathBuf>,
    duration: f64,
    harmonics: usize,
    base_frequency: f64,
    objective: &str,
    seed: u64,
    iterations: usize,
    starts: usize,
    margin: f64,
    max_acceleration: Option<Vec<f64>>,
    max_jerk: Option<Vec<f64>>,
    ramp: Option<f64>,
    samples: usize,
    rate: f64,
    out: Option<PathBuf>,
    csv: Option<PathBuf>,
    mcap: Option<PathBuf>,
    check: bool,
    threads: Option<usize>,
) -> PyResult<Excitation> {
    let opts = api::excite::ExciteOptions {
        from: excite_from(robot, scenario)?,
        duration,
        harmonics,
        base_frequency,
        objective: self::objective(objective)?,
        seed,
        iterations,
        starts,
        margin,
        max_acceleration,
        max_jerk,
        ramp,
        samples,
        rate,
        out: out.clone(),
        csv,
        mcap,
        check,
    };
    let pool = thread_pool(threads)?;
    let (result, notices) = cancellable(py, move |cancel| {
        let mut notices = vec![];
        let stop = || is_cancelled(&cancel);
        let result =
            pool.install(|| api::excite::excite_until(&opts, &mut |n| notices.push(n), &stop));
        (result, notices)
    })?;
    warn(py, &notices)?;
    Ok(Excitation {
        inner: result.map_err(api_error)?,
        out,
        notices,
    })
}

/// Scores the motion a scenario already has (`physid excite --score`): its own excitation
/// simulated for `duration` s and the information of its true states under the design's
/// weighting (`objective`, `margin` and the Fourier keywords as for `excite`). Returns a dict
/// equal to `excite --score --json`: `d_optimal` (log det F / r), `e_optimal` (log λ_min(F)),
/// `condition` (κ(F)), `samples`. Ctrl-C interrupts it.
#[pyfunction]
#[pyo3(signature = (scenario, *, duration = 20.0, harmonics = 5, base_frequency = 0.5,
    objective = "d-optimal", margin = 0.15, samples = 200, rate = 1000.0, threads = None))]
#[allow(clippy::too_many_arguments)]
fn score_motion<'py>(
    py: Python<'py>,
    scenario: PathBuf,
    duration: f64,
    harmonics: usize,
    base_frequency: f64,
    objective: &str,
    margin: f64,
    samples: usize,
    rate: f64,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let opts = api::excite::ExciteOptions {
        from: api::excite::ExciteFrom::Scenario(scenario),
        duration,
        harmonics,
        base_frequency,
        objective: self::objective(objective)?,
        margin,
        samples,
        rate,
        check: false,
        ..api::excite::ExciteOptions::default()
    };
    let pool = thread_pool(threads)?;
    let (result, notices) = interruptible(py, move || {
        let mut notices = vec![];
        let result = pool.install(|| api::excite::score_motion(&opts, &mut |n| notices.push(n)));
        (result, notices)
    })?;
    warn(py, &notices)?;
    let s = result.map_err(api_error)?;
    let out = PyDict::new(py);
    out.set_item("d_optimal", s.d_optimal)?;
    out.set_item("e_optimal", s.e_optimal)?;
    out.set_item("condition", s.condition)?;
    out.set_item("samples", s.samples)?;
    Ok(out)
}

/// Simulates a scenario's excitation experiment and logs it to MCAP at `out` (and the
/// processed samples as CSV at `csv`), as `physid simulate` does: `engine` (`"physid"` or
/// `"rapier"`), `duration` (s) and `seed` override the scenario's. `progress`, if given, is
/// called with the fraction done (0 to 1, at most every percent), e.g. to drive a tqdm bar.
/// Outputs never replace an input (the scenario, its robot's files). Ctrl-C stops the run (within a percent of it) and nothing is written.
#[pyfunction]
#[pyo3(signature = (scenario, out, *, csv = None, engine = None, duration = None, seed = None,
    progress = None))]
#[allow(clippy::too_many_arguments)]
fn simulate(
    py: Python<'_>,
    scenario: PathBuf,
    out: PathBuf,
    csv: Option<PathBuf>,
    engine: Option<&str>,
    duration: Option<f64>,
    seed: Option<u64>,
    progress: Option<PyObject>,
) -> PyResult<Simulation> {
    let engine = engine_of(engine)?;
    let files = physid::io::scenario_files(&scenario);
    let inputs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let outputs: Vec<&Path> = std::iter::once(out.as_path())
        .chain(csv.as_deref())
        .collect();
    physid::io::check_outputs(&outputs, &inputs).map_err(value_error)?;
    let opts = api::simulate::SimulateOptions {
        engine,
        duration,
        seed,
    };
    let (path, log, table) = (scenario.clone(), out.clone(), csv.clone());
    let (result, callback_error) = cancellable(py, move |cancel| {
        let stop = || is_cancelled(&cancel);
        let mut shown = -1.0;
        let mut failed: Option<PyErr> = None;
        let mut report = |f: f64| {
            let Some(cb) = &progress else { return };
            if failed.is_some() || (f - shown < 0.01 && f < 1.0) {
                return;
            }
            shown = f;
            if let Err(e) = Python::with_gil(|py| cb.call1(py, (f,)).map(|_| ())) {
                failed = Some(e);
            }
        };
        let run = api::simulate::simulate_until(&path, &opts, &mut report, &stop).and_then(|run| {
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
        });
        (run, failed)
    })?;
    if let Some(e) = callback_error {
        return Err(e);
    }
    let run = result.map_err(api_error)?;
    Ok(Simulation { run, out })
}

/// `simulate`'s `engine` keyword (`None`: the scenario's own).
fn engine_of(engine: Option<&str>) -> PyResult<Option<physid::sim::scenario::Engine>> {
    match engine {
        None => Ok(None),
        Some("physid") => Ok(Some(physid::sim::scenario::Engine::Physid)),
        Some("rapier") => Ok(Some(physid::sim::scenario::Engine::Rapier)),
        Some(other) => Err(value_error(format!(
            "--engine: '{other}' is not one of physid, rapier"
        ))),
    }
}

/// A table written by the library as CSV text (or why it could not be made), read back as a
/// DataFrame of `backend`: the columns of the CLI's CSV.
fn table_of<'py>(
    py: Python<'py>,
    csv: Result<String, String>,
    backend: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let text = csv.map_err(value_error)?;
    let module = frames(py, backend)?;
    let buffer = py
        .import("io")?
        .getattr("BytesIO")?
        .call1((PyBytes::new(py, text.as_bytes()),))?;
    module.getattr("read_csv")?.call1((buffer,))
}

/// The sample-size experiment of a scenario (`physid experiment`): every (seed, n_s,
/// constraint set) cell; `rows()` and `summary()` are the CLI's `rows.csv` and `summary.csv`
/// as pandas DataFrames.
#[pyclass(frozen, module = "physid")]
struct Experiment {
    rows: Vec<physid::experiment::Row>,
    joints: Vec<String>,
    bodies: Vec<String>,
    sets: Vec<String>,
    seconds: f64,
}

impl Experiment {
    /// The long table (or, with `summary`, its summary over seeds) as CSV text.
    fn csv(&self, summary: bool) -> Result<String, String> {
        use physid::experiment::tables;
        let long = tables::long_table_with_bodies(&self.rows, &self.joints, &self.bodies)
            .map_err(|e| e.to_string())?;
        let mut table = if summary {
            tables::summary(&long).map_err(|e| e.to_string())?
        } else {
            long
        };
        tables::csv_text(&mut table).map_err(|e| e.to_string())
    }
}

#[pymethods]
impl Experiment {
    /// One row per (seed, n_s, constraint set): validation and training RMS (N m), parameter
    /// errors against the truth, consistency, solver status and time (the CLI's rows.csv).
    #[pyo3(signature = (backend = "pandas"))]
    fn rows<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        table_of(py, self.csv(false), backend)
    }

    /// Median and quartiles over seeds per n_s × constraint set (the CLI's summary.csv).
    #[pyo3(signature = (backend = "pandas"))]
    fn summary<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        table_of(py, self.csv(true), backend)
    }

    /// The constraint sets compared, loosest first.
    #[getter]
    fn constraints(&self) -> Vec<String> {
        self.sets.clone()
    }

    /// Wall time of the run (s).
    #[getter]
    fn seconds(&self) -> f64 {
        self.seconds
    }

    fn __repr__(&self) -> String {
        format!(
            "Experiment({} cells, constraint sets {}, {:.1} s)",
            self.rows.len(),
            self.sets.join(", "),
            self.seconds
        )
    }
}

/// Runs the sample-size experiment of a scenario file (its `[experiment]` table) as
/// `physid experiment` does, seeds in parallel on `threads` workers (default: all cores; the
/// results do not depend on it); `seeds` overrides the scenario's count. `progress`, if given,
/// is called with (seeds done, seeds). Ctrl-C interrupts it.
#[pyfunction]
#[pyo3(signature = (scenario, *, seeds = None, threads = None, progress = None))]
fn experiment(
    py: Python<'_>,
    scenario: PathBuf,
    seeds: Option<usize>,
    threads: Option<usize>,
    progress: Option<PyObject>,
) -> PyResult<Experiment> {
    let shown = scenario.display().to_string();
    let (sc, model, _) = physid::sim::scenario::load(&scenario).map_err(value_error)?;
    let mut spec = physid::experiment::ExperimentSpec::from_scenario(&sc)
        .map_err(|e| value_error(format!("{shown}: [experiment]: {e}")))?;
    if let Some(n) = seeds {
        spec.seeds = n;
    }
    spec.validate()
        .map_err(|e| value_error(format!("{shown}: {e}")))?;
    if !spec.excitations.is_empty() {
        return Err(value_error(format!(
            "{shown}: an experiment over several excitation motions ([[experiment.excitations]]) is not in the Python package yet: run `physid experiment {shown}`"
        )));
    }
    let pool = thread_pool(threads)?;
    let (joints, bodies) = (
        model.joint_names(),
        physid::ident::bodies(&model)
            .into_iter()
            .map(|(n, _, _)| n)
            .collect(),
    );
    let sets = spec
        .constraints
        .iter()
        .map(|s| s.name().to_string())
        .collect();
    let start = std::time::Instant::now();
    let (rows, failed) = interruptible(py, move || {
        let failed: std::sync::Mutex<Option<PyErr>> = std::sync::Mutex::new(None);
        let report = |done: usize, total: usize| {
            let Some(cb) = &progress else { return };
            if let Err(e) = Python::with_gil(|py| cb.call1(py, (done, total)).map(|_| ())) {
                if let Ok(mut f) = failed.lock() {
                    f.get_or_insert(e);
                }
            }
        };
        let rows = pool.install(|| physid::experiment::run(&model, &sc, &spec, &report));
        (rows, failed.into_inner().ok().flatten())
    })?;
    if let Some(e) = failed {
        return Err(e);
    }
    let rows = rows.map_err(|e| value_error(format!("running the experiment of {shown}: {e}")))?;
    Ok(Experiment {
        rows,
        joints,
        bodies,
        sets,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// A parameter sweep's result (`physid sweep`): its folder, what ran, and once every cell is
/// there the merged tables (`rows()`, `summary()` as pandas DataFrames, `markdown`).
#[pyclass(frozen, module = "physid")]
struct Sweep {
    out: PathBuf,
    cells: usize,
    mine: usize,
    ran: usize,
    missing: usize,
    stale: usize,
    tables: Option<(String, String, String)>,
}

#[pymethods]
impl Sweep {
    /// The result folder (cells/, and once merged rows.csv, summary.csv/.md/.svg).
    #[getter]
    fn out(&self) -> PathBuf {
        self.out.clone()
    }

    /// Cells of the whole grid, of this shard, run by this call, and still missing (other
    /// shards), as a dict; `stale`: cell files of another configuration, not used.
    #[getter]
    fn cells<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("total", self.cells)?;
        d.set_item("shard", self.mine)?;
        d.set_item("ran", self.ran)?;
        d.set_item("missing", self.missing)?;
        d.set_item("stale", self.stale)?;
        Ok(d)
    }

    /// Every cell is there and the tables are merged.
    #[getter]
    fn merged(&self) -> bool {
        self.tables.is_some()
    }

    /// One row per (grid point, seed, n_s, constraint set): the CLI's rows.csv.
    #[pyo3(signature = (backend = "pandas"))]
    fn rows<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        table_of(py, self.table(0), backend)
    }

    /// Medians and quartiles over seeds per (grid point, n_s, set): summary.csv.
    #[pyo3(signature = (backend = "pandas"))]
    fn summary<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        table_of(py, self.table(1), backend)
    }

    /// summary.md.
    #[getter]
    fn markdown(&self) -> PyResult<String> {
        self.table(2).map_err(value_error)
    }

    fn __repr__(&self) -> String {
        format!(
            "Sweep('{}', {} cells, {} run now, {})",
            self.out.display(),
            self.cells,
            self.ran,
            if self.tables.is_some() {
                "merged".to_string()
            } else {
                format!("{} missing (other shards)", self.missing)
            }
        )
    }
}

impl Sweep {
    fn table(&self, k: usize) -> Result<String, String> {
        let (rows, summary, md) = self.tables.as_ref().ok_or_else(|| {
            format!(
                "{} of {} cells are still missing (other shards): run them, then sweep again without shard to merge",
                self.missing, self.cells
            )
        })?;
        Ok([rows, summary, md][k].clone())
    }
}

/// Runs a parameter sweep (`physid sweep`, docs/sweeps.md): a grid over scenario keys crossed
/// with the constraint sets, written to `out` (default `results/<sweep name>`), resumable
/// (finished cells are skipped) and shardable (`shard=(k, n)`: the cells with index ≡ k mod
/// n); merged once every cell is there. `progress(done, total)` is called after each cell.
/// Ctrl-C stops it: the cells finished stay, none is written after the interrupt and nothing is merged.
#[pyfunction]
#[pyo3(signature = (sweep, *, out = None, shard = None, threads = None, progress = None))]
fn sweep(
    py: Python<'_>,
    sweep: PathBuf,
    out: Option<PathBuf>,
    shard: Option<(usize, usize)>,
    threads: Option<usize>,
    progress: Option<PyObject>,
) -> PyResult<Sweep> {
    let opts = api::sweep::SweepOptions { sweep, out, shard };
    let pool = thread_pool(threads)?;
    let (result, failed) = cancellable(py, move |cancel| {
        let stop = || is_cancelled(&cancel);
        let failed: std::sync::Mutex<Option<PyErr>> = std::sync::Mutex::new(None);
        let result = api::sweep::plan(&opts).and_then(|plan| {
            let done = std::sync::atomic::AtomicUsize::new(0);
            let total = plan.todo.len();
            let report = || {
                let k = done.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
                let Some(cb) = &progress else { return };
                if let Err(e) = Python::with_gil(|py| cb.call1(py, (k, total)).map(|_| ())) {
                    if let Ok(mut f) = failed.lock() {
                        f.get_or_insert(e);
                    }
                }
            };
            pool.install(|| plan.run_until(&report, &stop))?;
            if stop() {
                return Err(api::ApiError::Cancelled);
            }
            let merged = plan.merge()?;
            Ok((plan, merged))
        });
        (result, failed.into_inner().ok().flatten())
    })?;
    if let Some(e) = failed {
        return Err(e);
    }
    let (plan, merged) = result.map_err(api_error)?;
    let tables = match merged {
        None => None,
        Some(mut m) => {
            let csv = |df: &mut polars::prelude::DataFrame| {
                physid::experiment::tables::csv_text(df).map_err(value_error)
            };
            Some((csv(&mut m.rows)?, csv(&mut m.summary)?, m.markdown))
        }
    };
    Ok(Sweep {
        out: plan.out.clone(),
        cells: plan.cells.len(),
        mine: plan.mine.len(),
        ran: plan.todo.len(),
        missing: plan.missing(),
        stale: plan.stale,
        tables,
    })
}

/// A comparison of experiment or sweep results (`physid compare`): per group (grid point, n_s,
/// constraint set) the paired seeds' medians, ratio, one-sided p-value and outcome.
#[pyclass(frozen, module = "physid")]
struct Comparison {
    cmp: physid::experiment::compare::Comparison,
}

#[pymethods]
impl Comparison {
    /// Groups that regressed.
    #[getter]
    fn regressions(&self) -> usize {
        self.cmp.regressions()
    }

    /// Groups with too few seed pairs to be judged.
    #[getter]
    fn too_few(&self) -> usize {
        self.cmp.too_few()
    }

    /// Every group as a pandas DataFrame: point, n_s, set, pairs, reference_median,
    /// candidate_median, median_ratio, p_value, outcome.
    #[pyo3(signature = (backend = "pandas"))]
    fn groups<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        frame(py, plain(py, &self.cmp.groups)?, backend)
    }

    /// The comparison as `physid compare` prints it (Markdown).
    fn markdown(&self) -> String {
        self.cmp.markdown()
    }

    /// The comparison as a JUnit XML report (`physid compare --junit`).
    fn junit(&self) -> String {
        self.cmp.junit()
    }

    /// The comparison as a dict (title, metric, tolerance, alpha, groups).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        plain(py, &self.cmp)
    }

    fn __repr__(&self) -> String {
        format!(
            "Comparison('{}', {} groups, {} regressions, {} with too few pairs)",
            self.cmp.title,
            self.cmp.groups.len(),
            self.cmp.regressions(),
            self.cmp.too_few()
        )
    }
}

/// Compares experiment or sweep results as `physid compare` does: `result` (a results folder)
/// against `baseline` (another), or two constraint sets within it with `variant="A<=B"` ("A is
/// no worse than B"); `metric`, `tolerance`, `alpha`, `min_pairs`, `allow_too_few`, `max_n_s` as
/// its flags (defaults: val_rms, 0.05, 0.01, 6).
#[pyfunction]
#[pyo3(signature = (result, *, baseline = None, variant = None, metric = None, tolerance = None,
    alpha = None, min_pairs = None, allow_too_few = false, max_n_s = None))]
#[allow(clippy::too_many_arguments)]
fn compare(
    py: Python<'_>,
    result: PathBuf,
    baseline: Option<PathBuf>,
    variant: Option<String>,
    metric: Option<String>,
    tolerance: Option<f64>,
    alpha: Option<f64>,
    min_pairs: Option<usize>,
    allow_too_few: bool,
    max_n_s: Option<u64>,
) -> PyResult<Comparison> {
    use physid::experiment::compare::{self, CompareOptions};
    let d = CompareOptions::default();
    let opts = CompareOptions {
        metric: metric.unwrap_or(d.metric),
        tolerance: tolerance.unwrap_or(d.tolerance),
        alpha: alpha.unwrap_or(d.alpha),
        min_pairs: min_pairs.unwrap_or(d.min_pairs),
        allow_too_few,
        max_n_s,
    };
    opts.validate().map_err(api_error)?;
    let cmp = match (&baseline, &variant) {
        (Some(_), Some(_)) => {
            return Err(value_error("give baseline or variant, not both"));
        }
        (Some(b), None) => py
            .allow_threads(|| compare::against_baseline(&result, b, &opts))
            .map_err(api_error)?,
        (None, Some(v)) => {
            let Some((better, reference)) = v.split_once("<=") else {
                return Err(value_error(format!(
                    "--variant '{v}': give two constraint sets as A<=B, e.g. ellipsoid<=consistent"
                )));
            };
            py.allow_threads(|| compare::variants(&result, better.trim(), reference.trim(), &opts))
                .map_err(api_error)?
        }
        (None, None) => return Err(value_error("give baseline=DIR or variant=\"A<=B\"")),
    };
    Ok(Comparison { cmp })
}

/// physid's version.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
fn _physid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The library's parallel loops (the normal equations' chunks) run on rayon's global pool.
    // Named here: threads spawned from a call's worker would otherwise inherit its name
    // ("physid") and look like abandoned workers. An error means a pool already exists.
    let _ = rayon::ThreadPoolBuilder::new()
        .thread_name(|i| format!("physid-rayon-{i}"))
        .build_global();
    m.add_class::<Robot>()?;
    m.add_class::<Identification>()?;
    m.add_class::<Diagnosis>()?;
    m.add_class::<Simulation>()?;
    m.add_class::<Experiment>()?;
    m.add_class::<Comparison>()?;
    m.add_class::<Excitation>()?;
    m.add_class::<Sweep>()?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add_function(wrap_pyfunction!(excite, m)?)?;
    m.add_function(wrap_pyfunction!(score_motion, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(experiment, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(identify_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(identify, m)?)?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    Ok(())
}
