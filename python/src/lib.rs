//! `physid._physid`: the Python extension over physid's library entry points (`physid::api`).
//!
//! Arrays cross as numpy arrays of float64: joint quantities as `(samples, n)` (a 1-D array of
//! `n` is one sample), results likewise. Errors raise `ValueError` with the library's message;
//! long calls release the GIL.

use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArrayDyn};
use physid::api;
use physid::ident::{ConstraintSet, NormalEquations, Options};
use physid::model::Model;
use physid::trajectory::Trajectory;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A library error as a Python `ValueError` with its message.
fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
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

/// An array of joint values as a flat sample-major vector and its sample count: `(samples, n)`
/// or one sample of `n`.
fn samples(name: &str, a: &PyReadonlyArrayDyn<'_, f64>, n: usize) -> PyResult<(Vec<f64>, usize)> {
    let view = a.as_array();
    let shape = view.shape().to_vec();
    let count = match shape[..] {
        [m] if m == n => 1,
        [s, m] if m == n => s,
        _ => {
            return Err(value_error(format!(
            "{name} has shape {shape:?}: give (samples, {n}) or ({n},) for the robot's {n} joints"
        )))
        }
    };
    Ok((view.iter().copied().collect(), count))
}

/// Positions, velocities and accelerations as flat sample-major vectors, and q's samples (the
/// library checks that the others have as many).
struct States {
    q: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
    samples: usize,
}

fn states(
    q: &PyReadonlyArrayDyn<'_, f64>,
    qd: &PyReadonlyArrayDyn<'_, f64>,
    qdd: &PyReadonlyArrayDyn<'_, f64>,
    n: usize,
) -> PyResult<States> {
    let (q, count) = samples("q", q, n)?;
    Ok(States {
        q,
        qd: samples("qd", qd, n)?.0,
        qdd: samples("qdd", qdd, n)?.0,
        samples: count,
    })
}

/// A robot: the built-in leg (`"cheetah3"`), a URDF file, or a robot TOML file.
#[pyclass(frozen, module = "physid")]
struct Robot {
    model: Model,
}

#[pymethods]
impl Robot {
    #[new]
    fn new(robot: &str) -> PyResult<Self> {
        let model = physid::io::load_robot(robot).map_err(value_error)?;
        Ok(Robot { model })
    }

    /// The robot's name.
    #[getter]
    fn name(&self) -> String {
        self.model.name.clone()
    }

    /// Number of joints.
    #[getter]
    fn dof(&self) -> usize {
        self.model.dof()
    }

    /// Joint names, in the robot's order (the columns of every array).
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.model
            .bodies
            .iter()
            .map(|b| b.joint_name.clone())
            .collect()
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

    /// `τ = RNEA(q, q̇, q̈) + friction` (N m): `(samples, n)`.
    fn inverse_dynamics<'py>(
        &self,
        py: Python<'py>,
        q: PyReadonlyArrayDyn<'py, f64>,
        qd: PyReadonlyArrayDyn<'py, f64>,
        qdd: PyReadonlyArrayDyn<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let n = self.model.dof();
        let States {
            q,
            qd,
            qdd,
            samples: s,
        } = states(&q, &qd, &qdd, n)?;
        let tau = py
            .allow_threads(|| api::dynamics::inverse_dynamics(&self.model, &q, &qd, &qdd))
            .map_err(value_error)?;
        tau.into_pyarray(py).reshape([s, n])
    }

    /// The joint-space mass matrix `H(q)` (kg m²): `(samples, n, n)`.
    fn mass_matrix<'py>(
        &self,
        py: Python<'py>,
        q: PyReadonlyArrayDyn<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let n = self.model.dof();
        let (q, s) = samples("q", &q, n)?;
        let h = py
            .allow_threads(|| api::dynamics::mass_matrices(&self.model, &q))
            .map_err(value_error)?;
        h.into_pyarray(py).reshape([s, n, n])
    }

    /// The regressor `Y(q, q̇, q̈)`, `Y θ = τ`: `(samples, n, p)`.
    fn regressor<'py>(
        &self,
        py: Python<'py>,
        q: PyReadonlyArrayDyn<'py, f64>,
        qd: PyReadonlyArrayDyn<'py, f64>,
        qdd: PyReadonlyArrayDyn<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let (n, p) = (self.model.dof(), self.model.layout().len);
        let States {
            q,
            qd,
            qdd,
            samples: s,
        } = states(&q, &qd, &qdd, n)?;
        let y = py
            .allow_threads(|| api::dynamics::regressors(&self.model, &q, &qd, &qdd))
            .map_err(value_error)?;
        y.into_pyarray(py).reshape([s, n, p])
    }

    /// The robot described: bodies, rotors, joints, gravity torque at rest (the JSON of
    /// `physid model --json`).
    fn describe<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, "model", &api::model::describe(&self.model))
    }

    fn __repr__(&self) -> String {
        format!(
            "Robot('{}', {} joints, {} parameters)",
            self.model.name,
            self.model.dof(),
            self.model.layout().len
        )
    }
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
    q: PyReadonlyArrayDyn<'py, f64>,
    qd: PyReadonlyArrayDyn<'py, f64>,
    qdd: PyReadonlyArrayDyn<'py, f64>,
    tau: PyReadonlyArrayDyn<'py, f64>,
    constraints: Option<&str>,
    prior_weight: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let m = &robot.model;
    let n = m.dof();
    let given = constraints
        .map(|c| c.parse::<ConstraintSet>())
        .transpose()
        .map_err(value_error)?;
    let (set, because) = api::identify::constraint_set(given, m);
    let mut opts = Options::new(set);
    opts.prior_weight = prior_weight;
    opts.validate().map_err(value_error)?;
    let States {
        q,
        qd,
        qdd,
        samples: s,
    } = states(&q, &qd, &qdd, n)?;
    let tau = samples("tau", &tau, n)?.0;
    // Lengths, sample counts and finiteness, named by array, sample and joint.
    api::dynamics::samples(m, &q, &[("qd", &qd), ("qdd", &qdd), ("tau", &tau)])
        .map_err(value_error)?;
    let mut tr = Trajectory::new(robot.joint_names(), true);
    tr.q = q;
    tr.qd = qd;
    tr.qdd = Some(qdd);
    tr.tau = tau;
    tr.t = (0..s).map(|k| k as f64 * 1e-3).collect();
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

/// physid's version.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
fn _physid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Robot>()?;
    m.add_function(wrap_pyfunction!(identify_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    Ok(())
}
