//! A floating-base robot on flat ground in rapier3d, a second contact engine for physid's own
//! ([`super::floating`]): the same trunk and tree as one rapier multibody whose root is free,
//! a ball collider at each foot point, a fixed ground, and the experiment's controller.
//!
//! rapier's contact is its own: a velocity-level constraint with Coulomb friction solved at
//! every step (penetration corrected softly, by its default integration parameters), not
//! physid's spring and damper under a point foot. The ball is centred on the foot point and
//! the ground's surface lies a radius below `z = 0`, so a foot touches where physid's point
//! foot does; with a millimetre radius its rolling is negligible.

use super::floating::{Standing, Start};
use super::rapier::{RapierError, RapierSim};
use nalgebra::{Matrix3, Vector3};
use physid_core::dynamics::Data;
use physid_core::model::floating::FloatingModel;
use rapier3d_f64::prelude::*;

/// The ball at each foot (m) where [`standing_in_rapier`] is not told otherwise.
pub const FOOT_RADIUS: f64 = 0.001;

/// The robot in rapier: the multibody, its trunk and its feet's colliders.
pub struct RapierFloating {
    sim: RapierSim,
    trunk: RigidBodyHandle,
    feet: Vec<ColliderHandle>,
}

/// What a run in rapier records at each control step: the trunk's pose, the joints, and each
/// foot's normal force.
#[derive(Clone, Debug, Default)]
pub struct EngineRun {
    /// Time (s).
    pub t: Vec<f64>,
    /// The trunk's orientation (world from trunk) and its origin's position (m, world).
    pub trunk: Vec<(Matrix3<f64>, Vector3<f64>)>,
    /// The trunk origin's velocity (m/s, world).
    pub velocity: Vec<Vector3<f64>>,
    /// Joint angles (rad), `joints` per step.
    pub q: Vec<f64>,
    /// The ground's normal force on each foot (N), `feet` per step, over the step before.
    pub normal: Vec<f64>,
    /// Joints.
    pub joints: usize,
    /// Feet.
    pub feet: usize,
}

impl RapierFloating {
    /// The robot with its trunk's origin at `pos` (m, world; the trunk level), moving at
    /// `velocity` (m/s, world), its joints at `q` (rad) and at rest, a ball of `radius` (m) at
    /// each of `feet` (`(body, point in the body)`), on a ground of friction `mu`, stepped by
    /// `dt` (s).
    pub fn new(
        robot: &FloatingModel,
        feet: &[(usize, Vector3<f64>)],
        (pos, velocity, q): (Vector3<f64>, Vector3<f64>, &[f64]),
        (mu, radius): (f64, f64),
        dt: f64,
    ) -> Result<Self, RapierError> {
        check_start(robot, (&pos, &velocity, q), (mu, radius), dt)?;
        let mut bodies = RigidBodySet::new();
        let trunk = bodies.insert(
            RigidBodyBuilder::dynamic()
                .additional_mass_properties(super::rapier::mass_properties(&robot.trunk().inertia))
                .build(),
        );
        let mut sim = RapierSim::hung_from(robot.tree(), bodies, trunk, dt)?;
        let ground = sim.bodies.insert(RigidBodyBuilder::fixed().build());
        let slab = ColliderBuilder::cuboid(50.0, 50.0, 0.5)
            .translation(Vector::new(0.0, 0.0, -0.5 - radius))
            .friction(mu)
            .build();
        sim.colliders
            .insert_with_parent(slab, ground, &mut sim.bodies);
        let mut handles = vec![];
        for &(b, ref p) in feet {
            let ball = ColliderBuilder::ball(radius)
                .translation(Vector::new(p.x, p.y, p.z))
                .friction(mu)
                .build();
            let link = sim.link(b);
            handles.push(
                sim.colliders
                    .insert_with_parent(ball, link, &mut sim.bodies),
            );
        }
        let qd = vec![0.0; q.len()];
        let root = (
            [pos.x, pos.y, pos.z, 0.0, 0.0, 0.0],
            [velocity.x, velocity.y, velocity.z, 0.0, 0.0, 0.0],
        );
        sim.set_state(q, &qd, Some(root));
        Ok(Self {
            sim,
            trunk,
            feet: handles,
        })
    }

    /// Advances one step with the joint torques `tau` (N m) held.
    pub fn step_with_torque(&mut self, tau: &[f64]) {
        self.sim.step_with_torque(tau);
    }

    /// Joint angles (rad) and rates (rad/s).
    pub fn joints(&self) -> (Vec<f64>, Vec<f64>) {
        self.sim.state()
    }

