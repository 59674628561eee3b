//! The immutable robot model: a fixed-base kinematic tree of rigid bodies, each connected to its
//! parent by one joint, where any joint may drive a **rotor** through a gearbox.
//!
//! Topology follows RBDA §4.1: bodies are numbered so that `parent(i) < i`; body `i` is the
//! successor of joint `i`; the fixed base is "body −1" (`parent = None`). `x_tree[i]` is the
//! transform from the parent's frame to joint `i`'s frame at `q_i = 0`; each body's inertial
//! parameters are expressed in its own joint frame.
//!
//! A rotor (architecture.md §2, as in the open MIT Cheetah software) sits on the **parent** of body `i`
//! at the fixed transform `x_rot` from the parent frame, spins about its own `axis` by `N q_i`
//! (motion subspace `S_rot = N [axis; 0]`) and carries its own ten inertial parameters. Joint
//! torques are at the gearbox output. [`RotorModel::Reflected`] replaces the spinning rotor by
//! the classic armature approximation for comparison.

pub mod cheetah3;
pub mod floating;
mod joint;
pub mod quadruped;
pub mod random;

pub use joint::Joint;

use crate::spatial::{Ellipsoid, InertialParams, Transform};
use nalgebra::{DVector, Vector3};

/// Errors in a robot description. Each names the element at fault.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ModelError {
    /// The tree has no bodies.
    #[error("the model has no moving bodies")]
    Empty,
    /// A parent index does not precede its child.
    #[error("body '{body}': parent index {parent} must be less than its own index {index} (a tree numbered root first)")]
    BadParent {
        /// Body name.
        body: String,
        /// Its index.
        index: usize,
        /// The offending parent index.
        parent: usize,
    },
    /// Two bodies (or two joints) share a name.
    #[error("duplicate {what} name '{name}'")]
    DuplicateName {
        /// "body" or "joint".
        what: &'static str,
        /// The repeated name.
        name: String,
    },
    /// A non-finite or otherwise invalid number.
    #[error("{element}: {field} is invalid ({reason})")]
    BadValue {
        /// Body, joint or rotor name.
        element: String,
        /// The field at fault.
        field: &'static str,
        /// Why.
        reason: String,
    },
    /// Inertial parameters that no mass distribution can have.
    #[error("{element}: inertial parameters are not physically consistent: {reason}")]
    Inconsistent {
        /// Body or rotor name.
        element: String,
        /// Which condition fails, with the margin.
        reason: String,
    },
    /// A parameter vector of the wrong length.
    #[error("parameter vector has {got} entries, the model needs {expected}")]
    ParamLength {
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
}

/// A rotor driven by joint `i` through a gearbox, mounted on the parent of body `i`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Rotor {
    /// Name, e.g. `knee_rotor`.
    pub name: String,
    /// Transform from the parent body's frame to the rotor frame at zero rotor angle.
    pub x_rot: Transform,
    /// How the rotor moves relative to its parent, in the rotor frame: spinning about a unit
    /// axis (a motor; `Joint::Revolute`), or sliding along it (`Joint::Prismatic`: a URDF
    /// `<mimic>` of a prismatic joint, such as a gripper's second finger).
    pub joint: Joint,
    /// Gear ratio `N`: the rotor moves by `N q_i` (rad or m per rad or m of its joint).
    pub gear_ratio: f64,
    /// Inertial parameters in the rotor frame.
    pub inertia: InertialParams,
    /// Bounding ellipsoid in the rotor frame, if known.
    pub bounding: Option<Ellipsoid>,
}

impl Rotor {
    /// Armature `N² Sᵀ I_rot S` (kg m² or kg, at the joint): the rotor's inertia along its own
    /// motion reflected through the gearbox (`N² axisᵀ Ī_rot axis` for a spinning rotor,
    /// `N² m` for a sliding one), as the reflected model and MuJoCo's `armature` use it.
    pub fn armature(&self) -> f64 {
        let a = self.joint.axis();
        let own = match self.joint {
            Joint::Revolute { .. } => a.dot(&(self.inertia.ibar() * a)),
            Joint::Prismatic { .. } => self.inertia.mass(),
        };
        self.gear_ratio * self.gear_ratio * own
    }

