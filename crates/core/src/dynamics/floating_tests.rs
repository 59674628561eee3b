//! The floating-base dynamics of the built-in quadruped against independent computations: the
//! regressor against the RNEA, the CRBA against RNEA columns, the trunk rows against the rate of
//! change of the whole robot's momentum (finite differences along a smooth motion of trunk and
//! joints), the point Jacobian against the feet's finite-difference velocities, and the joint
//! rows against the fixed-base RNEA when the trunk stands still.

use crate::dynamics::{
    crba_floating, kinematics, point_jacobian_floating, regressor_floating, rnea, rnea_floating,
    stacked, BaseState, Data,
};
use crate::model::floating::FloatingModel;
use crate::model::quadruped::quadruped;
use crate::model::random::random_state;
use crate::model::{cheetah3, RotorModel};
use crate::spatial::{rot_axis_angle, Force, Motion, Transform};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

fn rel(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).norm() / b.norm().max(1e-300)
}

/// A random trunk state: pose, twist and acceleration (seeded).
fn random_base(seed: u64) -> BaseState {
    let [a, b, c] = random_state(seed, 6, 1.5);
    let rot = rot_axis_angle(&Vector3::new(a[0], a[1], a[2]).normalize(), a[3]);
    BaseState {
        pose: Transform::from_pose(&rot, &Vector3::new(a[4], a[5], 0.4)),
        v: Motion::new(
            Vector3::new(b[0], b[1], b[2]),
            Vector3::new(b[3], b[4], b[5]),
        ),
        a: Motion::new(
            Vector3::new(c[0], c[1], c[2]),
            Vector3::new(c[3], c[4], c[5]),
        ),
    }
}

fn robots() -> Vec<(&'static str, FloatingModel)> {
    let full = quadruped();
    let reflected = FloatingModel::new(
        full.trunk().clone(),
        full.tree().clone().with_rotor_model(RotorModel::Reflected),
    )
    .unwrap();
    vec![("full rotors", full), ("reflected rotors", reflected)]
}

#[test]
fn the_regressor_times_the_parameters_is_the_inverse_dynamics() {
    for (label, robot) in robots() {
        let tree = robot.tree();
        let theta = robot.parameters();
        let mut data = Data::new(tree);
        let mut y = DMatrix::zeros(robot.dof(), robot.parameter_count());
        for s in 0..20 {
            let base = random_base(100 + s);
            let [q, qd, qdd] = random_state(s, tree.dof(), 2.0);
            let f_b = rnea_floating(&robot, &mut data, &base, &q, &qd, &qdd);
            let friction = crate::dynamics::friction_torque(tree, &qd);
            let expected = stacked(&f_b, &(&data.tau + friction));
            regressor_floating(&robot, &mut data, &base, (&q, &qd, &qdd), &mut y);
            let e = rel(&(&y * &theta), &expected);
            assert!(e < 1e-12, "{label}, state {s}: relative error {e:e}");
        }
    }
}

/// `M ν̇ + h` of the CRBA and the RNEA at zero acceleration equals the RNEA; `M`'s columns are
/// RNEA differences; `M` is symmetric positive definite and independent of the trunk's pose.
#[test]
fn the_mass_matrix_is_the_rnea_s_and_moves_with_the_robot() {
    for (label, robot) in robots() {
        let tree = robot.tree();
        let n = tree.dof();
        let mut data = Data::new(tree);
        for s in 0..10 {
            let base = random_base(200 + s);
            let [q, qd, qdd] = random_state(30 + s, n, 2.0);
            let m = crba_floating(&robot, &mut data, &q);
            assert!(
                (&m - m.transpose()).norm() < 1e-12 * m.norm(),
                "{label}: not symmetric"
            );
            assert!(
                m.clone().cholesky().is_some(),
                "{label}: not positive definite"
            );
            let at_rest = BaseState {
                a: Motion::zero(),
                ..base
            };
            let h_f = rnea_floating(&robot, &mut data, &at_rest, &q, &qd, &vec![0.0; n]);
            let h = stacked(&h_f, &data.tau);
            let f = rnea_floating(&robot, &mut data, &base, &q, &qd, &qdd);
            let full = stacked(&f, &data.tau);
            let nu_dot =
                DVector::from_iterator(6 + n, base.a.to_vec6().iter().chain(qdd.iter()).copied());
            let e = rel(&(&m * nu_dot + &h), &full);
            assert!(e < 1e-12, "{label}, state {s}: M ν̇ + h vs RNEA {e:e}");
        }
    }
}

