//! The robot-description keys shared by the robot TOML format and URDF sidecars: frame
//! placements, inertials, ellipsoids, rotors and friction ([`RobotExtras`], applied to a tree
//! read from either format). Key reference: [`super::robot_toml`] and docs/robot-format.md.

use super::geometry::GeometryOptions;
use super::IoError;
use nalgebra::{Matrix3, Vector3};
use physid_core::model::{Body, JointFriction, RotorModel};
use physid_core::spatial::{rpy_to_matrix, Ellipsoid, InertialParams, Transform};
use serde::Deserialize;
use std::path::Path;

/// A frame placement: `xyz` (m) and URDF roll-pitch-yaw `rpy` (rad).
#[derive(Clone, Debug, Default, Deserialize, PartialEq, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct OriginSpec {
    /// Position (m).
    #[serde(default)]
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw (rad).
    #[serde(default)]
    pub rpy: [f64; 3],
}

impl OriginSpec {
    pub(crate) fn transform(&self) -> Transform {
        Transform::from_pose(
            &rpy_to_matrix(&Vector3::from(self.rpy)),
            &Vector3::from(self.xyz),
        )
    }
}

/// Inertial parameters, see the module docs.
#[derive(Clone, Debug, Default, Deserialize, PartialEq, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct InertialSpec {
    /// The ten parameters in the paper's order.
    pub pi: Option<[f64; 10]>,
    /// Mass (kg).
    pub mass: Option<f64>,
    /// Centre of mass (m).
    pub com: Option<[f64; 3]>,
    /// `[Ixx, Ixy, Ixz, Iyy, Iyz, Izz]` about the CoM (kg m²).
    pub inertia: Option<[f64; 6]>,
    /// Added rms extent (m).
    pub thicken: Option<f64>,
}

impl InertialSpec {
    pub(crate) fn params(&self, what: &str) -> Result<InertialParams, String> {
        let p = match (self.pi, self.mass, self.com, self.inertia) {
            (Some(pi), None, None, None) => {
                InertialParams::from_slice(&pi).map_err(|e| format!("{what}.inertial.pi: {e}"))?
            }
            (None, Some(m), Some(c), Some(i)) => {
                let ic = Matrix3::new(i[0], i[1], i[2], i[1], i[3], i[4], i[2], i[4], i[5]);
                InertialParams::from_mass_com_inertia(m, &Vector3::from(c), &ic)
            }
            _ => {
                return Err(format!(
                    "{what}.inertial: give either `pi` or all of `mass`, `com`, `inertia`"
                ))
            }
        };
        match self.thicken {
            Some(d) if !(d.is_finite() && d >= 0.0) => {
                Err(format!("{what}.inertial.thicken: {d} m must be >= 0"))
            }
            Some(d) => Ok(p.thickened(d)),
            None => Ok(p),
        }
    }
}

/// An ellipsoid in a body frame.
#[derive(Clone, Debug, Deserialize, PartialEq, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct EllipsoidSpec {
    /// Body or rotor name (sidecar form only).
    pub body: Option<String>,
    /// Centre (m).
    pub center: [f64; 3],
    /// Semi-axes (m), along the axes rotated by `rpy`.
    pub semi_axes: [f64; 3],
    /// Orientation of the semi-axes (rad).
    #[serde(default)]
    pub rpy: [f64; 3],
    /// Whether the body's inertia must lie inside (default). `false` keeps the ellipsoid for
    /// identification but only warns when the description's inertia is outside: what
    /// `identify --out-urdf` writes for a model identified under a looser set than the
    /// ellipsoids (it then lies outside the geometry's ellipsoids, and must still load).
    #[serde(default = "strict")]
    pub strict: bool,
}

fn strict() -> bool {
    true
}

impl EllipsoidSpec {
    pub(crate) fn ellipsoid(&self, what: &str) -> Result<Ellipsoid, String> {
        if self.semi_axes.iter().any(|a| !(a.is_finite() && *a > 0.0)) {
            return Err(format!(
                "{what}.ellipsoid.semi_axes: {:?} must all be positive",
                self.semi_axes
            ));
        }
        let r = rpy_to_matrix(&Vector3::from(self.rpy));
        let a = Vector3::from(self.semi_axes);
        let qs = r * Matrix3::from_diagonal(&a.component_mul(&a)) * r.transpose();
        Ok(Ellipsoid {
            center: Vector3::from(self.center),
            qs,
        })
    }
}

