//! The `[robot]` table of a physid TOML file (a scenario or a robot file). Unknown keys are
//! errors. Three ways to give the robot, exactly one per file:
//!
//! ```toml
//! [robot]
//! builtin = "cheetah3"          # the built-in leg, with optional `truth`, `gear_ratios`,
//!                               # `rotors = false` for the link-only leg
//! # or
//! urdf = "arm.urdf"             # relative to this file; sidecar tables below add to it
//! # or
//! name = "my_leg"               # an explicit tree: [[robot.body]] tables, parents first
//! ```
//!
//! Shared keys (units): `gravity = [x, y, z]` (m/s², base frame), `rotor_model = "full" |
//! "reflected"`, `[[robot.rotor]]` with `joint = "name"` (sidecar rotors), `[[robot.friction]]`
//! with `joint`, `viscous` (N m s/rad), `coulomb` (N m), `[[robot.ellipsoid]]` with `body` (a
//! body or rotor name), `center` (m), `semi_axes` (m), optional `rpy` (rad).
//!
//! A `[[robot.body]]` has `name`, `joint`, `parent` (`"base"` or an earlier body), `type`
//! (`"revolute"` | `"prismatic"`), `axis`, `origin = { xyz (m), rpy (rad) }` (the joint frame in
//! the parent's frame at q = 0, URDF convention), `inertial`, and optional `ellipsoid`,
//! `rotor`, `friction`, `limits = { lower, upper (rad or m), velocity (rad/s), effort (N m) }`.
//!
//! An `inertial` is either `pi = [m, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz]` (the paper's
//! order, kg, kg m, kg m², about the body frame origin) or `mass` (kg), `com` (m) and
//! `inertia = [Ixx, Ixy, Ixz, Iyy, Iyz, Izz]` (kg m², about the CoM, body axes); either may add
//! `thicken = d` (m) to thicken the mass distribution by an rms extent `d` on every axis.
//! A `rotor` has optional `name`, `gear_ratio`, `origin` (in the parent body frame), optional
//! `axis` (rotor frame, default the joint axis), `inertial` (rotor frame) and `ellipsoid`.

use super::geometry::GeometryOptions;
use super::robot_spec::{
    rotor_from_spec, EllipsoidSpec, FrictionSpec, InertialSpec, OriginSpec, RobotExtras,
    RobotOptions, RotorSpec,
};
use super::IoError;
use nalgebra::Vector3;
use physid_core::model::cheetah3::{self, LegOptions, Truth};
use physid_core::model::{
    Body, Joint, JointFriction, JointLimits, Model, RotorModel, STANDARD_GRAVITY,
};
use physid_core::spatial::Transform;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// One body of an explicit tree.
#[derive(Clone, Debug, Deserialize, PartialEq, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Body name.
    pub name: String,
    /// Joint name.
    pub joint: String,
    /// `"base"` or the name of an earlier body.
    pub parent: String,
    /// `"revolute"` or `"prismatic"`.
    #[serde(rename = "type")]
    pub joint_type: String,
    /// Joint axis in the joint frame.
    pub axis: [f64; 3],
    /// Joint frame in the parent frame at q = 0.
    #[serde(default)]
    pub origin: OriginSpec,
    /// Inertial parameters in the joint frame.
    pub inertial: InertialSpec,
    /// Bounding ellipsoid.
    pub ellipsoid: Option<EllipsoidSpec>,
    /// Rotor driven by this joint.
    pub rotor: Option<RotorSpec>,
    /// Joint friction.
    pub friction: Option<JointFriction>,
    /// Joint limits.
    pub limits: Option<LimitsSpec>,
}

/// Joint limits; missing entries are unlimited.
#[derive(Clone, Debug, Default, Deserialize, PartialEq, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct LimitsSpec {
    /// Lower position limit (rad or m).
    pub lower: Option<f64>,
    /// Upper position limit (rad or m).
    pub upper: Option<f64>,
    /// Speed limit (rad/s or m/s).
    pub velocity: Option<f64>,
    /// Torque limit (N m or N).
    pub effort: Option<f64>,
    /// Acceleration limit for designed motions (rad/s² or m/s²).
    pub acceleration: Option<f64>,
    /// Jerk limit for designed motions (rad/s³ or m/s³).
    pub jerk: Option<f64>,
}

