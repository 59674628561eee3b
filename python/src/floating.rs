//! `physid.simulate_floating`, `physid.identify_floating` and `FloatingIdentification`: the
//! whole robot from its logs (`physid simulate-floating`, `physid identify-floating`).

use crate::convert::*;
use crate::errors::*;
use crate::work::*;
use numpy::{IntoPyArray, PyArray1, PyArrayDyn};
use physid::api;
use physid::api::floating::{
    FloatingReadOptions, Foot, IdentifyFloatingOptions, SimulateFloatingOptions, StartOptions,
};
use physid::api::model::RobotOptions;
use pyo3::prelude::*;
use std::path::PathBuf;

/// A floating robot identified from a log; `to_dict()` is `physid identify-floating --json`.
#[pyclass(frozen, module = "physid")]
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct FloatingIdentification {
    found: api::floating::FloatingIdentification,
}

#[pymethods]
impl FloatingIdentification {
    /// Pickles (and copies) as its state in physid's binary form.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<crate::pickle::Reduced<'py>> {
        crate::pickle::reduce(py, "FloatingIdentification", self)
    }

    /// The notebook's view: the fit, the masses, every body's mass and consistency margin.
    fn _repr_html_(&self) -> String {
        use crate::notebook::{card, number, table};
        let f = &self.found;
        let rows: Vec<Vec<String>> = (f.bodies.iter())
            .map(|b| {
                vec![
                    b.name.clone(),
                    number(b.pi[0]),
                    number(b.consistency.min_eig_pseudo),
                ]
            })
            .collect();
        card(
            &format!("Floating robot '{}' identified", f.robot),
            &[
                ("setting", api::files::serde_name(&f.setting)),
                ("constraints", api::files::serde_name(&f.constraints)),
                ("samples used", f.samples_used.to_string()),
                ("residual RMS", number(f.identified_rms)),
                ("total mass (kg)", number(f.identified_mass)),
                ("constraints hold", f.constraints_hold.to_string()),
            ],
            &[("bodies", table(&["body", "m (kg)", "min eig J"], &rows))],
        )
    }

    /// θ: the trunk's ten parameters, the tree's bodies' and rotors', then viscous and Coulomb
    /// friction per joint (the paper's order per body: m, h, I about the body frame's origin).
    #[getter]
    fn theta<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.found.theta.clone().into_pyarray(py)
    }

    /// Whether every constraint of the set holds (checked from the parameters).
    #[getter]
    fn constraints_hold(&self) -> bool {
        self.found.constraints_hold
    }

    /// The whole robot's identified mass (kg).
    #[getter]
    fn mass(&self) -> f64 {
        self.found.identified_mass
    }

    /// The result as `physid identify-floating --json` prints it.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, "identify_floating", &self.found)
    }

    fn __repr__(&self) -> String {
        let f = &self.found;
        format!(
            "FloatingIdentification('{}', {}, {}, {} samples, residual {:.4} from {:.4}, {:.3} kg)",
            f.robot,
            api::files::serde_name(&f.setting),
            api::files::serde_name(&f.constraints),
            f.samples_used,
            f.identified_rms,
            f.description_rms,
            f.identified_mass
        )
    }
}

/// The robot options of the floating functions' `robot` and `no_rotors`.
/// The robot a floating function is given: a [`FloatingRobot`] (as it was loaded: `no_rotors`
/// then belongs to it), a path, or `"cheetah3"` (the default).
fn floating_robot_options(
    robot: Option<&Bound<'_, PyAny>>,
    no_rotors: bool,
) -> PyResult<RobotOptions> {
    let Some(robot) = robot else {
        return Ok(robot_options(PathBuf::from("cheetah3"), no_rotors));
    };
    if let Ok(loaded) = robot.downcast::<FloatingRobot>() {
        if no_rotors {
            return Err(exception(
                "no_rotors: give it when loading the FloatingRobot (FloatingRobot(..., no_rotors=True))",
            ));
        }
        return Ok(loaded.get().options.clone());
    }
    let path: PathBuf = robot.extract().map_err(|_| {
        exception("robot: give a physid.FloatingRobot, \"cheetah3\" or the path of a floating URDF or its sidecar TOML")
    })?;
    Ok(robot_options(path, no_rotors))
}

fn robot_options(robot: PathBuf, no_rotors: bool) -> RobotOptions {
    RobotOptions {
        no_rotors,
        ..RobotOptions::new(&robot.to_string_lossy())
    }
}