    /// The rotor's motion subspace at its joint, `S_rot = N S` (rotor frame).
    pub fn motion_subspace(&self) -> crate::spatial::Motion {
        self.joint.motion_subspace() * self.gear_ratio
    }
}

/// Joint friction `τ_f = B q̇ + B_c sign(q̇)` (paper eq. 9), at the joint (gearbox output).
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(deny_unknown_fields)]
pub struct JointFriction {
    /// Viscous coefficient `B` (N m s/rad).
    pub viscous: f64,
    /// Coulomb coefficient `B_c` (N m).
    pub coulomb: f64,
}

/// Joint limits. Infinite where unknown.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointLimits {
    /// Lower position limit (rad or m).
    pub lower: f64,
    /// Upper position limit (rad or m).
    pub upper: f64,
    /// Speed limit (rad/s or m/s).
    pub velocity: f64,
    /// Torque limit at the joint (N m or N).
    pub effort: f64,
    /// Acceleration limit (rad/s² or m/s²), for the motions physid designs.
    #[serde(default = "unlimited")]
    pub acceleration: f64,
    /// Jerk limit (rad/s³ or m/s³), for the motions physid designs.
    #[serde(default = "unlimited")]
    pub jerk: f64,
}

fn unlimited() -> f64 {
    f64::INFINITY
}

impl Default for JointLimits {
    fn default() -> Self {
        Self {
            lower: f64::NEG_INFINITY,
            upper: f64::INFINITY,
            velocity: f64::INFINITY,
            effort: f64::INFINITY,
            acceleration: f64::INFINITY,
            jerk: f64::INFINITY,
        }
    }
}

/// One moving body and the joint that connects it to its parent.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Body {
    /// Body (link) name.
    pub name: String,
    /// Name of the joint whose successor this body is.
    pub joint_name: String,
    /// Parent body index, `None` for the fixed base.
    pub parent: Option<usize>,
    /// The joint type and axis.
    pub joint: Joint,
    /// Transform from the parent frame to this joint's frame at `q = 0`.
    pub x_tree: Transform,
    /// Inertial parameters in this body's joint frame.
    pub inertia: InertialParams,
    /// Bounding ellipsoid in this body's frame, if known.
    pub bounding: Option<Ellipsoid>,
    /// The description's shapes (collision, else visual) in this body's frame, for export only
    /// (dynamics never reads them).
    pub shapes: Vec<Shape>,
    /// The rotor this joint drives, if any.
    pub rotor: Option<Rotor>,
    /// Joint friction (the truth, for simulation; identified otherwise).
    pub friction: JointFriction,
    /// Joint limits.
    pub limits: JointLimits,
}

/// A shape of a body as the description gives it, placed in the body's frame.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Shape {
    /// The shape's frame: its pose in the body frame (`from_pose` convention).
    pub pose: Transform,
    /// What it is.
    pub kind: ShapeKind,
}

/// URDF's geometry kinds (m).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum ShapeKind {
    /// A box of full side lengths `size`, centred.
    Box {
        /// Full side lengths (m).
        size: [f64; 3],
    },
    /// A cylinder along z, centred.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Full length (m).
        length: f64,
    },
    /// A capsule along z (cylinder part of `length`), centred.
    Capsule {
        /// Radius (m).
        radius: f64,
        /// Length of the cylinder part (m).
        length: f64,
    },
    /// A sphere, centred.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// A mesh file (found on disk), scaled.
    Mesh {
        /// The resolved file.
        path: std::path::PathBuf,
        /// Scale per axis.
        scale: [f64; 3],
    },
}

