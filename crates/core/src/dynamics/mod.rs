//! Rigid-body dynamics with geared rotors, one algorithm per file, in RBDA's notation:
//!
//! - [`rnea`]: inverse dynamics `τ = H(q) q̈ + C(q, q̇) q̇ + g(q)` (RBDA Table 5.1), with rotors
//!   as in architecture.md §2;
//! - [`crba`]: the joint-space mass matrix `H(q)` (RBDA Table 6.2) with rotor terms;
//! - [`forward_dynamics`]: `q̈ = H⁻¹ (τ − C q̇ − g)` by Cholesky (RBDA §6.1, "FDcrb");
//! - [`regressor`]: `Y(q, q̇, q̈)` with `τ + friction = Y θ` exactly, θ as in
//!   [`crate::model::ParamLayout`];
//! - `energy`: kinetic and potential energy, from body velocities and poses;
//! - [`kinematics`]: world poses, points and point Jacobians.
//!
//! Every function takes the immutable [`Model`] and a mutable [`Data`] workspace (pinocchio's
//! split): no allocation happens on the hot path. Joint vectors are `&[f64]` of length `n`.
//! Units: rad, rad/s, rad/s², N m (prismatic joints: m, m/s, m/s², N).

mod crba;
mod energy;
mod fd;
mod floating;
#[cfg(test)]
mod floating_tests;
mod gravity;
pub mod kinematics;
mod regressor;
mod regressor_slope;
mod rnea;

pub use crba::crba;
pub use energy::{kinetic_energy, potential_energy};
pub use fd::{forward_dynamics, FdError};
pub use floating::{
    crba_floating, point_jacobian_floating, regressor_floating, rnea_floating, stacked, BaseState,
};
pub use gravity::gravity_from_transforms;
pub use regressor::{for_each_regressor, inertia_bilinear, regressor, row_columns};
pub use regressor_slope::weighted_regressor_slope;
pub use rnea::{
    friction_torque, joint_friction, rnea, rnea_after_joint, rnea_from_transforms,
    rnea_with_friction, sign,
};

use crate::model::{Model, Rotor, RotorModel};
use crate::spatial::{Force, Motion, RigidInertia, Transform};
use nalgebra::{DMatrix, DVector};

/// Workspace and results of the dynamics algorithms for one [`Model`].
///
/// After [`forward_pass`], `x_up`, `s`, `v`, `a` and the rotor fields hold the kinematics of the
/// state that was passed; the other fields hold the result of the last algorithm that wrote them.
#[derive(Clone, Debug)]
pub struct Data {
    /// `x_up[i] = i_X_λ(i)`: parent frame to body `i` frame (RBDA `Xup`).
    pub x_up: Vec<Transform>,
    /// Motion subspace of joint `i` in body `i` coordinates.
    pub s: Vec<Motion>,
    /// Spatial velocity of body `i`, body coordinates.
    pub v: Vec<Motion>,
    /// Spatial acceleration of body `i` including the fictitious `−g` base acceleration.
    pub a: Vec<Motion>,
    /// Net spatial force on body `i` (RNEA backward pass).
    pub f: Vec<Force>,
    /// Body `i`'s own term of the backward pass, `I_i a_i + v_i ×* I_i v_i` (body coordinates):
    /// kept apart from `f` so that a pass from a later body reuses it for the bodies before.
    pub f_body: Vec<Force>,
    /// The same of rotor `i` (rotor coordinates; zero where joint `i` has no rotor).
    pub f_rotor: Vec<Force>,
    /// The wrench the root (the fixed base, or a floating trunk) exerts on the tree, root
    /// coordinates `[n; f]` (N m, N): the sum the RNEA's backward pass passes up from the bodies
    /// and rotors mounted on the root.
    pub f_root: Force,
    /// Parent frame to rotor `i` frame (identity where joint `i` has no rotor).
    pub x_rot: Vec<Transform>,
    /// Rotor motion subspace `S_rot = N [axis; 0]`, rotor coordinates (zero in reflected mode).
    pub s_rot: Vec<Motion>,
    /// Rotor spatial velocity.
    pub v_rot: Vec<Motion>,
    /// Rotor spatial acceleration (with `−g`).
    pub a_rot: Vec<Motion>,
    /// Body inertias (operational form), cached from the model.
    pub inertia: Vec<RigidInertia>,
    /// Rotor inertias (zero where none).
    pub inertia_rot: Vec<RigidInertia>,
    /// Composite inertias (CRBA).
    pub ic: Vec<RigidInertia>,
    /// Joint torques (RNEA result).
    pub tau: DVector<f64>,
    /// Mass matrix (CRBA result).
    pub h: DMatrix<f64>,
    /// Bias forces `C q̇ + g` (forward dynamics).
    pub bias: DVector<f64>,
    /// Accelerations (forward dynamics result).
    pub qdd: DVector<f64>,
    /// World (base) to body `i` frame, filled by [`kinematics::update_world`].
    pub x_world: Vec<Transform>,
    /// Cholesky workspace for forward dynamics.
    pub chol: DMatrix<f64>,
    /// A zero joint vector.
    pub zero: Vec<f64>,
    /// `s_anc[i * n + k]`: joint `k`'s motion subspace in body `i` coordinates, for `k` in the
    /// support of `i` (regressor workspace).
    pub s_anc: Vec<Motion>,
}

