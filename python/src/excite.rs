//! `physid.excite` and `physid.score_motion` (`physid excite`).

use crate::convert::*;
use crate::errors::*;
use crate::robot::Robot;
use crate::work::*;
use physid::api;
use physid::api::data::Notice;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// A designed excitation (`physid excite`): the design, the scenario that runs it, its check
/// in simulation against the robot's limits.
#[pyclass(frozen, module = "physid")]
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct Excitation {
    inner: api::excite::Excitation,
    out: Option<PathBuf>,
    notices: Vec<Notice>,
}

#[pymethods]
impl Excitation {
    /// Pickles (and copies) as its state in physid's binary form.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<crate::pickle::Reduced<'py>> {
        crate::pickle::reduce(py, "Excitation", self)
    }

    /// The notebook's view: the design's objective and identifiability, and per joint the
    /// simulated peaks against the robot's limits.
    fn _repr_html_(&self) -> String {
        use crate::notebook::{card, number, table};
        let e = &self.inner;
        let rows: Vec<Vec<String>> = (e.check.iter().flat_map(|c| c.joints.iter()))
            .map(|u| {
                vec![
                    u.joint.clone(),
                    format!("{} … {}", number(u.q_range[0]), number(u.q_range[1])),
                    number(u.velocity),
                    number(u.acceleration),
                    number(u.torque),
                    if u.within { "yes" } else { "no" }.into(),
                ]
            })
            .collect();
        let header = [
            "joint",
            "q range (rad)",
            "speed/limit",
            "acceleration (rad/s²)",
            "torque/limit",
            "within",
        ];
        let within = e
            .within_limits()
            .map_or("not checked".into(), |w| w.to_string());
        let objective = api::files::serde_name(&e.design.objective);
        card(
            "Excitation design",
            &[
                ("harmonics", e.options.harmonics.to_string()),
                (
                    "base frequency",
                    format!("{} Hz", number(e.options.base_frequency)),
                ),
                (objective.as_str(), number(e.design.value)),
                (
                    "identifiable",
                    format!("{} of {}", e.design.identifiable, e.design.parameters),
                ),
                ("within limits", within),
            ],
            &[("simulated use of the limits", table(&header, &rows))],
        )
    }

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
        notice_texts(&self.notices)
    }

    /// The designed reference trajectory at `rate` Hz (default 1000) over the run: `t` (s),
    /// `q`, `qd`, `qdd` (`(samples, n)`, rad, rad/s, rad/s²; `tau` zero), to send to a
    /// controller.
    #[pyo3(signature = (rate = 1000.0))]
    fn reference<'py>(&self, py: Python<'py>, rate: f64) -> PyResult<Bound<'py, PyDict>> {
        if !(rate.is_finite() && rate > 0.0 && rate <= 1e5) {
            return Err(exception(format!(
                "--rate must be a sample rate in (0, 100000] Hz, got {rate}"
            )));
        }
        let e = &self.inner;
        let tr =
            api::excite::reference_trajectory(&e.model, &e.design.series, e.options.duration, rate);
        trajectory_dict(py, &tr)
    }

    /// Per joint, how the simulated run used the robot's limits (a pandas DataFrame; no rows
    /// when not checked): `joint`, `q_min` and `q_max` (the angles reached, rad), `q_lower` and
    /// `q_upper` (the position limits, rad; NaN: none), `velocity` and `torque` (peak over the
    /// run divided by the joint's limit: within it below 1), `acceleration` (peak in the
    /// motion's band, rad/s²: the true acceleration low-passed at 5 times the highest
    /// harmonic), `within` (every peak inside its limit).
    #[pyo3(signature = (backend = "pandas"))]
    fn limits<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        let rows = pyo3::types::PyList::empty(py);
        for u in self.inner.check.iter().flat_map(|c| c.joints.iter()) {
            let row = PyDict::new(py);
            row.set_item("joint", &u.joint)?;
            row.set_item("q_min", u.q_range[0])?;
            row.set_item("q_max", u.q_range[1])?;
            row.set_item("q_lower", u.q_limits[0])?;
            row.set_item("q_upper", u.q_limits[1])?;
            row.set_item("velocity", u.velocity)?;
            row.set_item("acceleration", u.acceleration)?;
            row.set_item("torque", u.torque)?;
            row.set_item("within", u.within)?;
            rows.append(row)?;
        }
        let columns = [
            "joint",
            "q_min",
            "q_max",
            "q_lower",
            "q_upper",
            "velocity",
            "acceleration",
            "torque",
            "within",
        ];
        records(py, rows.into_any(), &columns, backend)
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
            api::files::serde_name(&self.inner.design.objective),
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
pub(crate) fn objective(name: &str) -> PyResult<api::excite::Objective> {
    use api::excite::Objective;
    match name {
        "d-optimal" => Ok(Objective::DOptimal),
        "e-optimal" => Ok(Objective::EOptimal),
        "condition" => Ok(Objective::Condition),
        other => Err(exception(format!(
            "--objective: '{other}' is not one of d-optimal, e-optimal, condition"
        ))),
    }
}

