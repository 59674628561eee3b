//! Kinetic and potential energy, computed from body velocities and poses (independently of the
//! RNEA backward pass, so that energy and power balance test the algorithms).

use super::{armature, check_len, forward_pass, kinematics, Data};
use crate::model::{Model, RotorModel};

/// Kinetic energy `T = Σ ½ v_iᵀ I_i v_i` over links and rotors (J). In the reflected model
/// each rotor contributes its frozen-body energy plus `½ N² I_axis q̇_i²`.
pub fn kinetic_energy(model: &Model, data: &mut Data, q: &[f64], qd: &[f64]) -> f64 {
    check_len(model, "qd", qd);
    let zero = vec![0.0; model.dof()];
    forward_pass(model, data, q, qd, &zero, false);
    let mut t = 0.0;
    for (i, b) in model.bodies().iter().enumerate() {
        let v = &data.v[i];
        t += 0.5 * v.dot(&data.inertia[i].mul_motion(v));
        if b.rotor.is_some() {
            let vr = &data.v_rot[i];
            t += 0.5 * vr.dot(&data.inertia_rot[i].mul_motion(vr));
            if model.rotor_model() == RotorModel::Reflected {
                t += 0.5 * armature(model, i) * qd[i] * qd[i];
            }
        }
    }
    t
}

/// Potential energy `U = −Σ g · (m p_c)` over links and rotors (J), zero at the base origin.
pub fn potential_energy(model: &Model, data: &mut Data, q: &[f64]) -> f64 {
    kinematics::update_world(model, data, q);
    let g = model.gravity();
    let mut u = 0.0;
    for (i, b) in model.bodies().iter().enumerate() {
        let x0 = &data.x_world[i];
        let mh = |ii: &crate::spatial::RigidInertia, x: &crate::spatial::Transform| {
            x.e.tr_mul(&ii.h) + x.r * ii.m
        };
        u -= g.dot(&mh(&data.inertia[i], x0));
        if b.rotor.is_some() {
            let xr = match b.parent {
                Some(p) => data.x_rot[i].compose(&data.x_world[p]),
                None => data.x_rot[i],
            };
            u -= g.dot(&mh(&data.inertia_rot[i], &xr));
        }
    }
    u
}
