//! Recursive Newton–Euler inverse dynamics with geared rotors (RBDA Table 5.1; architecture.md §2).

use super::{
    armature, base_acceleration, check_len, forward_pass_from_body, forward_pass_from_transforms,
    update_joint_transform, update_transforms, Data,
};
use crate::model::{JointFriction, Model, RotorModel};
use crate::spatial::Motion;
use nalgebra::DVector;

/// Inverse dynamics `τ = H(q) q̈ + C(q, q̇) q̇ + g(q)` of links and rotors, at the joints
/// (gearbox output), without friction. Returns `&data.tau`.
///
/// Backward pass: `f_i = I_i a_i + v_i ×* I_i v_i`; `τ_i = S_iᵀ f_i + S_rot,iᵀ f_rot,i`; the
/// parent receives `X_up,iᵀ f_i + X_rot,iᵀ f_rot,i`. In the reflected model the rotor term in
/// `τ_i` is the armature `N² I_axis q̈_i`.
pub fn rnea<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> &'a DVector<f64> {
    check_len(model, "q", q);
    update_transforms(model, data, q);
    rnea_from_transforms(model, data, qd, qdd)
}

/// [`rnea`] on the joint transforms already in `data` (from [`update_transforms`], or
/// [`crate::dynamics::kinematics::update_world`], at the configuration wanted): the same
/// numbers without computing the transforms again. Returns `&data.tau`.
pub fn rnea_from_transforms<'a>(
    model: &Model,
    data: &'a mut Data,
    qd: &[f64],
    qdd: &[f64],
) -> &'a DVector<f64> {
    check_len(model, "qd", qd);
    check_len(model, "qdd", qdd);
    forward_pass_from_transforms(model, data, qd, qdd, true);
    backward_pass(model, data, qdd)
}

/// [`rnea_from_transforms`] of a state that differs from the one `data` holds in joint `j`
/// alone: its angle `q_j` (the joint's transform set for the pass and restored after), rate
/// and acceleration in `qd`, `qdd`. The forward pass starts at body `j` (no body before it
/// descends from it, so their velocities and accelerations in `data` stand), the backward pass
/// is whole but takes their own terms (`I a + v ×* I v`) from `data`. The same numbers as a
/// whole [`rnea`], bit for bit, when the bodies before `j` hold those of `qd`, `qdd`: after a
/// whole pass at the unchanged state, evaluate changed joints from the last to the first.
/// Returns `&data.tau`.
pub fn rnea_after_joint<'a>(
    model: &Model,
    data: &'a mut Data,
    (j, q_j): (usize, f64),
    qd: &[f64],
    qdd: &[f64],
) -> &'a DVector<f64> {
    check_len(model, "qd", qd);
    check_len(model, "qdd", qdd);
    let frame = (data.x_up[j], data.s[j], data.x_rot[j], data.s_rot[j]);
    update_joint_transform(model, data, j, q_j);
    let root = (Motion::zero(), base_acceleration(model));
    forward_pass_from_body(model, data, qd, qdd, root, j);
    backward_pass_from(model, data, qdd, j);
    (data.x_up[j], data.s[j], data.x_rot[j], data.s_rot[j]) = frame;
    &data.tau
}

/// The RNEA's backward pass on the velocities and accelerations in `data` (bodies and rotors):
/// the joint torques into `data.tau` (`q̈` for the reflected rotors' armature), and the wrench
/// on the root into `data.f_root`.
pub(crate) fn backward_pass<'a>(
    model: &Model,
    data: &'a mut Data,
    qdd: &[f64],
) -> &'a DVector<f64> {
    backward_pass_from(model, data, qdd, 0)
}