/// The pose, twist and acceleration of the trunk and the joints along a smooth motion, by
/// central differences of the pose (the twist) and of the twist (the acceleration).
struct SmoothMotion {
    t: f64,
}

const EPS: f64 = 1e-4;

fn pose_at(t: f64) -> (Matrix3<f64>, Vector3<f64>) {
    let r = rot_axis_angle(
        &Vector3::new(0.3, -0.5, 0.8).normalize(),
        0.7 * t + 0.4 * t * t,
    ) * rot_axis_angle(&Vector3::x(), 0.5 * (1.3 * t).sin());
    let p = Vector3::new(0.2 * t, -0.1 * t * t, 0.45 + 0.05 * (2.0 * t).sin());
    (r, p)
}

fn joints_at(t: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| 0.6 * ((1.0 + 0.3 * k as f64) * t + k as f64).sin())
        .collect()
}

impl SmoothMotion {
    fn twist(t: f64) -> Motion {
        let (r, _) = pose_at(t);
        let (r1, p1) = pose_at(t + EPS);
        let (r0, p0) = pose_at(t - EPS);
        let r_dot = (r1 - r0) / (2.0 * EPS);
        let w = r.transpose() * r_dot;
        let omega = Vector3::new(
            w[(2, 1)] - w[(1, 2)],
            w[(0, 2)] - w[(2, 0)],
            w[(1, 0)] - w[(0, 1)],
        ) * 0.5;
        Motion::new(omega, r.transpose() * (p1 - p0) / (2.0 * EPS))
    }

    fn state(&self, n: usize) -> (BaseState, [Vec<f64>; 3]) {
        let t = self.t;
        let (r, p) = pose_at(t);
        let v = Self::twist(t);
        let a = (Self::twist(t + EPS) - Self::twist(t - EPS)) * (0.5 / EPS);
        let q = joints_at(t, n);
        let (q1, q0) = (joints_at(t + EPS, n), joints_at(t - EPS, n));
        let qd: Vec<f64> = q1
            .iter()
            .zip(&q0)
            .map(|(a, b)| (a - b) / (2.0 * EPS))
            .collect();
        let qdd: Vec<f64> = (0..n)
            .map(|k| (q1[k] - 2.0 * q[k] + q0[k]) / (EPS * EPS))
            .collect();
        let base = BaseState {
            pose: Transform::from_pose(&r, &p),
            v,
            a,
        };
        (base, [q, qd, qdd])
    }
}

/// The whole robot's spatial momentum in world coordinates (about the world origin), and
/// `Σ m c` (kg m), from every body's and rotor's own velocity and pose.
fn momentum(
    robot: &FloatingModel,
    data: &mut Data,
    base: &BaseState,
    q: &[f64],
    qd: &[f64],
) -> (Force, Vector3<f64>) {
    let tree = robot.tree();
    let n = tree.dof();
    rnea_floating(robot, data, base, q, qd, &vec![0.0; n]);
    kinematics::update_world(tree, data, q);
    let i_b = robot.trunk().inertia.rigid();
    let mut h = base.pose.inv_apply_force(&i_b.mul_motion(&base.v));
    let mut mc = base.pose.point_to_a(&(i_b.h / i_b.m.max(1e-300))) * i_b.m;
    let mut add = |x_w: Transform, i: &crate::spatial::RigidInertia, v: &Motion| {
        h += x_w.inv_apply_force(&i.mul_motion(v));
        if i.m > 0.0 {
            mc += x_w.point_to_a(&(i.h / i.m)) * i.m;
        }
    };
    for (i, b) in tree.bodies().iter().enumerate() {
        add(
            data.x_world[i].compose(&base.pose),
            &data.inertia[i],
            &data.v[i],
        );
        if b.rotor.is_some() {
            let x_r0 = match b.parent {
                Some(p) => data.x_rot[i].compose(&data.x_world[p]),
                None => data.x_rot[i],
            };
            add(
                x_r0.compose(&base.pose),
                &data.inertia_rot[i],
                &data.v_rot[i],
            );
        }
    }
    (h, mc)
}