/// Simulates the built-in quadruped (or a floating URDF of it) standing and shifting its
/// weight and logs it as its sensors would (CSV at `out`), as `physid simulate-floating` does;
/// `sensors` a dict over the default sensors' fields (`{"force_noise": 5.0, "velocities":
/// True}`), or `"exact"`. Returns the summary `--json` prints.
#[doc = include_str!("../keywords/simulate_floating.txt")]
#[pyfunction]
#[pyo3(signature = (out, *, robot = None, no_rotors = false,
    duration = 10.0, rate = 1000.0, seed = 1, trot = None, still = false, drop = 0.0,
    push = None, ground_friction = None, sensors = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn simulate_floating<'py>(
    py: Python<'py>,
    out: PathBuf,
    robot: Option<&Bound<'py, PyAny>>,
    no_rotors: bool,
    duration: f64,
    rate: f64,
    seed: u64,
    trot: Option<(f64, f64)>,
    still: bool,
    drop: f64,
    push: Option<Vec<f64>>,
    ground_friction: Option<f64>,
    sensors: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let standing = StartOptions::default();
    let push = match push.as_deref() {
        None => standing.push,
        Some(&[x, y, z]) => [x, y, z],
        Some(_) => {
            return Err(InputError::new_err(
                "push: expected VX,VY,VZ (three numbers)",
            ))
        }
    };
    let opts = SimulateFloatingOptions {
        robot: floating_robot_options(robot, no_rotors)?,
        duration,
        rate,
        seed,
        trot,
        still,
        start: StartOptions {
            drop,
            push,
            ground_friction: ground_friction.unwrap_or(standing.ground_friction),
        },
        sensors: sensors_of(py, sensors)?,
        out,
    };
    let done =
        cancellable(py, move |_| api::floating::simulate_floating(&opts))?.map_err(api_error)?;
    plain(py, &done)
}

/// The sensors of `simulate_floating`'s `sensors` keyword.
fn sensors_of(
    py: Python<'_>,
    sensors: Option<&Bound<'_, PyAny>>,
) -> PyResult<api::floating::Sensors> {
    use api::floating::Sensors;
    let Some(s) = sensors else {
        return Ok(Sensors::default());
    };
    if let Ok(text) = s.extract::<String>() {
        return match text.as_str() {
            "exact" => Ok(Sensors::exact()),
            other => Err(exception(format!(
                "sensors: '{other}' is not \"exact\" (give a dict of the sensors' fields)"
            ))),
        };
    }
    let json: String = py
        .import("json")?
        .call_method1("dumps", (s,))
        .map_err(|_| exception("sensors: give a dict of the sensors' fields, or \"exact\""))?
        .extract()?;
    let mut merged = serde_json::to_value(Sensors::default()).map_err(exception)?;
    let given: serde_json::Map<String, serde_json::Value> = serde_json::from_str(&json)
        .map_err(|_| exception("sensors: give a dict of the sensors' fields, or \"exact\""))?;
    for (k, v) in given {
        merged[k] = v;
    }
    let sensors: Sensors =
        serde_json::from_value(merged).map_err(|e| exception(format!("sensors: {e}")))?;
    sensors
        .validate()
        .map_err(|e| exception(format!("sensors: {e}")))?;
    Ok(sensors)
}