/// The `[robot]` table.
#[derive(Clone, Debug, Default, Deserialize, PartialEq, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// `"cheetah3"`.
    pub builtin: Option<String>,
    /// A URDF file, relative to the TOML file.
    pub urdf: Option<PathBuf>,
    /// Robot name (explicit trees).
    pub name: Option<String>,
    /// Built-in leg: ground truth (`{ kind = "thickened", d = 0.01 }` or `{ kind = "published" }`).
    pub truth: Option<Truth>,
    /// Built-in leg: gear ratios (ab/ad, hip, knee).
    pub gear_ratios: Option<[f64; 3]>,
    /// Built-in leg: include the rotors (default true).
    pub rotors: Option<bool>,
    /// Explicit tree.
    #[serde(default)]
    pub body: Vec<BodySpec>,
    /// Gravity (m/s², base frame).
    pub gravity: Option<[f64; 3]>,
    /// Rotor treatment.
    pub rotor_model: Option<RotorModel>,
    /// Sidecar rotors (`joint` names the driving joint).
    #[serde(default)]
    pub rotor: Vec<RotorSpec>,
    /// Friction per joint.
    #[serde(default)]
    pub friction: Vec<FrictionSpec>,
    /// Bounding ellipsoids by body or rotor name.
    #[serde(default)]
    pub ellipsoid: Vec<EllipsoidSpec>,
    /// Scale every bounding ellipsoid about its centre (semi-axes × s), after the truth's
    /// consistency check: below 1 the identification's ellipsoids may cut into the true mass
    /// distribution (a sweep axis: how tight is too tight).
    pub ellipsoid_scale: Option<f64>,
    /// URDF robots: added to every semi-axis of an ellipsoid computed from the URDF's geometry
    /// (m, default 0).
    pub ellipsoid_margin: Option<f64>,
    /// URDF robots: folders holding ROS packages for `package://` meshes (relative to this
    /// file).
    #[serde(default)]
    pub package_dirs: Vec<PathBuf>,
    /// URDF robots: `false` takes no ellipsoids from geometry, only from `[[robot.ellipsoid]]`
    /// (default true).
    pub geometry_ellipsoids: Option<bool>,
}

impl RobotSpec {
    /// The keys that apply to any robot.
    pub fn extras(&self) -> RobotExtras {
        RobotExtras {
            geometry: GeometryOptions {
                package_dirs: self.package_dirs.clone(),
                margin: self.ellipsoid_margin.unwrap_or(0.0),
                ignore_geometry: self.geometry_ellipsoids == Some(false),
                ..Default::default()
            },
            gravity: self.gravity,
            rotor_model: self.rotor_model,
            rotor: self.rotor.clone(),
            friction: self.friction.clone(),
            ellipsoid: self.ellipsoid.clone(),
        }
    }
}

/// A TOML error with the file name, line and column.
pub fn toml_error(path: &Path, e: toml::de::Error) -> IoError {
    IoError::Parse {
        path: path.to_path_buf(),
        message: e.to_string().trim_end().to_string(),
    }
}

/// Loads the `[robot]` table of a TOML file; other top-level tables (a scenario's) are ignored
/// here and checked by their own readers.
pub fn load(path: &Path) -> Result<Model, IoError> {
    load_with(path, &RobotOptions::default()).map(|(m, _)| m)
}

/// [`load`] with command-line options over the file's keys; also returns the loader's
/// warnings (URDF elements given twice, geometry that gave no bounding ellipsoid).
pub fn load_with(path: &Path, opts: &RobotOptions) -> Result<(Model, Vec<String>), IoError> {
    from_spec_with(&read_spec(path)?, path, opts)
}

/// The `[robot]` table of a TOML file, unbuilt.
pub fn read_spec(path: &Path) -> Result<RobotSpec, IoError> {
    let text = super::read_to_string(path)?;
    #[derive(Deserialize)]
    struct Doc {
        robot: Option<RobotSpec>,
    }
    let doc: Doc = toml::from_str(&text).map_err(|e| toml_error(path, e))?;
    doc.robot
        .ok_or_else(|| IoError::invalid(path, "no [robot] table"))
}

/// Builds the model a `[robot]` table describes; `path` is the TOML file (for relative paths
/// and error messages).
pub fn from_spec(spec: &RobotSpec, path: &Path) -> Result<Model, IoError> {
    from_spec_with(spec, path, &RobotOptions::default()).map(|(m, _)| m)
}

