//! `model`: a robot described — its bodies and rotors, mass properties, consistency
//! margins, joints, and its gravity torque at a reference configuration — as the JSON
//! contract [`ModelJson`] (schema docs/schemas/model.schema.json).

use crate::dynamics::{rnea, Data};
use crate::model::Model;
use crate::spatial::{ConsistencyReport, Ellipsoid, InertialParams};

/// An ellipsoid: centre (m), semi-axes (m, ascending), `Q_s` (m²).
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct EllipsoidJson {
    /// Centre (m, body frame).
    pub center: Vec<f64>,
    /// Semi-axes (m, ascending).
    pub semi_axes: Vec<f64>,
    /// `Q_s` (m²), the shape matrix of the paper's `tr(JQ) ≥ 0`.
    pub qs: Vec<Vec<f64>>,
}

/// One body or rotor: its ten parameters (paper order, own frame), mass (kg), CoM (m),
/// principal moments about the CoM (kg m²), consistency margins, bounding ellipsoid.
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct BodyJson {
    /// Its bounding ellipsoid, if it has one.
    pub ellipsoid: Option<EllipsoidJson>,
    /// Body or rotor name.
    pub name: String,
    /// `π = [m, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz]` (own frame, inertia about its origin).
    pub pi: Vec<f64>,
    /// kg.
    pub mass: f64,
    /// Centre of mass (m, own frame); none for a massless body.
    pub com: Option<Vec<f64>>,
    /// Principal moments about the CoM (kg m², ascending).
    pub principal_moments: Option<Vec<f64>>,
    /// Consistency margins: `λ_min I`, `λ_min J`, `tr(JQ)/m`.
    pub consistency: ConsistencyReport,
}

/// One joint: friction and limits `[lower, upper, velocity, effort]`.
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct JointJson {
    /// Joint name.
    pub name: String,
    /// Viscous and Coulomb friction.
    pub friction: crate::model::JointFriction,
    /// `[lower, upper, velocity, effort]` (rad or m, rad/s or m/s, N m or N).
    pub limits: [f64; 4],
}

/// `model --json` (schema `physid.model/1`, docs/schemas/).
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct ModelJson {
    /// The robot's name.
    pub name: String,
    /// Joints.
    pub dof: usize,
    /// Geared rotors.
    pub rotors: usize,
    /// How rotors are modelled.
    pub rotor_model: crate::model::RotorModel,
    /// kg.
    pub total_mass: f64,
    /// Length of θ (bodies' and rotors' ten parameters, then friction).
    pub parameters: usize,
    /// Every body followed by its rotor.
    pub bodies: Vec<BodyJson>,
    /// Every joint.
    pub joints: Vec<JointJson>,
    /// The reference configuration (rad): zero clamped into the limits.
    pub q0: Vec<f64>,
    /// Gravity torque at `q0` (N m).
    pub gravity_torque_q0: Vec<f64>,
}

/// An ellipsoid as reported.
pub fn ellipsoid_json(e: &Ellipsoid) -> EllipsoidJson {
    EllipsoidJson {
        center: e.center.as_slice().to_vec(),
        semi_axes: e.semi_axes().as_slice().to_vec(),
        qs: (0..3)
            .map(|i| (0..3).map(|j| e.qs[(i, j)]).collect())
            .collect(),
    }
}

/// A body or rotor as reported (`e` its bounding ellipsoid).
pub fn body_json(name: &str, p: &InertialParams, e: Option<&Ellipsoid>) -> BodyJson {
    BodyJson {
        ellipsoid: e.map(ellipsoid_json),
        name: name.to_string(),
        pi: p.0.as_slice().to_vec(),
        mass: p.mass(),
        com: p.com().map(|c| c.as_slice().to_vec()),
        principal_moments: p.principal_moments().map(|(v, _)| v.as_slice().to_vec()),
        consistency: p.consistency(e),
    }
}

/// The reference configuration (rad): zero clamped into each joint's limits.
pub fn reference_configuration(m: &Model) -> Vec<f64> {
    m.bodies()
        .iter()
        .map(|b| 0.0f64.clamp(b.limits.lower, b.limits.upper))
        .collect()
}

/// The robot described: every body followed by its rotor, the joints, the reference
/// configuration and the gravity torque there.
pub fn describe(m: &Model) -> ModelJson {
    let mut bodies = vec![];
    for b in m.bodies() {
        bodies.push(body_json(&b.name, &b.inertia, b.bounding.as_ref()));
        if let Some(r) = &b.rotor {
            bodies.push(body_json(&r.name, &r.inertia, r.bounding.as_ref()));
        }
    }
    let q0 = reference_configuration(m);
    let zero = vec![0.0; m.dof()];
    let g = rnea(m, &mut Data::new(m), &q0, &zero, &zero).clone();
    ModelJson {
        name: m.name().to_string(),
        dof: m.dof(),
        rotors: m.rotor_count(),
        rotor_model: m.rotor_model(),
        total_mass: m.total_mass(),
        parameters: m.layout().len,
        bodies,
        joints: m
            .bodies()
            .iter()
            .map(|b| JointJson {
                name: b.joint_name.clone(),
                friction: b.friction,
                limits: [
                    b.limits.lower,
                    b.limits.upper,
                    b.limits.velocity,
                    b.limits.effort,
                ],
            })
            .collect(),
        q0,
        gravity_torque_q0: g.as_slice().to_vec(),
    }
}

