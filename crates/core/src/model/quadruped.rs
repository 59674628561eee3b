//! The built-in Cheetah-3-like quadruped: a trunk and four of the built-in legs
//! ([`super::cheetah3`]: ab/ad, hip, knee, each with its rotor behind its gearbox), floating.
//!
//! Legs in Cheetah-Software's order: front right, front left, hind right, hind left (`fr_`,
//! `fl_`, `hr_`, `hl_` before each body, joint and rotor name). The left legs are the built-in
//! leg as it is, its base frame at `(±HIP_X, +HIP_Y, 0)` in the trunk frame; the right legs are
//! its mirror image in the trunk's x–z plane (positions, CoMs and products of inertia with y
//! negated, revolute axes `a ↦ −S a` with `S = diag(1, −1, 1)`, so that the same joint angle
//! gives the mirrored posture), as Cheetah-Software builds them.
//!
//! The trunk is a uniform box of the published Cheetah 3 body (0.60 × 0.256 × 0.20 m) whose
//! mass brings the robot to the published 45 kg (Bledt et al., IROS 2018), its centre of mass
//! 2 cm forward and 1 cm down from the trunk origin so that no product of inertia vanishes by
//! symmetry of the whole robot; its bounding ellipsoid is the box's circumscribed one.

use super::cheetah3::{self, LegOptions};
use super::floating::{FloatingModel, Trunk};
use super::{Body, Joint, Model, ModelError, Rotor};
use crate::spatial::{Ellipsoid, InertialParams, Transform};
use nalgebra::{Matrix3, Vector3};

/// Trunk box, full side lengths (m).
pub const TRUNK_SIZE: [f64; 3] = [0.60, 0.256, 0.20];
/// The whole robot's mass (kg).
pub const ROBOT_MASS: f64 = 45.0;
/// Leg base frames at `(±HIP_X, ±HIP_Y, 0)` in the trunk frame (m).
pub const HIP_X: f64 = 0.30;
/// See [`HIP_X`].
pub const HIP_Y: f64 = 0.20;
/// The trunk's centre of mass in the trunk frame (m).
pub const TRUNK_COM: [f64; 3] = [0.02, 0.0, -0.01];

/// The legs: name prefix, front (+1) or hind (−1), left (+1) or right (−1).
pub const LEGS: [(&str, f64, f64); 4] = [
    ("fr", 1.0, -1.0),
    ("fl", 1.0, 1.0),
    ("hr", -1.0, -1.0),
    ("hl", -1.0, 1.0),
];

/// The quadruped with the default leg options.
pub fn quadruped() -> FloatingModel {
    quadruped_with(&LegOptions::default()).expect("the built-in quadruped is valid")
}

/// The quadruped with every leg built from `o`.
pub fn quadruped_with(o: &LegOptions) -> Result<FloatingModel, ModelError> {
    let leg = cheetah3::leg_with(o)?;
    let mut bodies = vec![];
    for (prefix, front, left) in LEGS {
        let offset = bodies.len();
        let base = Transform::translation(&Vector3::new(front * HIP_X, left * HIP_Y, 0.0));
        for b in leg.bodies() {
            let b = if left > 0.0 { b.clone() } else { mirrored(b) };
            bodies.push(placed(b, prefix, offset, &base));
        }
    }
    let tree = Model::new("cheetah3_quadruped", bodies, leg.gravity())?;
    let legs_mass = tree.total_mass();
    let trunk = Trunk {
        name: "trunk".into(),
        inertia: box_inertia(ROBOT_MASS - legs_mass),
        bounding: Some(Ellipsoid::axis_aligned(
            Vector3::zeros(),
            Vector3::from(TRUNK_SIZE) * (0.5 * 3f64.sqrt()),
        )),
    };
    FloatingModel::new(trunk, tree)
}

/// The quadruped's feet, as contact points: each leg's shank (tree bodies 2, 5, 8, 11, in
/// [`LEGS`]' order) at [`cheetah3::foot_in_shank`].
pub fn feet() -> Vec<(usize, Vector3<f64>)> {
    (0..LEGS.len())
        .map(|l| (3 * l + 2, cheetah3::foot_in_shank()))
        .collect()
}

/// The trunk: a uniform box of mass `m` (kg) and [`TRUNK_SIZE`] centred at [`TRUNK_COM`].
fn box_inertia(m: f64) -> InertialParams {
    let [a, b, c] = TRUNK_SIZE;
    let ic = Matrix3::from_diagonal(&Vector3::new(b * b + c * c, a * a + c * c, a * a + b * b))
        * (m / 12.0);
    InertialParams::from_mass_com_inertia(m, &Vector3::from(TRUNK_COM), &ic)
}

