//! MJCF export for MuJoCo cross-checks.
//!
//! MuJoCo has no geared rotor body, so each rotor is exported as physid's
//! [`RotorModel::Reflected`](crate::model::RotorModel::Reflected): the rotor's inertia is lumped
//! into its parent body (frozen at zero rotor angle) and its spin inertia becomes the joint's
//! `armature = N² I_axis`. MuJoCo's `mj_inverse` on this file therefore equals physid's RNEA in
//! reflected mode. Friction, damping and limits are left out so that `mj_inverse` gives the pure
//! rigid-body torque; no geoms are written (inertias are explicit).

use crate::model::{Joint, Model, Rotor};
use crate::spatial::InertialParams;
use nalgebra::{Rotation3, UnitQuaternion, Vector3};
use std::fmt::Write;

fn v3(v: &Vector3<f64>) -> String {
    format!("{} {} {}", v.x, v.y, v.z)
}

/// Each body's inertia with the rotors mounted on it lumped in (body frame).
pub fn lumped_inertias(model: &Model) -> Vec<InertialParams> {
    let mut out: Vec<InertialParams> = model.bodies.iter().map(|b| b.inertia).collect();
    for b in &model.bodies {
        if let (Some(p), Some(r)) = (b.parent, &b.rotor) {
            out[p] = InertialParams(out[p].0 + r.inertia.transformed(&r.x_rot.inverse()).0);
        }
    }
    out
}

/// The model as MJCF text (see the module docs).
pub fn to_string(model: &Model) -> String {
    let inertias = lumped_inertias(model);
    let mut s = String::new();
    let _ = writeln!(s, "<mujoco model=\"{}\">", model.name);
    let _ = writeln!(
        s,
        "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>"
    );
    let _ = writeln!(
        s,
        "  <option gravity=\"{}\" timestep=\"0.001\" integrator=\"RK4\"/>",
        v3(&model.gravity)
    );
    let _ = writeln!(s, "  <worldbody>");
    fn body(model: &Model, inertias: &[InertialParams], i: usize, depth: usize, s: &mut String) {
        let b = &model.bodies[i];
        let pad = "  ".repeat(depth + 2);
        let (rot, pos) = b.x_tree.to_pose();
        let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rot));
        let _ = writeln!(
            s,
            "{pad}<body name=\"{}\" pos=\"{}\" quat=\"{} {} {} {}\">",
            b.name,
            v3(&pos),
            q.w,
            q.i,
            q.j,
            q.k
        );
        let p = &inertias[i];
        let (c, ic) = (
            p.com().unwrap_or_default(),
            p.inertia_about_com().unwrap_or_default(),
        );
        let _ = writeln!(
            s,
            "{pad}  <inertial pos=\"{}\" mass=\"{}\" fullinertia=\"{} {} {} {} {} {}\"/>",
            v3(&c),
            p.mass(),
            ic[(0, 0)],
            ic[(1, 1)],
            ic[(2, 2)],
            ic[(0, 1)],
            ic[(0, 2)],
            ic[(1, 2)]
        );
        let (kind, axis) = match b.joint {
            Joint::Revolute { axis } => ("hinge", axis),
            Joint::Prismatic { axis } => ("slide", axis),
        };
        let _ = writeln!(
            s,
            "{pad}  <joint name=\"{}\" type=\"{kind}\" axis=\"{}\" armature=\"{}\" damping=\"0\" frictionloss=\"0\" limited=\"false\"/>",
            b.joint_name,
            v3(&axis),
            model.bodies[i].rotor.as_ref().map_or(0.0, Rotor::armature)
        );
        for c in (0..model.dof()).filter(|&c| model.bodies[c].parent == Some(i)) {
            body(model, inertias, c, depth + 1, s);
        }
        let _ = writeln!(s, "{pad}</body>");
    }
    for i in (0..model.dof()).filter(|&i| model.bodies[i].parent.is_none()) {
        body(model, &inertias, i, 0, &mut s);
    }
    let _ = writeln!(s, "  </worldbody>");
    let _ = writeln!(s, "</mujoco>");
    s
}