/// A rotor driven by a joint.
#[derive(Clone, Debug, Deserialize, PartialEq, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct RotorSpec {
    /// The driving joint (sidecar form only).
    pub joint: Option<String>,
    /// Rotor name (default `<joint>_rotor`).
    pub name: Option<String>,
    /// Gear ratio N.
    pub gear_ratio: f64,
    /// Rotor frame in the parent body's frame.
    #[serde(default)]
    pub origin: OriginSpec,
    /// Spin axis in the rotor frame (default: the joint axis).
    pub axis: Option<[f64; 3]>,
    /// How the rotor moves: `revolute` (spins about its axis, the default) or `prismatic`
    /// (slides along it: a mimic of a prismatic joint).
    #[serde(rename = "type", default)]
    pub kind: RotorJointType,
    /// Rotor inertial parameters, rotor frame.
    pub inertial: InertialSpec,
    /// Bounding ellipsoid, rotor frame.
    pub ellipsoid: Option<EllipsoidSpec>,
}

/// How a rotor moves relative to its parent.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RotorJointType {
    /// Spins about its axis (a motor behind a gearbox).
    #[default]
    Revolute,
    /// Slides along its axis.
    Prismatic,
}

/// Friction of one joint (sidecar form).
#[derive(Clone, Debug, Deserialize, PartialEq, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionSpec {
    /// Joint name.
    pub joint: String,
    /// Viscous coefficient (N m s/rad).
    #[serde(default)]
    pub viscous: f64,
    /// Coulomb coefficient (N m).
    #[serde(default)]
    pub coulomb: f64,
}

/// How a robot is loaded, beyond its files: bounding ellipsoids from its geometry. Given on
/// the command line; each set field overrides the robot TOML's key of the same name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RobotOptions {
    /// Added to every semi-axis of an ellipsoid computed from geometry (m).
    pub ellipsoid_margin: Option<f64>,
    /// Extra folders holding ROS packages, for `package://` meshes.
    pub package_dirs: Vec<std::path::PathBuf>,
    /// `false`: no ellipsoids from geometry (only the sidecar's).
    pub geometry_ellipsoids: Option<bool>,
}

/// The widest ellipsoid margin accepted (m).
pub const MAX_MARGIN: f64 = 10.0;

impl RobotOptions {
    /// Checks the margin (finite, 0 to [`MAX_MARGIN`]).
    pub fn validate(&self) -> Result<(), String> {
        match self.ellipsoid_margin {
            Some(m) if !(m.is_finite() && (0.0..=MAX_MARGIN).contains(&m)) => Err(format!(
                "ellipsoid margin {} m must be a finite number >= 0 and at most {MAX_MARGIN} m (a wider ellipsoid bounds nothing on a robot)",
                physid_core::options::readable(m)
            )),
            _ => Ok(()),
        }
    }

    /// `self` over `base`: fields set here win, package folders add up.
    pub(crate) fn over(&self, base: &GeometryOptions) -> GeometryOptions {
        GeometryOptions {
            package_dirs: base
                .package_dirs
                .iter()
                .chain(&self.package_dirs)
                .cloned()
                .collect(),
            margin: self.ellipsoid_margin.unwrap_or(base.margin),
            ignore_geometry: self
                .geometry_ellipsoids
                .map_or(base.ignore_geometry, |g| !g),
            cache: base.cache.clone(),
        }
    }
}

/// Additions that apply to any robot: sidecar rotors, friction, ellipsoids, gravity, rotor
/// model, and how geometry becomes bounding ellipsoids.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RobotExtras {
    /// Bounding ellipsoids from the description's geometry.
    pub geometry: GeometryOptions,
    /// Gravity (m/s², base frame).
    pub gravity: Option<[f64; 3]>,
    /// Rotor treatment.
    pub rotor_model: Option<RotorModel>,
    /// Sidecar rotors (`joint` names the driving joint).
    pub rotor: Vec<RotorSpec>,
    /// Friction per joint.
    pub friction: Vec<FrictionSpec>,
    /// Bounding ellipsoids by body or rotor name.
    pub ellipsoid: Vec<EllipsoidSpec>,
}