/// How rotors enter the dynamics.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum RotorModel {
    /// Each rotor is a body spinning at `N q̇` on its parent (gyroscopic coupling kept).
    #[default]
    Full,
    /// Reflected inertia: the rotor is frozen onto its parent and its spin inertia appears only
    /// as the armature `N² I_axis` on the diagonal of `H` (what MuJoCo's `armature` does).
    Reflected,
}

/// Where each group of parameters sits in the model's parameter vector `θ`.
///
/// `θ = [π_link_0, …, π_link_{n−1}, π_rotor (in joint order, for joints with a rotor),
/// B_0 … B_{n−1}, B_c0 … B_c{n−1}]`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ParamLayout {
    /// First column of each rotor's ten parameters, by joint; `None` for joints without one.
    pub rotor_col: Vec<Option<usize>>,
    /// First viscous-friction column.
    pub viscous_col: usize,
    /// First Coulomb-friction column.
    pub coulomb_col: usize,
    /// Total number of parameters.
    pub len: usize,
}

/// A validated, immutable robot model. Build it with [`Model::new`]; workspaces live in
/// [`crate::dynamics::Data`].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Model {
    /// Robot name.
    name: String,
    /// Bodies, parents first.
    bodies: Vec<Body>,
    /// Gravity in the base frame (m/s²).
    gravity: Vector3<f64>,
    /// How rotors enter the dynamics.
    rotor_model: RotorModel,
    /// The static base's shapes as the description gives them (in the base frame), for export
    /// only.
    base_shapes: Vec<Shape>,
    /// Rotor on the base frame's pose is fixed; rotors on bodies move with them.
    layout: ParamLayout,
    /// `support[i]`: joint `i` and its ancestors, nearest first.
    support: Vec<Vec<usize>>,
}

/// Standard gravity pointing down the base z axis (m/s²).
pub const STANDARD_GRAVITY: f64 = 9.81;

impl Model {
    /// Validates the structure and builds the model. Physical consistency of the inertias is
    /// checked separately by [`Model::check_physical`], because identified models may violate it.
    pub fn new(
        name: impl Into<String>,
        bodies: Vec<Body>,
        gravity: Vector3<f64>,
    ) -> Result<Self, ModelError> {
        if bodies.is_empty() {
            return Err(ModelError::Empty);
        }
        let mut names = std::collections::HashSet::new();
        let mut joint_names = std::collections::HashSet::new();
        let mut bodies = bodies;
        for (i, b) in bodies.iter_mut().enumerate() {
            check_body(i, b, &mut names, &mut joint_names)?;
        }
        if !gravity.iter().all(|g| g.is_finite()) {
            return Err(ModelError::BadValue {
                element: "model".into(),
                field: "gravity",
                reason: "not finite".into(),
            });
        }
        let layout = ParamLayout::of(&bodies);
        let support = support_of(&bodies);
        Ok(Self {
            name: name.into(),
            bodies,
            gravity,
            rotor_model: RotorModel::Full,
            base_shapes: vec![],
            layout,
            support,
        })
    }

    /// The same model with the base's description shapes (for export).
    pub fn with_base_shapes(mut self, shapes: Vec<Shape>) -> Self {
        self.base_shapes = shapes;
        self
    }

    /// The same model with another rotor treatment.
    pub fn with_rotor_model(mut self, rotor_model: RotorModel) -> Self {
        self.rotor_model = rotor_model;
        self
    }

    /// The same model under another gravity vector (m/s², base frame).
    pub fn with_gravity(mut self, gravity: Vector3<f64>) -> Self {
        self.gravity = gravity;
        self
    }

    /// The same model with every bounding ellipsoid scaled about its centre by `s`.
    pub fn with_ellipsoids_scaled(mut self, s: f64) -> Model {
        for b in &mut self.bodies {
            b.bounding = b.bounding.map(|e| e.scaled(s));
            if let Some(r) = b.rotor.as_mut() {
                r.bounding = r.bounding.map(|e| e.scaled(s));
            }
        }
        self
    }