/// [`from_spec`] with command-line options over the table's keys, and the loader's warnings.
pub fn from_spec_with(
    spec: &RobotSpec,
    path: &Path,
    opts: &RobotOptions,
) -> Result<(Model, Vec<String>), IoError> {
    let model_err = |source| IoError::Model {
        path: path.to_path_buf(),
        source,
    };
    let extras = extras_of(spec, path, opts)?;
    check_ways(spec, path)?;
    let model = if let Some(b) = &spec.builtin {
        builtin_model(spec, b, &extras, path)?
    } else if let Some(u) = &spec.urdf {
        let upath = path.parent().unwrap_or(Path::new(".")).join(u);
        let (m, warnings) = super::urdf::load(&upath, &extras)?;
        return Ok((scaled(m, spec.ellipsoid_scale, path)?, warnings));
    } else {
        let mut bodies: Vec<Body> = vec![];
        for (k, b) in spec.body.iter().enumerate() {
            let body = body_from_spec(k, b, &bodies, path)?;
            bodies.push(body);
        }
        let ident = vec![Transform::identity(); bodies.len()];
        extras.apply(&mut bodies, &ident, path)?;
        let gravity = extras
            .gravity
            .map_or(Vector3::new(0.0, 0.0, -STANDARD_GRAVITY), Vector3::from);
        let name = spec.name.clone().unwrap_or_else(|| "robot".into());
        Model::new(name, bodies, gravity).map_err(model_err)?
    };
    let model = model.with_rotor_model(extras.rotor_model.unwrap_or_default());
    model.check_physical().map_err(model_err)?;
    Ok((scaled(model, spec.ellipsoid_scale, path)?, vec![]))
}

/// Loads a floating robot from a TOML file's `[robot]` table, which names its URDF (`urdf`, as
/// the sidecar of `identify-floating --out-urdf` does) and adds what URDF cannot carry
/// (ellipsoids, the trunk's among them; gravity; the rotor model); command-line options over
/// the file's keys.
pub fn load_floating_with(
    path: &Path,
    opts: &RobotOptions,
) -> Result<(physid_core::model::floating::FloatingModel, Vec<String>), IoError> {
    let spec = read_spec(path)?;
    check_ways(&spec, path)?;
    let Some(u) = &spec.urdf else {
        return Err(IoError::invalid(
            path,
            "robot: a floating robot's table names its URDF (`urdf`); built-in legs and [[robot.body]] trees do not float",
        ));
    };
    if spec.ellipsoid_scale.is_some() {
        return Err(IoError::invalid(
            path,
            "robot.ellipsoid_scale: not read for floating robots",
        ));
    }
    let extras = extras_of(&spec, path, opts)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    super::urdf::load_floating(&dir.join(u), &extras)
}

/// The table's extras with its package folders relative to the TOML file `path` and the
/// command-line options over its keys; the resulting ellipsoid margin checked.
fn extras_of(spec: &RobotSpec, path: &Path, opts: &RobotOptions) -> Result<RobotExtras, IoError> {
    let mut extras = spec.extras();
    let dir = path.parent().unwrap_or(Path::new("."));
    extras.geometry.package_dirs = (extras.geometry.package_dirs.iter())
        .map(|d| dir.join(d))
        .collect();
    extras.geometry = opts.over(&extras.geometry);
    RobotOptions {
        ellipsoid_margin: Some(extras.geometry.margin),
        ..Default::default()
    }
    .validate()
    .map_err(|m| IoError::invalid(path, format!("robot.ellipsoid_margin: {m}")))?;
    Ok(extras)
}

/// `model` with its ellipsoids scaled by `scale` (`robot.ellipsoid_scale`), if given.
fn scaled(model: Model, scale: Option<f64>, path: &Path) -> Result<Model, IoError> {
    match scale {
        None => Ok(model),
        Some(s) if s.is_finite() && s > 0.0 => Ok(model.with_ellipsoids_scaled(s)),
        Some(s) => Err(IoError::invalid(
            path,
            format!("robot.ellipsoid_scale: {s} must be > 0"),
        )),
    }
}

