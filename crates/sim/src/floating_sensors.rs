//! A floating-base run as a robot's sensors log it ([`physid_io::floating_log`]): joint
//! encoders and motor currents, an IMU's gyro and a state estimator's pose and velocity for the
//! trunk, force sensors (read through an anti-aliasing filter: [`FloatingRun::contact_mean`])
//! and a contact estimator at the feet, and the IMU's accelerometer, each with its own noise
//! and, for the trunk, a constant bias.
//!
//! Noise is Gaussian, drawn from `seed` in a fixed order, so the same seed gives the same log.

use crate::floating::FloatingRun;
use nalgebra::{Matrix3, Vector3};
use physid_core::spatial::{rot_axis_angle, Motion};
use physid_io::floating_log::FloatingLog;
use physid_io::prepare::Logged;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

/// The sensors' noise and what they log.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Sensors {
    /// Joint torque noise, standard deviation (N m).
    pub torque_noise: f64,
    /// Contact force noise per axis (N).
    pub force_noise: f64,
    /// Gyro noise per axis (rad/s).
    pub gyro_noise: f64,
    /// Gyro bias per axis, drawn once per log with this standard deviation (rad/s).
    pub gyro_bias: f64,
    /// Estimated trunk velocity noise per axis, trunk coordinates (m/s).
    pub velocity_noise: f64,
    /// Estimated trunk velocity bias per axis, drawn once per log (m/s).
    pub velocity_bias: f64,
    /// Estimated orientation error: a rotation about a random axis per sample, angle with this
    /// standard deviation per axis (rad).
    pub tilt_noise: f64,
    /// Estimated position noise per axis (m).
    pub position_noise: f64,
    /// Accelerometer noise per axis (m/s²).
    pub accel_noise: f64,
    /// Accelerometer bias per axis, drawn once per log (m/s²).
    pub accel_bias: f64,
    /// Encoder resolution (rad): positions logged rounded to it (0: exact).
    pub encoder_step: f64,
    /// Log the joint velocities (else the data pipeline derives them).
    pub velocities: bool,
    /// Log the feet's contact forces.
    pub forces: bool,
    /// Log the feet's contact states (true where the force's normal part is positive).
    pub contacts: bool,
    /// Log the IMU's accelerometer (at the trunk frame's origin; off by default: a state
    /// estimator's pose and twist are what every floating log carries).
    pub accelerometer: bool,
}

impl Default for Sensors {
    fn default() -> Self {
        Self {
            torque_noise: 0.5,
            force_noise: 2.0,
            gyro_noise: 0.005,
            gyro_bias: 0.002,
            velocity_noise: 0.01,
            velocity_bias: 0.005,
            tilt_noise: 0.002,
            position_noise: 0.002,
            accel_noise: 0.04,
            accel_bias: 0.02,
            encoder_step: 0.0,
            velocities: false,
            forces: true,
            contacts: true,
            accelerometer: false,
        }
    }
}

impl Sensors {
    /// Noise-free sensors logging everything.
    pub fn exact() -> Self {
        Self {
            torque_noise: 0.0,
            force_noise: 0.0,
            gyro_noise: 0.0,
            gyro_bias: 0.0,
            velocity_noise: 0.0,
            velocity_bias: 0.0,
            tilt_noise: 0.0,
            position_noise: 0.0,
            accel_noise: 0.0,
            accel_bias: 0.0,
            encoder_step: 0.0,
            velocities: true,
            forces: true,
            contacts: true,
            accelerometer: true,
        }
    }

    /// Every noise finite and non-negative, every bias finite; `Err` names the field.
    pub fn validate(&self) -> Result<(), String> {
        let fields = [
            ("torque_noise", self.torque_noise),
            ("force_noise", self.force_noise),
            ("gyro_noise", self.gyro_noise),
            ("gyro_bias", self.gyro_bias),
            ("velocity_noise", self.velocity_noise),
            ("velocity_bias", self.velocity_bias),
            ("tilt_noise", self.tilt_noise),
            ("position_noise", self.position_noise),
            ("accel_noise", self.accel_noise),
            ("accel_bias", self.accel_bias),
            ("encoder_step", self.encoder_step),
        ];
        match fields.iter().find(|(_, v)| !(v.is_finite() && *v >= 0.0)) {
            Some((name, v)) => Err(format!("sensors: {name} = {v} must be finite and >= 0")),
            None if self.tilt_noise > 0.1 => Err(format!(
                "sensors: tilt_noise = {} rad is no state estimator's (at most 0.1)",
                self.tilt_noise
            )),
            None => Ok(()),
        }
    }
}