/// Identifies a floating robot from one log (CSV, MCAP or a rosbag2 directory), its
/// description the prior, as `physid
/// identify-floating` does; `foot` the feet as `"BODY:X,Y,Z"` strings or `(body, (x, y, z))`
/// pairs (default: the built-in quadruped's). `out_urdf` and `out_mjcf` write the identified
/// robot (never over an input).
#[doc = include_str!("../keywords/identify_floating.txt")]
#[pyfunction]
#[pyo3(signature = (data, *, robot = None, no_rotors = false,
    setting = "torques-and-contacts", constraints = "ellipsoid", prior_weight = 1e-4,
    cutoff = None, foot = None, contact_force = 10.0, out_urdf = None, out_mjcf = None,
    truth = None, baseline = None, topic = String::from("/joint_states"),
    odometry_topic = String::from("/odometry"), foot_forces_topic = String::from("/foot_forces"),
    imu_topic = String::from("/imu"), stamp = "log"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn identify_floating(
    py: Python<'_>,
    data: PathBuf,
    robot: Option<&Bound<'_, PyAny>>,
    no_rotors: bool,
    setting: &str,
    constraints: &str,
    prior_weight: f64,
    cutoff: Option<f64>,
    foot: Option<Vec<Bound<'_, PyAny>>>,
    contact_force: f64,
    out_urdf: Option<PathBuf>,
    out_mjcf: Option<PathBuf>,
    truth: Option<PathBuf>,
    baseline: Option<PathBuf>,
    topic: String,
    odometry_topic: String,
    foot_forces_topic: String,
    imu_topic: String,
    stamp: &str,
) -> PyResult<FloatingIdentification> {
    let opts = IdentifyFloatingOptions {
        robot: floating_robot_options(robot, no_rotors)?,
        data,
        topics: FloatingReadOptions {
            topic,
            stamp: stamp
                .parse()
                .map_err(|e| exception(format!("stamp: {e}")))?,
            odometry_topic,
            foot_forces_topic,
            imu_topic,
        },
        feet: foot
            .unwrap_or_default()
            .iter()
            .map(foot_of)
            .collect::<PyResult<_>>()?,
        setting: serde_json::from_value(serde_json::Value::String(setting.replace('-', "_")))
            .map_err(|_| {
                exception(format!(
                "setting: '{setting}' is not one of torques_and_contacts, torques_only, base_only"
            ))
            })?,
        constraints: constraints_of(constraints)?,
        prior_weight,
        cutoff,
        contact_force,
        out_urdf,
        out_mjcf,
        truth,
        baseline,
    };
    let found =
        cancellable(py, move |_| api::floating::identify_floating(&opts))?.map_err(api_error)?;
    warn(py, &found.notices)?;
    Ok(FloatingIdentification { found })
}

/// A foot from `"BODY:X,Y,Z"` or `(body, (x, y, z))`.
fn foot_of(v: &Bound<'_, PyAny>) -> PyResult<Foot> {
    if let Ok((body, point)) = v.extract::<(String, [f64; 3])>() {
        return Ok(Foot { body, point });
    }
    let text: String = v
        .extract()
        .map_err(|_| exception("foot: give \"BODY:X,Y,Z\" or (body, (x, y, z)) per foot"))?;
    text.parse().map_err(exception)
}

/// A constraint set from its name.
fn constraints_of(name: &str) -> PyResult<api::ConstraintSet> {
    name.parse().map_err(|_| {
        exception(format!(
            "constraints: '{name}' is not one of none, semi, consistent, ellipsoid"
        ))
    })
}

/// A floating robot (a free trunk carrying a tree: the built-in quadruped `"cheetah3"`, a
/// floating URDF, or its sidecar TOML) and its dynamics on arrays in pinocchio's free-flyer
/// layout: `q = [x, y, z, qx, qy, qz, qw, joints…]` (`nq = 7 + n`), velocities and
/// accelerations `[v, ω, joints…]` (`nv = 6 + n`, the trunk origin's velocity and the angular
/// velocity in trunk axes), generalized forces `[f, τ_trunk, joints…]` (N, N m, trunk axes).
/// The joints are in the robot's order (`joint_names`), not necessarily pinocchio's.
#[doc = include_str!("../keywords/FloatingRobot.txt")]
#[pyclass(frozen, module = "physid")]
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct FloatingRobot {
    robot: api::FloatingModel,
    /// How it was loaded (functions that take a robot load it so again).
    options: RobotOptions,
}

#[pymethods]
impl FloatingRobot {
    /// Loads `robot`; `no_rotors` drops the rotors (the link-only model). The loader's
    /// warnings are issued as `PhysidWarning`.
    #[new]
    #[pyo3(signature = (robot = PathBuf::from("cheetah3"), *, no_rotors = false))]
    fn new(py: Python<'_>, robot: PathBuf, no_rotors: bool) -> PyResult<Self> {
        let options = robot_options(robot, no_rotors);
        let loaded = options.load_floating().map_err(api_error)?;
        warn(py, &loaded.notices)?;
        Ok(Self {
            robot: loaded.robot,
            options,
        })
    }