/// Body `b` of a leg renamed with `prefix`, its parent index moved by `offset`, and, for the
/// leg's first body, its joint (and its rotor) placed at the leg's `base` in the trunk.
fn placed(mut b: Body, prefix: &str, offset: usize, base: &Transform) -> Body {
    b.name = format!("{prefix}_{}", b.name);
    b.joint_name = format!("{prefix}_{}", b.joint_name);
    match b.parent {
        Some(p) => b.parent = Some(p + offset),
        None => {
            b.x_tree = b.x_tree.compose(base);
            if let Some(r) = b.rotor.as_mut() {
                r.x_rot = r.x_rot.compose(base);
            }
        }
    }
    if let Some(r) = b.rotor.as_mut() {
        r.name = format!("{prefix}_{}", r.name);
    }
    b
}

/// `S = diag(1, −1, 1)`: the reflection in the x–z plane.
fn reflection() -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, 1.0))
}

/// The mirror image of body `b` in the x–z plane (see the module docs).
fn mirrored(b: &Body) -> Body {
    let mut m = b.clone();
    m.x_tree = mirror_transform(&b.x_tree);
    m.joint = mirror_joint(&b.joint);
    m.inertia = mirror_inertia(&b.inertia);
    m.bounding = b.bounding.as_ref().map(mirror_ellipsoid);
    m.rotor = b.rotor.as_ref().map(|r| Rotor {
        x_rot: mirror_transform(&r.x_rot),
        joint: mirror_joint(&r.joint),
        inertia: mirror_inertia(&r.inertia),
        bounding: r.bounding.as_ref().map(mirror_ellipsoid),
        ..r.clone()
    });
    m
}

fn mirror_transform(x: &Transform) -> Transform {
    let s = reflection();
    Transform {
        e: s * x.e * s,
        r: s * x.r,
    }
}

/// A revolute axis is a pseudo-vector (`S R_a(q) S = R_{−S a}(q)`); a prismatic axis is not.
fn mirror_joint(j: &Joint) -> Joint {
    let s = reflection();
    match *j {
        Joint::Revolute { axis } => Joint::Revolute { axis: -(s * axis) },
        Joint::Prismatic { axis } => Joint::Prismatic { axis: s * axis },
    }
}

fn mirror_inertia(p: &InertialParams) -> InertialParams {
    let s = reflection();
    InertialParams::from_parts(p.mass(), &(s * p.h()), &(s * p.ibar() * s))
}

fn mirror_ellipsoid(e: &Ellipsoid) -> Ellipsoid {
    let s = reflection();
    Ellipsoid {
        center: s * e.center,
        qs: s * e.qs * s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_quadruped_weighs_the_published_mass_with_twelve_joints_and_rotors() {
        let robot = quadruped();
        assert_eq!(robot.joints(), 12);
        assert_eq!(robot.dof(), 18);
        assert_eq!(robot.tree().rotor_count(), 12);
        assert_eq!(robot.parameter_count(), 10 + 12 * 20 + 24);
        assert!((robot.total_mass() - ROBOT_MASS).abs() < 1e-12);
        assert!(robot.trunk().inertia.mass() > 20.0);
        let names = robot.parameter_names();
        assert_eq!(names[0], "trunk.m");
        assert_eq!(names[10], "fr_abad.m");
        assert!(names.contains(&"hl_knee_rotor.Izz".to_string()));
        assert!(names.contains(&"fl_knee_joint.Bc".to_string()));
    }

    #[test]
    fn every_body_is_consistent_and_inside_its_ellipsoid_mirrored_or_not() {
        let robot = quadruped();
        let t = &robot.trunk();
        assert!(t.inertia.consistency(t.bounding.as_ref()).in_ellipsoid());
        for b in robot.tree().bodies() {
            let r = b.inertia.consistency(b.bounding.as_ref());
            assert!(r.in_ellipsoid() && r.consistent(), "{}: {r:?}", b.name);
            let rot = b.rotor.as_ref().expect("every joint has its rotor");
            let rr = rot.inertia.consistency(rot.bounding.as_ref());
            assert!(rr.in_ellipsoid() && rr.consistent(), "{}: {rr:?}", rot.name);
        }
    }

    #[test]
    fn a_right_leg_is_the_mirror_image_of_its_left_leg() {
        // With the same joint angles, every point of the front-right leg is the front-left
        // leg's point reflected in the trunk's x–z plane.
        use crate::dynamics::{kinematics, Data};
        let robot = quadruped();
        let tree = robot.tree();
        let mut data = Data::new(tree);
        let leg = [0.3, -0.8, 1.7];
        let q: Vec<f64> = (0..4).flat_map(|_| leg).collect();
        kinematics::update_world(tree, &mut data, &q);
        let foot = cheetah3::foot_in_shank();
        let right = kinematics::point_position(&data, 2, &foot);
        let left = kinematics::point_position(&data, 5, &foot);
        assert!(
            (right - reflection() * left).norm() < 1e-12,
            "{right} vs {left}"
        );
        assert!(left.y > HIP_Y * 0.5 && right.y < -HIP_Y * 0.5);
    }
}