/// [`backward_pass`] with the own terms (`data.f_body`, `data.f_rotor`) of the bodies before
/// `first` those already in `data` (their motions unchanged since they were computed).
fn backward_pass_from<'a>(
    model: &Model,
    data: &'a mut Data,
    qdd: &[f64],
    first: usize,
) -> &'a DVector<f64> {
    let full = model.rotor_model() == RotorModel::Full;
    for (i, b) in model.bodies().iter().enumerate().skip(first) {
        let (ii, v) = (&data.inertia[i], data.v[i]);
        data.f_body[i] = ii.mul_motion(&data.a[i]) + v.cross_force(&ii.mul_motion(&v));
        if b.rotor.is_some() {
            let (ir, vr) = (&data.inertia_rot[i], data.v_rot[i]);
            data.f_rotor[i] = ir.mul_motion(&data.a_rot[i]) + vr.cross_force(&ir.mul_motion(&vr));
        }
    }
    data.f.copy_from_slice(&data.f_body);
    data.f_root = crate::spatial::Force::zero();
    for i in (0..model.dof()).rev() {
        let b = &model.bodies()[i];
        let mut tau = data.s[i].dot(&data.f[i]);
        let mut to_parent = data.x_up[i].inv_apply_force(&data.f[i]);
        if b.rotor.is_some() {
            let f_rot = data.f_rotor[i];
            tau += if full {
                data.s_rot[i].dot(&f_rot)
            } else {
                armature(model, i) * qdd[i]
            };
            to_parent += data.x_rot[i].inv_apply_force(&f_rot);
        }
        data.tau[i] = tau;
        match b.parent {
            Some(p) => data.f[p] += to_parent,
            None => data.f_root += to_parent,
        }
    }
    &data.tau
}

/// Joint friction `B q̇ + B_c sign(q̇)` of the model's friction coefficients (N m), with
/// `sign(0) = 0`.
pub fn friction_torque(model: &Model, qd: &[f64]) -> DVector<f64> {
    DVector::from_iterator(
        model.dof(),
        model
            .bodies()
            .iter()
            .zip(qd)
            .map(|(b, &w)| joint_friction(&b.friction, w)),
    )
}

/// One joint's friction torque `B q̇ + B_c sign(q̇)` (N m) at its speed `qd` (rad/s), with
/// `sign(0) = 0`: the law of the regressor's friction columns.
#[inline]
pub fn joint_friction(f: &JointFriction, qd: f64) -> f64 {
    f.viscous * qd + f.coulomb * sign(qd)
}

/// `τ` needed at the joints including friction: [`rnea`] plus [`friction_torque`].
pub fn rnea_with_friction(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> DVector<f64> {
    rnea(model, data, q, qd, qdd) + friction_torque(model, qd)
}

/// `sign(x)` with `sign(0) = 0` (the regressor's Coulomb column).
#[inline]
pub fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::quadruped::quadruped;
    use crate::model::random::{random_state, random_tree};

    /// Each joint shifted in turn, from the last to the first, by [`rnea_after_joint`] after one
    /// whole pass: the torques of a whole [`rnea`] at the shifted state, bit for bit; and
    /// different from the unshifted torques (the shift is seen).
    fn shifts_match_whole_passes(model: &Model, seed: u64) {
        let n = model.dof();
        let [q, qd, qdd] = random_state(seed, n, 1.5);
        let mut data = Data::new(model);
        let mut whole = Data::new(model);
        let unshifted = rnea(model, &mut data, &q, &qd, &qdd).clone();
        for j in (0..n).rev() {
            let (mut q_s, mut qd_s, mut qdd_s) = (q.clone(), qd.clone(), qdd.clone());
            q_s[j] += 0.3;
            qd_s[j] -= 0.7;
            qdd_s[j] += 1.1;
            let after = rnea_after_joint(model, &mut data, (j, q_s[j]), &qd_s, &qdd_s).clone();
            let expected = rnea(model, &mut whole, &q_s, &qd_s, &qdd_s);
            assert_eq!(&after, expected, "joint {j} of {}", model.name());
            assert!((&after - &unshifted).amax() > 1e-6, "joint {j}");
        }
    }

    #[test]
    fn a_pass_after_one_joint_equals_the_whole_pass_on_a_branched_tree_and_the_quadruped() {
        for seed in 1..4 {
            shifts_match_whole_passes(&random_tree(seed, 7), seed);
        }
        shifts_match_whole_passes(quadruped().tree(), 9);
    }
}