/// Which robot and how it is built: what every command that loads a robot is given.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RobotOptions {
    /// `cheetah3` (the built-in leg), a `.urdf` file, or a `.toml` file with a `[robot]` table.
    pub robot: String,
    /// Override the rotor treatment (full spinning bodies, or reflected armature).
    pub rotor_model: Option<crate::model::RotorModel>,
    /// Drop the rotors (the link-only model).
    pub no_rotors: bool,
    /// URDF robots: lengthen every semi-axis of the geometry's bounding ellipsoids (m).
    pub ellipsoid_margin: Option<f64>,
    /// URDF robots: folders holding ROS packages, for `package://` meshes.
    pub package_dirs: Vec<std::path::PathBuf>,
    /// URDF robots: take no bounding ellipsoids from the geometry (only a sidecar's).
    pub no_geometry_ellipsoids: bool,
}

/// A robot as loaded, with what the loader had to say about its description.
#[derive(Clone, Debug)]
pub struct LoadedRobot {
    /// The model.
    pub model: Model,
    /// The loader's warnings, naming the robot file.
    pub notices: Vec<super::data::Notice>,
}

/// A floating robot as loaded, with what the loader had to say about its description.
#[derive(Clone, Debug)]
pub struct LoadedFloatingRobot {
    /// The robot: trunk and tree.
    pub robot: crate::model::floating::FloatingModel,
    /// The loader's warnings, naming the robot file.
    pub notices: Vec<super::data::Notice>,
}

impl RobotOptions {
    /// The robot `robot` as described, every option at its default.
    pub fn new(robot: &str) -> Self {
        RobotOptions {
            robot: robot.to_string(),
            ..Default::default()
        }
    }

    /// Loads the robot, with the loader's warnings (a mesh not found, an inertia outside its
    /// geometry's ellipsoid, …) as notices naming the robot file.
    pub fn load(&self) -> Result<LoadedRobot, super::ApiError> {
        if let Some(d) = self.package_dirs.iter().find(|d| !d.is_dir()) {
            let why = if d.exists() {
                "is not a folder"
            } else {
                "does not exist"
            };
            return Err(super::ApiError::Options(format!(
                "--package-dir {}: {why}",
                d.display()
            )));
        }
        let opts = crate::io::robot_spec::RobotOptions {
            ellipsoid_margin: self.ellipsoid_margin,
            package_dirs: self.package_dirs.clone(),
            geometry_ellipsoids: self.no_geometry_ellipsoids.then_some(false),
        };
        let (mut m, warnings) = crate::io::load_robot_with(&self.robot, &opts)?;
        if self.no_rotors {
            m = m.without_rotors();
        }
        if let Some(r) = self.rotor_model {
            m = m.with_rotor_model(r);
        }
        let notices = warnings
            .into_iter()
            .map(|w| super::data::Notice::warning(format!("{}: {w}", self.robot)))
            .collect();
        Ok(LoadedRobot { model: m, notices })
    }

    /// Loads the robot as a floating robot ([`crate::io::load_floating_robot_with`]): the
    /// built-in leg becomes the quadruped, a URDF's root link its trunk; `no_rotors` and
    /// `rotor_model` apply to the tree.
    pub fn load_floating(&self) -> Result<LoadedFloatingRobot, super::ApiError> {
        let opts = crate::io::robot_spec::RobotOptions {
            ellipsoid_margin: self.ellipsoid_margin,
            package_dirs: self.package_dirs.clone(),
            geometry_ellipsoids: self.no_geometry_ellipsoids.then_some(false),
        };
        let (robot, warnings) = crate::io::load_floating_robot_with(&self.robot, &opts)?;
        let mut tree = robot.tree().clone();
        if self.no_rotors {
            tree = tree.without_rotors();
        }
        if let Some(r) = self.rotor_model {
            tree = tree.with_rotor_model(r);
        }
        let robot = crate::model::floating::FloatingModel::new(robot.trunk().clone(), tree)
            .map_err(|e| super::ApiError::Options(e.to_string()))?;
        let notices = warnings
            .into_iter()
            .map(|w| super::data::Notice::warning(format!("{}: {w}", self.robot)))
            .collect();
        Ok(LoadedFloatingRobot { robot, notices })
    }

    /// Every file the robot reads (its URDF, sidecar, meshes): inputs no output may replace.
    pub fn files(&self) -> Vec<std::path::PathBuf> {
        crate::io::robot_files(&self.robot, &self.package_dirs)
    }
}