impl Data {
    /// A workspace sized for `model`.
    pub fn new(model: &Model) -> Self {
        let n = model.dof();
        let zero_i = RigidInertia {
            m: 0.0,
            h: Default::default(),
            ibar: Default::default(),
        };
        Self {
            x_up: vec![Transform::identity(); n],
            s: vec![Motion::zero(); n],
            v: vec![Motion::zero(); n],
            a: vec![Motion::zero(); n],
            f: vec![Force::zero(); n],
            f_body: vec![Force::zero(); n],
            f_rotor: vec![Force::zero(); n],
            f_root: Force::zero(),
            x_rot: vec![Transform::identity(); n],
            s_rot: vec![Motion::zero(); n],
            v_rot: vec![Motion::zero(); n],
            a_rot: vec![Motion::zero(); n],
            inertia: model.bodies().iter().map(|b| b.inertia.rigid()).collect(),
            inertia_rot: model
                .bodies()
                .iter()
                .map(|b| b.rotor.as_ref().map_or(zero_i, |r| r.inertia.rigid()))
                .collect(),
            ic: vec![zero_i; n],
            tau: DVector::zeros(n),
            h: DMatrix::zeros(n, n),
            bias: DVector::zeros(n),
            qdd: DVector::zeros(n),
            x_world: vec![Transform::identity(); n],
            s_anc: vec![Motion::zero(); n * n],
            chol: DMatrix::zeros(n, n),
            zero: vec![0.0; n],
        }
    }

    /// Whether this workspace was made for a model of this shape.
    pub fn fits(&self, model: &Model) -> bool {
        self.x_up.len() == model.dof()
    }
}

/// The fictitious base acceleration `a_0 = [0; −g]` that accounts for gravity (RBDA §5.3).
#[inline]
pub fn base_acceleration(model: &Model) -> Motion {
    Motion::new(Default::default(), -model.gravity())
}

/// Joint and rotor transforms for configuration `q`: fills `x_up`, `s`, `x_rot`, `s_rot`.
///
/// Rotor `i` (architecture.md §2), full model: `X_rot = X_J(N q_i) X_rot,0` and
/// `S_rot = N [axis; 0]`; reflected model: `X_rot = X_rot,0` (frozen) and `S_rot = 0`.
pub fn update_transforms(model: &Model, data: &mut Data, q: &[f64]) {
    debug_assert!(data.fits(model));
    // (Sliced, not truncated: a `q` shorter than the model is a caller's error, as before.)
    for (i, &q_i) in q[..model.dof()].iter().enumerate() {
        update_joint_transform(model, data, i, q_i);
    }
}

/// Joint `i`'s part of [`update_transforms`]: its `x_up`, `s` and its rotor's `x_rot`, `s_rot`
/// at angle `q_i` (rad, or m for a prismatic joint), the other joints' left as they are. With
/// the transforms of a configuration in `data`, this gives those of the configuration that
/// differs from it in joint `i` alone, for one joint's sine and cosine instead of all.
pub fn update_joint_transform(model: &Model, data: &mut Data, i: usize, q_i: f64) {
    let b = &model.bodies()[i];
    data.s[i] = b.joint.motion_subspace();
    data.x_up[i] = b.joint.transform_after(q_i, &b.x_tree);
    if let Some(r) = &b.rotor {
        if model.rotor_model() == RotorModel::Full {
            data.x_rot[i] = r.joint.transform_after(r.gear_ratio * q_i, &r.x_rot);
            data.s_rot[i] = r.motion_subspace();
        } else {
            data.x_rot[i] = r.x_rot;
            data.s_rot[i] = Motion::zero();
        }
    }
}