/// The `[robot]` table names exactly one way to build the robot, and only that way's keys.
fn check_ways(spec: &RobotSpec, path: &Path) -> Result<(), IoError> {
    if spec.urdf.is_none()
        && (spec.ellipsoid_margin.is_some()
            || !spec.package_dirs.is_empty()
            || spec.geometry_ellipsoids.is_some())
    {
        return Err(IoError::invalid(
            path,
            "robot: `ellipsoid_margin`, `package_dirs` and `geometry_ellipsoids` apply to URDF robots only",
        ));
    }
    let ways = [
        spec.builtin.is_some(),
        spec.urdf.is_some(),
        !spec.body.is_empty(),
    ];
    if ways.iter().filter(|w| **w).count() != 1 {
        return Err(IoError::invalid(
            path,
            "robot: give exactly one of `builtin`, `urdf` or [[robot.body]] tables",
        ));
    }
    if spec.builtin.is_none()
        && (spec.truth.is_some() || spec.gear_ratios.is_some() || spec.rotors.is_some())
    {
        return Err(IoError::invalid(
            path,
            "robot: `truth`, `gear_ratios` and `rotors` apply to the built-in leg only",
        ));
    }
    Ok(())
}

/// The built-in robot `name` with the table's options and extras.
fn builtin_model(
    spec: &RobotSpec,
    name: &str,
    extras: &RobotExtras,
    path: &Path,
) -> Result<Model, IoError> {
    let model_err = |source| IoError::Model {
        path: path.to_path_buf(),
        source,
    };
    if name != "cheetah3" {
        return Err(IoError::invalid(
            path,
            format!("robot.builtin: unknown robot '{name}' (known: cheetah3)"),
        ));
    }
    let mut o = LegOptions::default();
    if let Some(t) = spec.truth {
        o.truth = t;
    }
    if let Some(g) = spec.gear_ratios {
        o.gear_ratios = g;
    }
    if let Some(r) = spec.rotors {
        o.rotors = r;
    }
    let m = cheetah3::leg_with(&o).map_err(model_err)?;
    let mut bodies = m.bodies().to_vec();
    let ident = vec![Transform::identity(); bodies.len()];
    extras.apply(&mut bodies, &ident, path)?;
    let gravity = extras.gravity.map_or(m.gravity(), Vector3::from);
    Model::new(m.name().to_string(), bodies, gravity).map_err(model_err)
}

/// Body `k` of an explicit tree; its parent must be `base` or one of the `earlier` bodies.
fn body_from_spec(k: usize, b: &BodySpec, earlier: &[Body], path: &Path) -> Result<Body, IoError> {
    let what = format!("robot.body[{k}] '{}'", b.name);
    let e = |m: String| IoError::invalid(path, m);
    let parent = match b.parent.as_str() {
        "base" => None,
        p => Some(earlier.iter().position(|x| x.name == p).ok_or_else(|| {
            e(format!(
                "{what}: parent '{p}' is not 'base' or an earlier body"
            ))
        })?),
    };
    let axis = Vector3::from(b.axis);
    let joint = match b.joint_type.as_str() {
        "revolute" => Joint::Revolute { axis },
        "prismatic" => Joint::Prismatic { axis },
        t => {
            return Err(e(format!(
                "{what}: type '{t}' is not 'revolute' or 'prismatic'"
            )))
        }
    };
    let l = b.limits.clone().unwrap_or_default();
    let d = JointLimits::default();
    Ok(Body {
        name: b.name.clone(),
        joint_name: b.joint.clone(),
        parent,
        joint,
        x_tree: b.origin.transform(),
        inertia: b.inertial.params(&what).map_err(e)?,
        bounding: b
            .ellipsoid
            .as_ref()
            .map(|x| x.ellipsoid(&what))
            .transpose()
            .map_err(e)?,
        shapes: vec![],
        rotor: b
            .rotor
            .as_ref()
            .map(|r| rotor_from_spec(r, &b.joint, axis, &Transform::identity()))
            .transpose()
            .map_err(e)?,
        friction: b.friction.unwrap_or_default(),
        limits: JointLimits {
            lower: l.lower.unwrap_or(d.lower),
            upper: l.upper.unwrap_or(d.upper),
            velocity: l.velocity.unwrap_or(d.velocity),
            effort: l.effort.unwrap_or(d.effort),
            acceleration: l.acceleration.unwrap_or(d.acceleration),
            jerk: l.jerk.unwrap_or(d.jerk),
        },
    })
}