    /// The link-only model: every rotor removed (its parameters leave the layout).
    pub fn without_rotors(&self) -> Model {
        let bodies = self
            .bodies
            .iter()
            .cloned()
            .map(|b| Body { rotor: None, ..b })
            .collect();
        Model::new(self.name.clone(), bodies, self.gravity)
            .expect("removing rotors keeps a valid model")
    }

    /// The model of a designer who left the rotors' spin out: each rotor's mass properties are
    /// added to the body it sits on (the parent of its joint's body; lost for a rotor on the
    /// fixed base), and the rotors removed. What is missing is then only what spinning adds:
    /// the reflected inertia `N² I_axis` and the gyroscopic coupling.
    pub fn with_rotors_frozen(&self) -> Model {
        let mut m = self.without_rotors();
        for b in &self.bodies {
            if let (Some(r), Some(p)) = (&b.rotor, b.parent) {
                let frozen = r.inertia.transformed(&r.x_rot.inverse());
                m.bodies[p].inertia = InertialParams(m.bodies[p].inertia.0 + frozen.0);
            }
        }
        m
    }

    /// The robot's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The bodies, parents first (body `i` moves with joint `i`).
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// The joints' names, in body order (joint `i` moves body `i`).
    pub fn joint_names(&self) -> Vec<String> {
        self.bodies.iter().map(|b| b.joint_name.clone()).collect()
    }

    /// Gravity in the base frame (m/s²).
    pub fn gravity(&self) -> Vector3<f64> {
        self.gravity
    }

    /// How rotors enter the dynamics.
    pub fn rotor_model(&self) -> RotorModel {
        self.rotor_model
    }

    /// The static base's shapes as the description gives them (base frame), for export only.
    pub fn base_shapes(&self) -> &[Shape] {
        &self.base_shapes
    }

    /// A copy with each body edited by `edit(i, body)`, validated again as [`Model::new`]
    /// validates (the tree, the rotors, finite parameters), its name, gravity, rotor model and
    /// base shapes kept: the model stays immutable, and an edit cannot leave its layout stale.
    pub fn with_bodies_edited(
        &self,
        mut edit: impl FnMut(usize, &mut Body),
    ) -> Result<Model, ModelError> {
        let mut bodies = self.bodies.clone();
        for (i, b) in bodies.iter_mut().enumerate() {
            edit(i, b);
        }
        Ok(Model::new(self.name.clone(), bodies, self.gravity)?
            .with_rotor_model(self.rotor_model)
            .with_base_shapes(self.base_shapes.clone()))
    }

    /// Number of degrees of freedom (one per joint).
    pub fn dof(&self) -> usize {
        self.bodies.len()
    }

    /// Number of rotors.
    pub fn rotor_count(&self) -> usize {
        self.bodies.iter().filter(|b| b.rotor.is_some()).count()
    }

    /// The parameter layout.
    pub fn layout(&self) -> &ParamLayout {
        &self.layout
    }

    /// Joint `i` and its ancestors, nearest first.
    pub fn support(&self, i: usize) -> &[usize] {
        &self.support[i]
    }

    /// The full parameter vector `θ` (see [`ParamLayout`]).
    pub fn parameters(&self) -> DVector<f64> {
        let l = &self.layout;
        let mut th = DVector::zeros(l.len);
        for (i, b) in self.bodies.iter().enumerate() {
            th.rows_mut(10 * i, 10).copy_from(&b.inertia.0);
            if let (Some(c), Some(r)) = (l.rotor_col[i], &b.rotor) {
                th.rows_mut(c, 10).copy_from(&r.inertia.0);
            }
            th[l.viscous_col + i] = b.friction.viscous;
            th[l.coulomb_col + i] = b.friction.coulomb;
        }
        th
    }