    /// Pickles (and copies) as its state in physid's binary form.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<crate::pickle::Reduced<'py>> {
        crate::pickle::reduce(py, "FloatingRobot", self)
    }

    /// The robot's name.
    #[getter]
    fn name(&self) -> String {
        self.robot.name().to_string()
    }

    /// The trunk's (root body's) name.
    #[getter]
    fn trunk(&self) -> String {
        self.robot.trunk().name.clone()
    }

    /// Sizes `(nq, nv)`: `7 + n` and `6 + n`.
    #[getter]
    fn sizes(&self) -> (usize, usize) {
        (7 + self.robot.joints(), 6 + self.robot.joints())
    }

    /// Joint names, in the robot's order (entries 7… of `q`, 6… of velocities).
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.robot.tree().joint_names()
    }

    /// The names of θ's entries (the trunk's `m, hx, …, Izz`, then the tree's).
    #[getter]
    fn parameter_names(&self) -> Vec<String> {
        self.robot.parameter_names()
    }

    /// The description's parameter vector θ.
    fn parameters<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.robot.parameters().as_slice().to_vec().into_pyarray(py)
    }

    /// The total mass (kg).
    #[getter]
    fn mass(&self) -> f64 {
        self.robot.total_mass()
    }

    /// pinocchio's `rnea` of the free flyer: `[f, τ_trunk, joint torques]` (friction not
    /// included), `(samples, nv)` or `(nv,)` for one sample given as `(nq,)`.
    fn inverse_dynamics<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        v: &Bound<'py, PyAny>,
        a: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let nv = self.sizes().1;
        self.on_states(
            py,
            (q, v, a),
            api::dynamics::floating_inverse_dynamics,
            &[nv],
        )
    }

    /// pinocchio's `crba` of the free flyer (both triangles): `(samples, nv, nv)`, or `(nv, nv)`
    /// for one configuration given as `(nq,)`.
    fn mass_matrix<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let (nq, nv) = self.sizes();
        let q = crate::arrays::samples("q", q, nq)?;
        let m = py
            .allow_threads(|| api::dynamics::floating_mass_matrices(&self.robot, &q.values))
            .map_err(api_error)?;
        crate::arrays::shaped(py, m, q.samples, q.one, &[nv, nv])
    }

    /// The regressor, `Y θ` = `inverse_dynamics` plus the joints' friction with θ =
    /// `parameters()` (its last `2 n` columns the viscous and Coulomb friction's, `q̇` and
    /// `sign(q̇)` of each joint): `(samples, nv, p)`, or `(nv, p)` for one sample given as `(nq,)`.
    fn regressor<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        v: &Bound<'py, PyAny>,
        a: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let (nv, p) = (self.sizes().1, self.robot.parameter_count());
        self.on_states(py, (q, v, a), api::dynamics::floating_regressors, &[nv, p])
    }

    fn __repr__(&self) -> String {
        format!(
            "FloatingRobot('{}', nq {}, nv {}, {} parameters)",
            self.robot.name(),
            7 + self.robot.joints(),
            6 + self.robot.joints(),
            self.robot.parameter_count()
        )
    }
}

impl FloatingRobot {
    /// `batch` of the states `(q, v, a)` (checked, then computed without the GIL), shaped
    /// `(samples, rest…)` or `rest` for one sample.
    fn on_states<'py>(
        &self,
        py: Python<'py>,
        (q, v, a): (&Bound<'py, PyAny>, &Bound<'py, PyAny>, &Bound<'py, PyAny>),
        batch: FloatingBatch,
        rest: &[usize],
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let x = floating_states(q, v, a, self.sizes())?;
        let values = py
            .allow_threads(|| batch(&self.robot, &x.q, &x.qd, &x.qdd))
            .map_err(api_error)?;
        crate::arrays::shaped(py, values, x.samples, x.one, rest)
    }
}

/// A batch routine over a floating robot's states (`api::dynamics::floating_*`).
type FloatingBatch =
    fn(&api::FloatingModel, &[f64], &[f64], &[f64]) -> Result<Vec<f64>, api::ApiError>;

/// `q` (`nq` per sample), `v` and `a` (`nv` per sample), as many samples each.
fn floating_states(
    q: &Bound<'_, PyAny>,
    v: &Bound<'_, PyAny>,
    a: &Bound<'_, PyAny>,
    (nq, nv): (usize, usize),
) -> PyResult<crate::arrays::States> {
    let q = crate::arrays::samples("q", q, nq)?;
    let (v, a) = (
        crate::arrays::samples("v", v, nv)?,
        crate::arrays::samples("a", a, nv)?,
    );
    if v.samples != q.samples || a.samples != q.samples {
        return Err(exception(format!(
            "q has {} samples, v {} and a {}: give as many of each",
            q.samples, v.samples, a.samples
        )));
    }
    Ok(crate::arrays::States {
        q: q.values,
        qd: v.values,
        qdd: a.values,
        samples: q.samples,
        one: q.one,
    })
}
