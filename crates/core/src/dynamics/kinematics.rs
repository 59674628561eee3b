//! Forward kinematics: world poses of bodies, positions and Jacobians of body-fixed points.
//! "World" is the fixed base frame.

use super::{update_transforms, Data};
use crate::model::Model;
use nalgebra::{DMatrix, Vector3};

/// Fills `data.x_world[i]` (base to body `i`) for configuration `q`, with the joint transforms.
pub fn update_world(model: &Model, data: &mut Data, q: &[f64]) {
    update_transforms(model, data, q);
    for (i, b) in model.bodies().iter().enumerate() {
        data.x_world[i] = match b.parent {
            Some(p) => data.x_up[i].compose(&data.x_world[p]),
            None => data.x_up[i],
        };
    }
}

/// World position (m) of the point `p` fixed in `body` (body coordinates). Call
/// [`update_world`] first.
pub fn point_position(data: &Data, body: usize, p: &Vector3<f64>) -> Vector3<f64> {
    data.x_world[body].point_to_a(p)
}

/// The 3×n linear-velocity Jacobian (world coordinates) of the point `p` fixed in `body`:
/// `ṗ = J q̇`. Column `k` (joints in the support of `body`) is the world-frame motion of
/// `S_k` evaluated at the point. Call [`update_world`] first.
pub fn point_jacobian(model: &Model, data: &Data, body: usize, p: &Vector3<f64>) -> DMatrix<f64> {
    let n = model.dof();
    let pw = point_position(data, body, p);
    let mut jac = DMatrix::zeros(3, n);
    for &k in model.support(body) {
        let col = point_jacobian_column(data, k, &pw);
        jac.fixed_view_mut::<3, 1>(0, k).copy_from(&col);
    }
    jac
}

/// Column `k` of [`point_jacobian`] (joint `k` in the point's support): the world-frame motion
/// of `S_k` evaluated at the point's world position `pw` (m), `ω × pw + v₀`. Call
/// [`update_world`] first.
pub fn point_jacobian_column(data: &Data, k: usize, pw: &Vector3<f64>) -> Vector3<f64> {
    let s0 = data.x_world[k].inv_apply_motion(&data.s[k]);
    s0.lin + s0.ang.cross(pw)
}