/// Where a design starts: exactly one of a robot and a base scenario.
pub(crate) fn excite_from(
    robot: Option<&Bound<'_, PyAny>>,
    scenario: Option<PathBuf>,
) -> PyResult<api::excite::ExciteFrom> {
    use api::excite::ExciteFrom;
    match (robot, scenario) {
        (Some(_), Some(_)) => Err(exception(
            "give a robot or a base scenario, not both (the scenario names its robot)",
        )),
        (None, Some(s)) => Ok(ExciteFrom::Scenario(s)),
        (Some(r), None) => {
            if let Ok(robot) = r.downcast::<Robot>() {
                // The written scenario names the robot's file, so the design must be for what
                // that file gives.
                let robot = robot.get();
                if !robot.as_file {
                    return Err(exception(format!(
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
        (None, None) => Err(exception("give a robot (or scenario=, a base scenario)")),
    }
}

/// Designs a Fourier excitation that carries the most information about `robot`'s
/// identifiable parameters within its limits (`physid excite`): `robot` is `"cheetah3"`, a
/// URDF or robot TOML path, or a `Robot`; or `scenario` a base scenario whose robot,
/// simulation, sensors and processing are kept. Keywords are the CLI's flags. The design is
/// simulated to check the robot's limits (`check=False` skips it); the scenario (`out`) and
/// the reference trajectory (`csv`, `mcap`) are written only when it stays within them, never
/// over an input. `progress`, if given, is called with the fraction of the design done (0 to 1).
/// Ctrl-C (or an exception in `progress`) stops it, within one evaluation of the design: nothing
/// is written after it.
#[doc = include_str!("../keywords/excite.txt")]
#[pyfunction]
#[pyo3(signature = (robot = None, *, scenario = None, duration = 20.0, harmonics = 5,
    base_frequency = None, objective = "d-optimal", seed = 1, iterations = 1000, starts = 4,
    margin = 0.15, max_acceleration = None, max_jerk = None, ramp = None, samples = 200,
    rate = 1000.0, out = None, csv = None, mcap = None, check = true, threads = None,
    progress = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn excite(
    py: Python<'_>,
    robot: Option<&Bound<'_, PyAny>>,
    scenario: Option<PathBuf>,
    duration: f64,
    harmonics: usize,
    base_frequency: Option<f64>,
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
    progress: Option<PyObject>,
) -> PyResult<Excitation> {
    let callback = progress;
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
    let (result, notices) = designed(py, opts, pool, callback)?;
    warn_once(py, &notices)?;
    Ok(Excitation {
        inner: result.map_err(api_error)?,
        out,
        notices,
    })
}

/// The design of `opts` on `pool`, off the GIL: its fraction done handed to `callback` on the
/// calling thread (at most every percent, increasing), Ctrl-C or an exception in `callback`
/// stopping it; the result and the notices that arose.
fn designed(
    py: Python<'_>,
    opts: api::excite::ExciteOptions,
    pool: rayon::ThreadPool,
    callback: Option<PyObject>,
) -> PyResult<(Result<api::excite::Excitation, api::ApiError>, Vec<Notice>)> {
    let work = move |cancel: Cancel, progress: Progress<f64>| {
        let mut notices = vec![];
        let stop = || is_cancelled(&cancel);
        // The design's evaluations run on the pool's threads.
        let evaluated = |done: usize, total: usize| {
            if (100 * done) % total < 100 || done == total {
                let _ = progress.send(done as f64 / total as f64);
            }
        };
        let watch = api::excite::Watch {
            evaluated: &evaluated,
            stop: &stop,
        };
        let result =
            pool.install(|| api::excite::excite_until(&opts, &mut |n| notices.push(n), &watch));
        (result, notices)
    };
    let mut shown = 0.0;
    reporting(py, work, |py, f: f64| match &callback {
        Some(cb) if f > shown => {
            shown = f;
            cb.call1(py, (f,)).map(drop)
        }
        _ => Ok(()),
    })
}

/// Scores the motion a scenario already has (`physid excite --score`): its own excitation
/// simulated for `duration` s and the information of its true states under the design's
/// weighting (`objective`, `margin` and the Fourier keywords as for `excite`). Returns a dict
/// equal to `excite --score --json`: `d_optimal` (log det F / r), `e_optimal` (log λ_min(F)),
/// `condition` (κ(F)), `samples`. Ctrl-C interrupts it.
#[doc = include_str!("../keywords/score_motion.txt")]
#[pyfunction]
#[pyo3(signature = (scenario, *, duration = 20.0, harmonics = 5, base_frequency = None,
    objective = "d-optimal", margin = 0.15, samples = 200, rate = 1000.0, threads = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn score_motion<'py>(
    py: Python<'py>,
    scenario: PathBuf,
    duration: f64,
    harmonics: usize,
    base_frequency: Option<f64>,
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
    warn_once(py, &notices)?;
    let s = result.map_err(api_error)?;
    let out = PyDict::new(py);
    out.set_item("d_optimal", s.d_optimal)?;
    out.set_item("e_optimal", s.e_optimal)?;
    out.set_item("condition", s.condition)?;
    out.set_item("samples", s.samples)?;
    Ok(out)
}