/// Newton–Euler for the whole robot: the wrench on the trunk (world coordinates) plus gravity
/// is the rate of change of the total momentum, by central differences along a smooth motion.
#[test]
fn the_trunk_rows_are_the_rate_of_change_of_the_whole_robot_s_momentum() {
    for (label, robot) in robots() {
        let tree = robot.tree();
        let n = tree.dof();
        let mut data = Data::new(tree);
        let g = tree.gravity();
        for &t in &[0.0, 0.37, 1.1] {
            let (base, [q, qd, qdd]) = SmoothMotion { t }.state(n);
            let f_b = rnea_floating(&robot, &mut data, &base, &q, &qd, &qdd);
            let f_w = base.pose.inv_apply_force(&f_b);
            let at = |dt: f64| {
                let (b, [q, qd, _]) = SmoothMotion { t: t + dt }.state(n);
                momentum(&robot, &mut Data::new(tree), &b, &q, &qd)
            };
            let ((h1, _), (h0, _)) = (at(EPS), at(-EPS));
            let h_dot = (h1 - h0) * (0.5 / EPS);
            let (_, mc) = at(0.0);
            let gravity = Force::new(mc.cross(&g), g * robot.total_mass());
            let lhs = (f_w + gravity).to_vec6();
            let e = (lhs - h_dot.to_vec6()).norm()
                / h_dot.to_vec6().norm().max(gravity.to_vec6().norm());
            assert!(
                e < 1e-6,
                "{label}, t = {t}: f_B + gravity vs dh/dt, relative {e:e}"
            );
        }
    }
}

/// `ṗ_W = J ν` for each foot, against central differences of the feet's world positions.
#[test]
fn the_feet_jacobians_give_their_world_velocities() {
    let robot = quadruped();
    let tree = robot.tree();
    let n = tree.dof();
    let mut data = Data::new(tree);
    let foot = cheetah3::foot_in_shank();
    let world_point = |t: f64, body: usize, data: &mut Data| {
        let (b, [q, _, _]) = SmoothMotion { t }.state(n);
        kinematics::update_world(tree, data, &q);
        b.pose
            .point_to_a(&kinematics::point_position(data, body, &foot))
    };
    for &t in &[0.2, 0.9] {
        let (base, [q, qd, _]) = SmoothMotion { t }.state(n);
        let nu = DVector::from_iterator(6 + n, base.v.to_vec6().iter().chain(qd.iter()).copied());
        for shank in [2, 5, 8, 11] {
            let jac = point_jacobian_floating(&robot, &mut data, &base, &q, (shank, &foot));
            let fd = (world_point(t + EPS, shank, &mut data)
                - world_point(t - EPS, shank, &mut data))
                / (2.0 * EPS);
            let v = &jac * &nu;
            let e = (Vector3::new(v[0], v[1], v[2]) - fd).norm() / fd.norm();
            assert!(e < 1e-6, "foot of body {shank}, t = {t}: {e:e}");
        }
    }
}

/// With the trunk at rest at the world origin, the joint rows are the fixed-base RNEA of the
/// tree and the trunk rows carry the weight of the whole robot.
#[test]
fn a_trunk_at_rest_gives_the_fixed_base_torques_and_carries_the_weight() {
    let robot = quadruped();
    let tree = robot.tree();
    let n = tree.dof();
    let mut data = Data::new(tree);
    let mut fixed = Data::new(tree);
    for s in 0..5 {
        let [q, qd, qdd] = random_state(50 + s, n, 2.0);
        rnea_floating(&robot, &mut data, &BaseState::at_rest(), &q, &qd, &qdd);
        let tau_fixed = rnea(tree, &mut fixed, &q, &qd, &qdd).clone();
        assert!(rel(&data.tau, &tau_fixed) < 1e-14, "state {s}");
        let zero = vec![0.0; n];
        let f = rnea_floating(&robot, &mut data, &BaseState::at_rest(), &q, &zero, &zero);
        let weight = robot.total_mass() * tree.gravity().norm();
        assert!(
            (f.lin.z - weight).abs() < 1e-9 * weight,
            "state {s}: {} vs {weight}",
            f.lin.z
        );
        assert!(f.lin.x.abs() < 1e-9 && f.lin.y.abs() < 1e-9);
    }
}