    /// Human-readable names of the parameters, e.g. `thigh.Ixz`, `knee_rotor.m`, `knee.B`.
    pub fn parameter_names(&self) -> Vec<String> {
        let names = crate::spatial::PARAM_NAMES;
        let mut out = vec![String::new(); self.layout.len];
        for (i, b) in self.bodies.iter().enumerate() {
            for k in 0..10 {
                out[10 * i + k] = format!("{}.{}", b.name, names[k]);
            }
            if let (Some(c), Some(r)) = (self.layout.rotor_col[i], &b.rotor) {
                for k in 0..10 {
                    out[c + k] = format!("{}.{}", r.name, names[k]);
                }
            }
            out[self.layout.viscous_col + i] = format!("{}.B", b.joint_name);
            out[self.layout.coulomb_col + i] = format!("{}.Bc", b.joint_name);
        }
        out
    }

    /// A copy with all inertial and friction parameters replaced by `theta` (same layout).
    /// Only finiteness is checked: identified parameters may be physically inconsistent.
    pub fn with_parameters(&self, theta: &DVector<f64>) -> Result<Model, ModelError> {
        let l = &self.layout;
        if theta.len() != l.len {
            return Err(ModelError::ParamLength {
                expected: l.len,
                got: theta.len(),
            });
        }
        let mut m = self.clone();
        let take = |c: usize| InertialParams(theta.fixed_rows::<10>(c).into_owned());
        for (i, b) in m.bodies.iter_mut().enumerate() {
            b.inertia = take(10 * i);
            check_params(&format!("body '{}'", b.name), &b.inertia)?;
            if let (Some(c), Some(r)) = (l.rotor_col[i], b.rotor.as_mut()) {
                r.inertia = take(c);
                check_params(&format!("rotor '{}'", r.name), &r.inertia)?;
            }
            b.friction = JointFriction {
                viscous: theta[l.viscous_col + i],
                coulomb: theta[l.coulomb_col + i],
            };
        }
        Ok(m)
    }

    /// Checks that every body and rotor has a positive mass (a massless leaf is allowed only if
    /// its whole inertia is zero) and a pseudo-inertia `J(π) ⪰ 0` up to a round-off tolerance of
    /// `1e-12 · ‖J‖`, and that each has a bounding ellipsoid containing it when one is given.
    pub fn check_physical(&self) -> Result<(), ModelError> {
        self.check_physical_with(true)
    }

    /// [`Model::check_physical`], checking containment in the bounding ellipsoids only when
    /// `bounds` is true (a description whose nominal inertia escapes the ellipsoid of its own
    /// geometry is still a valid model; the loader warns instead).
    pub fn check_physical_with(&self, bounds: bool) -> Result<(), ModelError> {
        let check = |element: String, p: &InertialParams, e: Option<&Ellipsoid>| {
            check_physical_element(element, p, e.filter(|_| bounds))
        };
        for b in &self.bodies {
            check(
                format!("body '{}'", b.name),
                &b.inertia,
                b.bounding.as_ref(),
            )?;
            if let Some(r) = &b.rotor {
                check(
                    format!("rotor '{}'", r.name),
                    &r.inertia,
                    r.bounding.as_ref(),
                )?;
            }
        }
        Ok(())
    }

    /// Total mass of links and rotors (kg).
    pub fn total_mass(&self) -> f64 {
        self.bodies
            .iter()
            .map(|b| b.inertia.mass() + b.rotor.as_ref().map_or(0.0, |r| r.inertia.mass()))
            .sum()
    }

    /// Index of a joint by name.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.bodies.iter().position(|b| b.joint_name == name)
    }
}