/// The RNEA forward pass (RBDA Table 5.1, first loop) for bodies and rotors: calls
/// [`update_transforms`], then fills `v`, `a`, `v_rot`, `a_rot`. With `gravity = false` the
/// base does not accelerate (for mass-matrix columns and energy).
///
/// `v_i = X_up,i v_λ(i) + S_i q̇_i`, `a_i = X_up,i a_λ(i) + S_i q̈_i + v_i × S_i q̇_i`, and for the
/// rotor of joint `i` on `p = λ(i)`: `v_rot = X_rot v_p + S_rot q̇_i`,
/// `a_rot = X_rot a_p + S_rot q̈_i + v_rot × S_rot q̇_i` (with `S_rot = 0` when reflected).
pub fn forward_pass(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    gravity: bool,
) {
    update_transforms(model, data, q);
    forward_pass_from_transforms(model, data, qd, qdd, gravity);
}

/// [`forward_pass`] on the transforms already in `data` (from [`update_transforms`] at the
/// configuration wanted): fills `v`, `a`, `v_rot`, `a_rot`.
pub(crate) fn forward_pass_from_transforms(
    model: &Model,
    data: &mut Data,
    qd: &[f64],
    qdd: &[f64],
    gravity: bool,
) {
    let a0 = if gravity {
        base_acceleration(model)
    } else {
        Motion::zero()
    };
    forward_pass_from_root(model, data, qd, qdd, (Motion::zero(), a0));
}

/// [`forward_pass_from_transforms`] with the root (base) moving: `v0` its spatial velocity and
/// `a0` its spatial acceleration, fictitious gravity included, both in root coordinates. For a
/// fixed base `v0 = 0`, `a0 = [0; −g]`; for a floating trunk its own motion.
pub(crate) fn forward_pass_from_root(
    model: &Model,
    data: &mut Data,
    qd: &[f64],
    qdd: &[f64],
    root: (Motion, Motion),
) {
    forward_pass_from_body(model, data, qd, qdd, root, 0);
}

/// [`forward_pass_from_root`] over bodies `first..` only: the bodies before `first` keep the
/// velocities and accelerations in `data` (none of them descends from `first`, as a parent
/// always precedes its children).
pub(crate) fn forward_pass_from_body(
    model: &Model,
    data: &mut Data,
    qd: &[f64],
    qdd: &[f64],
    (v0, a0): (Motion, Motion),
    first: usize,
) {
    for (i, b) in model.bodies().iter().enumerate().skip(first) {
        let (v_p, a_p) = match b.parent {
            Some(p) => (data.v[p], data.a[p]),
            None => (v0, a0),
        };
        let x_up = &data.x_up[i];
        let vj = data.s[i] * qd[i];
        let v = x_up.apply_motion(&v_p) + vj;
        data.a[i] = x_up.apply_motion(&a_p) + data.s[i] * qdd[i] + v.cross_motion(&vj);
        data.v[i] = v;
        if b.rotor.is_some() {
            let x_rot = &data.x_rot[i];
            let vj_rot = data.s_rot[i] * qd[i];
            let v_rot = x_rot.apply_motion(&v_p) + vj_rot;
            data.a_rot[i] =
                x_rot.apply_motion(&a_p) + data.s_rot[i] * qdd[i] + v_rot.cross_motion(&vj_rot);
            data.v_rot[i] = v_rot;
        }
    }
}

/// Armature (kg m²) of joint `i`'s rotor in the reflected model, 0 without a rotor
/// ([`Rotor::armature`]).
#[inline]
pub fn armature(model: &Model, i: usize) -> f64 {
    model.bodies()[i]
        .rotor
        .as_ref()
        .map_or(0.0, Rotor::armature)
}

/// Checks that joint vectors have the model's length (a programming error otherwise).
#[inline]
pub(crate) fn check_len(model: &Model, name: &str, v: &[f64]) {
    assert_eq!(
        v.len(),
        model.dof(),
        "{name} has {} entries, the model has {} joints",
        v.len(),
        model.dof()
    );
}
