//! `physid.Robot`: a robot description and its dynamics on arrays.

use crate::arrays::*;
use crate::convert::*;
use crate::errors::*;
use api::{Model, RotorModel};
use numpy::{IntoPyArray, PyArray1, PyArrayDyn};
use physid::api;
use physid::api::data::Notice;
use physid::api::model::RobotOptions;
use pyo3::prelude::*;
use std::path::PathBuf;

/// A robot: the built-in leg (`"cheetah3"`), a URDF file, or a robot TOML file.
#[doc = include_str!("../keywords/Robot.txt")]
#[pyclass(frozen, module = "physid")]
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct Robot {
    pub(crate) model: Model,
    /// The robot as given (`cheetah3` or a file), for outputs that copy its URDF.
    pub(crate) source: String,
    /// The model is the dynamics `source` gives by itself (no rotor option changed it), so a
    /// scenario may name the file for it.
    pub(crate) as_file: bool,
    /// The loader's notes and warnings.
    pub(crate) notices: Vec<Notice>,
}

#[pymethods]
impl Robot {
    /// Pickles (and copies) as its state in physid's binary form.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<crate::pickle::Reduced<'py>> {
        crate::pickle::reduce(py, "Robot", self)
    }

    /// The notebook's view: name, joints and parameters, the bodies' masses.
    fn _repr_html_(&self) -> String {
        use crate::notebook::{card, number, table};
        let m = &self.model;
        let theta = m.parameters();
        let rows: Vec<Vec<String>> = api::bodies(m)
            .into_iter()
            .map(|(name, first, _)| vec![name, number(theta[first])])
            .collect();
        card(
            &format!("Robot '{}'", m.name()),
            &[
                ("joints", m.dof().to_string()),
                ("parameters", m.layout().len.to_string()),
            ],
            &[("bodies and rotors", table(&["body", "m (kg)"], &rows))],
        )
    }

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
        let robot: PathBuf = robot
            .extract()
            .map_err(|_| exception("robot: give \"cheetah3\" or a path to a URDF or robot TOML"))?;
        let rotor_model = match rotor_model {
            None => None,
            Some("full") => Some(RotorModel::Full),
            Some("reflected") => Some(RotorModel::Reflected),
            Some(other) => {
                return Err(exception(format!(
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
        warn_once(py, &notices)?;
        Ok(Robot {
            model,
            source: opts.robot,
            as_file: rotor_model.is_none() && !no_rotors,
            notices,
        })
    }

    /// Writes the robot as MJCF for MuJoCo (rotors as joint armature), never over an input;
    /// meshes MuJoCo cannot read are left out with a `PhysidWarning`.
    fn write_mjcf(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let inputs = api::files::robot_files(&self.source, &[]);
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
        let inputs = api::files::robot_files(&self.source, &[]);
        api::export::write_urdf(&self.model, robot, &path, &inputs).map_err(api_error)
    }

    /// The loader's notes and warnings about the description (its warnings are raised as
    /// `PhysidWarning` the first time a file is loaded in a process, and kept here every time).
    #[getter]
    fn notices(&self) -> Vec<String> {
        notice_texts(&self.notices)
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
            .map_err(exception)?;
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
            .map_err(exception)?;
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
            .map_err(exception)?;
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