/// `run` as its sensors log it: joints named `joints`, feet named `feet` (in the order of
/// `run.feet`), noise drawn from `seed`.
pub fn log(
    run: &FloatingRun,
    (joints, feet): (&[String], &[String]),
    sensors: &Sensors,
    seed: u64,
) -> FloatingLog {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed.wrapping_mul(104_729) ^ 0x5e50);
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    let mut draw = |s: f64| s * unit.sample(&mut rng);
    let gyro_bias = Vector3::from_fn(|_, _| draw(sensors.gyro_bias));
    let velocity_bias = Vector3::from_fn(|_, _| draw(sensors.velocity_bias));
    let mut out = FloatingLog {
        joints: joint_log(run, joints, sensors, &mut draw),
        rotation: Vec::with_capacity(run.len()),
        position: Vec::with_capacity(run.len()),
        twist: Vec::with_capacity(run.len()),
        feet: feet.to_vec(),
        force: sensors.forces.then(Vec::new),
        contact: sensors.contacts.then(Vec::new),
        accel: sensors
            .accelerometer
            .then(|| accelerometer(run, sensors, seed)),
    };
    for (k, base) in run.base.iter().enumerate() {
        let (rot, pos) = base.pose.to_pose();
        let tilt = Vector3::from_fn(|_, _| draw(sensors.tilt_noise));
        out.rotation.push(rot * rotation(&tilt));
        out.position
            .push(pos + Vector3::from_fn(|_, _| draw(sensors.position_noise)));
        let noise = |s: f64, d: &mut dyn FnMut(f64) -> f64| Vector3::from_fn(|_, _| d(s));
        out.twist.push(Motion::new(
            base.v.ang + gyro_bias + noise(sensors.gyro_noise, &mut draw),
            base.v.lin + velocity_bias + noise(sensors.velocity_noise, &mut draw),
        ));
        let f = run.feet.len();
        for (now, mean) in run
            .contact_at(k)
            .iter()
            .zip(&run.contact_mean[k * f..(k + 1) * f])
        {
            if let Some(force) = out.force.as_mut() {
                force.push(mean + noise(sensors.force_noise, &mut draw));
            }
            if let Some(contact) = out.contact.as_mut() {
                contact.push(now.z > 0.0);
            }
        }
    }
    out
}

/// The accelerometer at the trunk frame's origin: the specific force `Rᵀ (p̈ − g)` through its
/// anti-aliasing filter ([`FloatingRun::specific_force_mean`]), with a bias drawn once and noise
/// per sample, from a stream of its own (so that the other sensors' noise is the same with it
/// or without it).
fn accelerometer(run: &FloatingRun, sensors: &Sensors, seed: u64) -> Vec<Vector3<f64>> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed.wrapping_mul(15_485_863) ^ 0xacce1);
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    let mut draw = |s: f64| Vector3::from_fn(|_, _| s * unit.sample(&mut rng));
    let bias = draw(sensors.accel_bias);
    (run.specific_force_mean.iter())
        .map(|f| f + bias + draw(sensors.accel_noise))
        .collect()
}

/// The rotation by the vector `theta` (axis times angle, rad).
fn rotation(theta: &Vector3<f64>) -> Matrix3<f64> {
    let angle = theta.norm();
    if angle == 0.0 {
        return Matrix3::identity();
    }
    rot_axis_angle(&(theta / angle), angle)
}

/// The joints' log: encoder positions (rounded to the step), velocities if logged, motor
/// torques with noise.
fn joint_log(
    run: &FloatingRun,
    joints: &[String],
    sensors: &Sensors,
    draw: &mut dyn FnMut(f64) -> f64,
) -> Logged {
    let step = sensors.encoder_step;
    let encoder = |q: f64| {
        if step > 0.0 {
            (q / step).round() * step
        } else {
            q
        }
    };
    Logged {
        joint_names: joints.to_vec(),
        t: run.t.clone(),
        q: run.q.iter().map(|&q| encoder(q)).collect(),
        qd: sensors.velocities.then(|| run.qd.clone()),
        qdd: None,
        tau: run
            .tau
            .iter()
            .map(|&t| t + draw(sensors.torque_noise))
            .collect(),
    }
}