fn check_transform(element: &str, field: &'static str, x: &Transform) -> Result<(), ModelError> {
    if !x.e.iter().chain(x.r.iter()).all(|v| v.is_finite()) {
        return Err(ModelError::BadValue {
            element: element.into(),
            field,
            reason: "not finite".into(),
        });
    }
    let ortho = (x.e * x.e.transpose() - nalgebra::Matrix3::identity()).norm();
    if ortho > 1e-9 || x.e.determinant() < 0.0 {
        return Err(ModelError::BadValue {
            element: element.into(),
            field,
            reason: format!("rotation is not proper orthonormal (error {ortho:.2e})"),
        });
    }
    Ok(())
}

fn check_params(element: &str, p: &InertialParams) -> Result<(), ModelError> {
    if let Some(k) = p.0.iter().position(|v| !v.is_finite()) {
        return Err(ModelError::BadValue {
            element: element.into(),
            field: "inertial",
            reason: format!("parameter {} is {}", crate::spatial::PARAM_NAMES[k], p.0[k]),
        });
    }
    Ok(())
}

/// Checks body `i` (names unique, parent before it, joint axis and origin, inertia, friction,
/// limits, rotor) and normalizes its joint and rotor axes.
fn check_body(
    i: usize,
    b: &mut Body,
    names: &mut std::collections::HashSet<String>,
    joint_names: &mut std::collections::HashSet<String>,
) -> Result<(), ModelError> {
    if !names.insert(b.name.clone()) {
        return Err(ModelError::DuplicateName {
            what: "body",
            name: b.name.clone(),
        });
    }
    if !joint_names.insert(b.joint_name.clone()) {
        return Err(ModelError::DuplicateName {
            what: "joint",
            name: b.joint_name.clone(),
        });
    }
    if let Some(p) = b.parent {
        if p >= i {
            return Err(ModelError::BadParent {
                body: b.name.clone(),
                index: i,
                parent: p,
            });
        }
    }
    let jn = format!("joint '{}'", b.joint_name);
    b.joint = b
        .joint
        .normalized()
        .map_err(|reason| ModelError::BadValue {
            element: jn.clone(),
            field: "axis",
            reason,
        })?;
    check_transform(&jn, "origin", &b.x_tree)?;
    check_params(&format!("body '{}'", b.name), &b.inertia)?;
    let f = &b.friction;
    for (field, v) in [
        ("friction.viscous", f.viscous),
        ("friction.coulomb", f.coulomb),
    ] {
        if !v.is_finite() || v < 0.0 {
            return Err(ModelError::BadValue {
                element: jn.clone(),
                field,
                reason: format!("{v} is not a finite non-negative number"),
            });
        }
    }
    // The rotor first: its gear ratio scales the joint's limits, so a zero ratio is named as
    // such rather than as the effort limit it zeroes.
    if let Some(r) = &mut b.rotor {
        check_rotor(r, names)?;
    }
    check_limits(&jn, &b.limits)
}

/// Checks the limits of joint `jn`: an ordered position range, positive rates and effort.
fn check_limits(jn: &str, l: &JointLimits) -> Result<(), ModelError> {
    if l.lower.is_nan() || l.upper.is_nan() || l.lower > l.upper {
        return Err(ModelError::BadValue {
            element: jn.to_string(),
            field: "limits",
            reason: format!("lower {} must not exceed upper {}", l.lower, l.upper),
        });
    }
    for (field, v) in [
        ("limits.velocity", l.velocity),
        ("limits.effort", l.effort),
        ("limits.acceleration", l.acceleration),
        ("limits.jerk", l.jerk),
    ] {
        // Positive, or infinite where unknown; a zero or negative limit stops the joint.
        if v.is_nan() || v <= 0.0 {
            return Err(ModelError::BadValue {
                element: jn.to_string(),
                field,
                reason: format!("{v} must be > 0 (or left out when unknown)"),
            });
        }
    }
    Ok(())
}