    /// The trunk's orientation (world from trunk), its origin's position (m) and velocity
    /// (m/s), world axes.
    pub fn trunk(&self) -> (Matrix3<f64>, Vector3<f64>, Vector3<f64>) {
        let body = &self.sim.bodies[self.trunk];
        let pose = body.position();
        let m = rapier3d_f64::math::Matrix::from_quat(pose.rotation);
        let rot = Matrix3::from_fn(|i, j| m.col(j)[i]);
        let t = pose.translation;
        let origin = Vector::new(t.x, t.y, t.z);
        let v = body.velocity_at_point(origin);
        (
            rot,
            Vector3::new(t.x, t.y, t.z),
            Vector3::new(v.x, v.y, v.z),
        )
    }

    /// The ground's normal force on each foot (N) over the last step: its contact impulse
    /// over the step's length.
    pub fn normal_forces(&self) -> Vec<f64> {
        let dt = self.sim.params.dt;
        self.feet
            .iter()
            .map(|&c| {
                self.sim
                    .narrow_phase
                    .contact_pairs_with(c)
                    .map(|pair| pair.total_impulse().z.abs())
                    .sum::<f64>()
                    / dt
            })
            .collect()
    }
}

/// `Err` naming what is out of range in [`RapierFloating::new`]'s arguments.
fn check_start(
    robot: &FloatingModel,
    (pos, velocity, q): (&Vector3<f64>, &Vector3<f64>, &[f64]),
    (mu, radius): (f64, f64),
    dt: f64,
) -> Result<(), RapierError> {
    let bad = |what: &str, v: f64| {
        RapierError::Unsupported(format!("floating robot on the ground: {what}, got {v}"))
    };
    if !(radius.is_finite() && radius > 0.0 && radius <= 0.1) {
        return Err(bad(
            "the feet's radius must be above 0 and at most 0.1 m",
            radius,
        ));
    }
    if !(mu.is_finite() && mu >= 0.0) {
        return Err(bad("the ground's friction must be finite and >= 0", mu));
    }
    if !(dt.is_finite() && dt > 0.0 && dt <= 0.01) {
        return Err(bad("the step must be above 0 and at most 0.01 s", dt));
    }
    if q.len() != robot.joints()
        || !pos
            .iter()
            .chain(velocity.iter())
            .chain(q)
            .all(|x| x.is_finite())
    {
        return Err(RapierError::Unsupported(format!(
            "floating robot on the ground: the start must be finite, with {} joint angles (got {})",
            robot.joints(),
            q.len()
        )));
    }
    Ok(())
}

/// `experiment` run in rapier on `robot` with feet `feet`: the same start, the same PD law
/// towards the same targets at the control rate, the same joint friction applied at every
/// step (`rate × substeps` Hz), balls of `radius` (m) at the feet on a ground of the
/// experiment's friction coefficient (its stiffness, damping and slip speed are physid's
/// contact model's, not rapier's).
pub fn standing_in_rapier(
    robot: &FloatingModel,
    feet: &[(usize, Vector3<f64>)],
    experiment: &Standing,
    radius: f64,
) -> Result<EngineRun, RapierError> {
    super::floating::check(robot, feet, experiment)
        .map_err(|e| RapierError::Unsupported(e.to_string()))?;
    let n = robot.joints();
    let (pos, q0) = experiment.initial_pose(robot, &mut Data::new(robot.tree()), feet);
    let Start { velocity, .. } = experiment.start;
    let dt = 1.0 / (experiment.rate * experiment.substeps as f64);
    let mut sim = RapierFloating::new(
        robot,
        feet,
        (pos, Vector3::from(velocity), &q0),
        (experiment.ground.friction, radius),
        dt,
    )?;
    let targets = experiment.targets(n);
    let mut run = EngineRun {
        joints: n,
        feet: feet.len(),
        ..Default::default()
    };
    let mut normal = vec![0.0; feet.len()];
    let steps = (experiment.duration * experiment.rate).round() as usize;
    for k in 0..steps {
        let t = k as f64 / experiment.rate;
        let (q, qd) = sim.joints();
        let motor = experiment.motor_torques(&q, &qd, &targets.at(t));
        let (rot, p, v) = sim.trunk();
        run.t.push(t);
        run.trunk.push((rot, p));
        run.velocity.push(v);
        run.q.extend(&q);
        run.normal.extend(&normal);
        for _ in 0..experiment.substeps {
            let (_, qd) = sim.joints();
            let friction = experiment.joint_friction(robot, &qd);
            let tau: Vec<f64> = motor.iter().zip(&friction).map(|(m, f)| m - f).collect();
            sim.step_with_torque(&tau);
        }
        normal = sim.normal_forces();
    }
    Ok(run)
}
