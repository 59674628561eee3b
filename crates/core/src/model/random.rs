//! Random kinematic trees with physically consistent bodies and rotors, for identity tests and
//! benchmarks (like spatial_v2's `autoTree`, but with random branching, axes and rotors).

use super::{Body, Joint, JointFriction, JointLimits, Model, Rotor};
use crate::spatial::{rot_axis_angle, skew, InertialParams, Transform};
use nalgebra::{Matrix3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn unit(rng: &mut ChaCha8Rng) -> Vector3<f64> {
    loop {
        let v = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let n = v.norm();
        if n > 0.1 && n <= 1.0 {
            return v / n;
        }
    }
}

fn pose(rng: &mut ChaCha8Rng, reach: f64) -> Transform {
    let rot = rot_axis_angle(&unit(rng), rng.random_range(-3.0..3.0));
    let pos = Vector3::new(
        rng.random_range(-reach..reach),
        rng.random_range(-reach..reach),
        rng.random_range(-reach..reach),
    );
    Transform::from_pose(&rot, &pos)
}

/// A body made of five random point masses within `reach` (m) of `center`: consistent
/// (`J ≻ 0`) by construction.
pub fn random_body(rng: &mut ChaCha8Rng, center: &Vector3<f64>, reach: f64) -> InertialParams {
    let (mut m, mut h, mut ibar) = (0.0, Vector3::zeros(), Matrix3::zeros());
    for _ in 0..5 {
        let mi: f64 = rng.random_range(0.05..1.0);
        let x = center + unit(rng) * rng.random_range(0.0..reach);
        let sx = skew(&x);
        m += mi;
        h += x * mi;
        ibar += mi * sx * sx.transpose();
    }
    InertialParams::from_parts(m, &h, &ibar)
}

/// A random rotor for body `i`: a gear ratio of either sign and magnitude 2–15, mostly
/// spinning, sometimes sliding (a mimic finger).
fn random_rotor(rng: &mut ChaCha8Rng, i: usize) -> Rotor {
    let n_abs = rng.random_range(2.0..15.0);
    let axis = unit(rng);
    let joint = if rng.random_bool(0.8) {
        Joint::Revolute { axis }
    } else {
        Joint::Prismatic { axis }
    };
    Rotor {
        name: format!("rotor{i}"),
        x_rot: pose(rng, 0.1),
        joint,
        gear_ratio: if rng.random_bool(0.5) { n_abs } else { -n_abs },
        inertia: random_body(rng, &Vector3::zeros(), 0.05),
        bounding: None,
    }
}

/// A random tree of `n` bodies: random parents, revolute (mostly) and prismatic joints with
/// random axes, random joint placements, rotors on about half of the joints with gear ratios of
/// either sign, and random friction.
pub fn random_tree(seed: u64, n: usize) -> Model {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let bodies = (0..n)
        .map(|i| {
            let parent = if i == 0 || rng.random_bool(0.2) {
                None
            } else {
                Some(rng.random_range(0..i))
            };
            let axis = unit(&mut rng);
            let joint = if rng.random_bool(0.8) {
                Joint::Revolute { axis }
            } else {
                Joint::Prismatic { axis }
            };
            let rotor = rng.random_bool(0.6).then(|| random_rotor(&mut rng, i));
            let com = Vector3::new(
                rng.random_range(-0.2..0.2),
                rng.random_range(-0.2..0.2),
                rng.random_range(-0.3..0.0),
            );
            Body {
                name: format!("body{i}"),
                joint_name: format!("joint{i}"),
                parent,
                joint,
                x_tree: pose(&mut rng, 0.3),
                inertia: random_body(&mut rng, &com, 0.15),
                bounding: None,
                shapes: vec![],
                rotor,
                friction: JointFriction {
                    viscous: rng.random_range(0.0..0.5),
                    coulomb: rng.random_range(0.0..2.0),
                },
                limits: JointLimits::default(),
            }
        })
        .collect();
    Model::new(
        format!("random{seed}"),
        bodies,
        Vector3::new(0.0, 0.0, -super::STANDARD_GRAVITY),
    )
    .expect("random tree is valid")
}

/// A random state `(q, q̇, q̈)` with entries in ±`scale`.
pub fn random_state(seed: u64, n: usize, scale: f64) -> [Vec<f64>; 3] {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut v = || {
        (0..n)
            .map(|_| rng.random_range(-scale..scale))
            .collect::<Vec<_>>()
    };
    [v(), v(), v()]
}