/// Checks a rotor (gear ratio, axis, origin, inertia, unique name) and normalizes its axis.
fn check_rotor(
    r: &mut Rotor,
    names: &mut std::collections::HashSet<String>,
) -> Result<(), ModelError> {
    let rn = format!("rotor '{}'", r.name);
    if !r.gear_ratio.is_finite() || r.gear_ratio == 0.0 {
        return Err(ModelError::BadValue {
            element: rn,
            field: "gear_ratio",
            reason: format!("{} must be finite and non-zero", r.gear_ratio),
        });
    }
    r.joint = r
        .joint
        .normalized()
        .map_err(|reason| ModelError::BadValue {
            element: rn.clone(),
            field: "axis",
            reason,
        })?;
    check_transform(&rn, "origin", &r.x_rot)?;
    check_params(&rn, &r.inertia)?;
    if !names.insert(r.name.clone()) {
        return Err(ModelError::DuplicateName {
            what: "body",
            name: r.name.clone(),
        });
    }
    Ok(())
}

impl ParamLayout {
    /// The layout of θ for `bodies`: ten columns per link, ten per rotor, then viscous and
    /// Coulomb friction per joint (architecture.md §1).
    fn of(bodies: &[Body]) -> Self {
        let n = bodies.len();
        let mut rotor_col = vec![None; n];
        let mut col = 10 * n;
        for (i, b) in bodies.iter().enumerate() {
            if b.rotor.is_some() {
                rotor_col[i] = Some(col);
                col += 10;
            }
        }
        ParamLayout {
            rotor_col,
            viscous_col: col,
            coulomb_col: col + n,
            len: col + 2 * n,
        }
    }
}

/// `support[i]`: joint `i` and its ancestors, nearest first.
fn support_of(bodies: &[Body]) -> Vec<Vec<usize>> {
    (0..bodies.len())
        .map(|i| {
            let mut s = vec![i];
            let mut j = i;
            while let Some(p) = bodies[j].parent {
                s.push(p);
                j = p;
            }
            s
        })
        .collect()
}
/// Checks one element's inertial parameters `p` (named `element` in the error): a mass not
/// negative, zero mass only with zero moments, `J(π) ⪰ 0` (to a tolerance of 10⁻¹² ‖J‖), and
/// the mass inside the bounding ellipsoid `e` when given (`tr(JQ) ≥ 0`).
fn check_physical_element(
    element: String,
    p: &InertialParams,
    e: Option<&Ellipsoid>,
) -> Result<(), ModelError> {
    if p.mass() < 0.0 {
        return Err(ModelError::Inconsistent {
            element,
            reason: format!("negative mass {} kg", p.mass()),
        });
    }
    if p.mass() == 0.0 {
        if p.0.iter().any(|&x| x != 0.0) {
            return Err(ModelError::Inconsistent {
                element,
                reason: "zero mass with non-zero first or second moments".into(),
            });
        }
        return Ok(());
    }
    let r = p.consistency(e);
    let tol = 1e-12 * p.pseudo_inertia().norm();
    if r.min_eig_pseudo < -tol {
        // The same tolerance picks the reason: a rank-one inertia (eigenvalues 0.03, 0, 0)
        // has `λ_min(I) = −3e-18` from rounding, and it is the triangle inequality it breaks.
        let why = if r.min_eig_spatial < -tol {
            "the 6x6 spatial inertia I(pi) is not positive semidefinite"
        } else {
            "the pseudo-inertia J(pi) is not positive semidefinite (principal moments violate the triangle inequality)"
        };
        return Err(ModelError::Inconsistent {
            element,
            reason: format!(
                "{why}; min eig J = {:.3e}, min eig I = {:.3e}",
                r.min_eig_pseudo, r.min_eig_spatial
            ),
        });
    }
    if let Some(t) = r.trace_jq_per_mass {
        if t < 0.0 {
            return Err(ModelError::Inconsistent {
                element,
                reason: format!("mass lies outside its bounding ellipsoid: tr(JQ)/m = {t:.4}"),
            });
        }
    }
    Ok(())
}