pub(crate) fn rotor_from_spec(
    spec: &RotorSpec,
    joint_name: &str,
    joint_axis: Vector3<f64>,
    x_parent: &Transform,
) -> Result<physid_core::model::Rotor, String> {
    let name = spec
        .name
        .clone()
        .unwrap_or_else(|| format!("{joint_name}_rotor"));
    let what = format!("rotor '{name}'");
    Ok(physid_core::model::Rotor {
        x_rot: spec.origin.transform().compose(x_parent),
        joint: {
            let axis = spec.axis.map_or(joint_axis, Vector3::from);
            match spec.kind {
                RotorJointType::Revolute => physid_core::model::Joint::Revolute { axis },
                RotorJointType::Prismatic => physid_core::model::Joint::Prismatic { axis },
            }
        },
        gear_ratio: spec.gear_ratio,
        inertia: spec.inertial.params(&what)?,
        bounding: spec
            .ellipsoid
            .as_ref()
            .map(|e| e.ellipsoid(&what))
            .transpose()?,
        name,
    })
}

impl RobotExtras {
    /// The sidecar ellipsoid of the body `name` (a floating robot's trunk, which is not among
    /// the tree's bodies), and these extras without it.
    pub fn split_ellipsoid(
        &self,
        name: Option<&str>,
        path: &Path,
    ) -> Result<(Option<Ellipsoid>, RobotExtras), IoError> {
        let mut rest = self.clone();
        let Some(name) = name else {
            return Ok((None, rest));
        };
        let (own, others): (Vec<EllipsoidSpec>, Vec<EllipsoidSpec>) = (self.ellipsoid.iter())
            .cloned()
            .partition(|e| e.body.as_deref() == Some(name));
        rest.ellipsoid = others;
        let ellipsoid = (own.last())
            .map(|e| e.ellipsoid(&format!("ellipsoid of '{name}'")))
            .transpose()
            .map_err(|m| IoError::invalid(path, m))?;
        Ok((ellipsoid, rest))
    }

    /// Applies sidecar rotors, friction and ellipsoids to `bodies`. `x_parent_link[i]` is the
    /// transform from body `i`'s parent body frame to its URDF parent link frame (identity for
    /// explicit trees), so sidecar rotor origins are given relative to the parent link.
    pub fn apply(
        &self,
        bodies: &mut [Body],
        x_parent_link: &[Transform],
        path: &Path,
    ) -> Result<(), IoError> {
        let find = |bodies: &[Body], joint: &str, what: &str| {
            bodies
                .iter()
                .position(|b| b.joint_name == joint)
                .ok_or_else(|| {
                    IoError::invalid(
                        path,
                        format!("{what} names joint '{joint}', which the robot does not have"),
                    )
                })
        };
        for r in &self.rotor {
            let joint = r.joint.as_deref().ok_or_else(|| {
                IoError::invalid(path, "robot.rotor: each sidecar rotor needs `joint`")
            })?;
            let k = find(bodies, joint, "robot.rotor")?;
            if bodies[k].rotor.is_some() {
                return Err(IoError::invalid(
                    path,
                    format!("robot.rotor: joint '{joint}' already has a rotor"),
                ));
            }
            let axis = bodies[k].joint.axis();
            bodies[k].rotor = Some(
                rotor_from_spec(r, joint, axis, &x_parent_link[k])
                    .map_err(|m| IoError::invalid(path, m))?,
            );
        }
        for f in &self.friction {
            let k = find(bodies, &f.joint, "robot.friction")?;
            bodies[k].friction = JointFriction {
                viscous: f.viscous,
                coulomb: f.coulomb,
            };
        }
        for e in &self.ellipsoid {
            place_ellipsoid(e, bodies, path)?;
        }
        Ok(())
    }
}

/// Puts sidecar ellipsoid `e` on the body or rotor it names; an error naming `path` when it
/// names neither or its values are not an ellipsoid.
fn place_ellipsoid(e: &EllipsoidSpec, bodies: &mut [Body], path: &Path) -> Result<(), IoError> {
    let name = e
        .body
        .as_deref()
        .ok_or_else(|| IoError::invalid(path, "robot.ellipsoid: each entry needs `body`"))?;
    let ell = e
        .ellipsoid(&format!("ellipsoid of '{name}'"))
        .map_err(|m| IoError::invalid(path, m))?;
    if let Some(b) = bodies.iter_mut().find(|b| b.name == name) {
        b.bounding = Some(ell);
    } else if let Some(r) = bodies
        .iter_mut()
        .filter_map(|b| b.rotor.as_mut())
        .find(|r| r.name == name)
    {
        r.bounding = Some(ell);
    } else {
        return Err(IoError::invalid(
            path,
            format!("robot.ellipsoid names '{name}', which is neither a body nor a rotor"),
        ));
    }
    Ok(())
}
