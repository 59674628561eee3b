//! Scenario files: one TOML file describes a whole experiment (robot, excitation, sensors,
//! processing, effects, duration, rates, seed). Unknown keys are errors; every key, its unit
//! and its default are listed in `docs/scenario-format.md`.

use physid_effect::physics::{check, non_negative, per_joint, positive};
pub use physid_effect::{
    toml_list, EffectSpec, ScenarioError, MAX_DELAY_SAMPLES, MAX_PAYLOAD_MASS, MAX_PAYLOAD_OFFSET,
};
use physid_io::{robot_toml, IoError};
use serde::{Deserialize, Serialize};

/// The numerical simulation.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SimulationSpec {
    /// Length of the experiment (s).
    pub duration: f64,
    /// Control and logging rate (Hz).
    #[serde(default = "default_rate")]
    pub rate: f64,
    /// Integration steps per control period (the torque is held over the period).
    #[serde(default = "default_substeps")]
    pub substeps: usize,
    /// `"physid"` or `"rapier"`.
    #[serde(default)]
    pub engine: Engine,
    /// The physid engine's Runge–Kutta method, `"rk4"` (the default) or `"ralston3"`; not
    /// for the rapier engine, which integrates with its own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub integrator: Option<super::Method>,
    /// Seed of every random draw (noise, Fourier coefficients).
    #[serde(default)]
    pub seed: u64,
    /// Coulomb friction regularization velocity `v_s` (rad/s): `B_c tanh(q̇ / v_s)`.
    #[serde(default = "default_friction_velocity")]
    pub friction_velocity: f64,
    /// Initial joint positions (rad). Passive: the start. Shell: the seed of the inverse
    /// kinematics that puts the point on its first target (the run starts there at rest).
    /// Fourier: unused (the run starts on the desired trajectory).
    pub initial_q: Option<Vec<f64>>,
    /// Any joint speed above this (rad/s) is divergence.
    #[serde(default = "default_divergence")]
    pub max_speed: f64,
}

fn default_rate() -> f64 {
    1000.0
}
fn default_substeps() -> usize {
    4
}
fn default_friction_velocity() -> f64 {
    0.01
}
fn default_divergence() -> f64 {
    200.0
}

/// Which engine integrates the dynamics.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Engine {
    /// physid's own forward dynamics with Runge–Kutta (`integrator`).
    #[default]
    Physid,
    /// rapier3d's multibody solver (an independent engine).
    Rapier,
}

/// The point a Cartesian controller moves.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PointSpec {
    /// Body name.
    pub body: String,
    /// Position in the body frame (m).
    pub offset: [f64; 3],
}

/// What drives the robot.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum ExcitationSpec {
    /// The paper's experiment: a point (the foot) tracks a target moving on an ellipsoidal shell
    /// through spherical angles with `φ̇ = A_φ sin(ω_φ t)`, `θ̇ = A_θ sin(ω_θ t)`, under
    /// Cartesian impedance control `τ = Jᵀ (K_p (p_d − p) + K_d (ṗ_d − J q̇)) + g(q) − D q̇`.
    Shell {
        /// The controlled point (default: the last body, origin).
        point: Option<PointSpec>,
        /// Shell centre in the base frame (m).
        center: [f64; 3],
        /// Shell semi-axes (m).
        radii: [f64; 3],
        /// Azimuth rate amplitude `A_φ` (rad/s).
        #[serde(default = "a_phi")]
        a_phi: f64,
        /// Polar phase rate amplitude `A_θ` (rad/s).
        #[serde(default = "a_theta")]
        a_theta: f64,
        /// `ω_φ` (rad/s).
        #[serde(default = "w_phi")]
        w_phi: f64,
        /// `ω_θ` (rad/s).
        #[serde(default = "w_theta")]
        w_theta: f64,
        /// Polar angle from straight down: `θ_p = polar_mid + polar_amplitude sin θ(t)` (rad).
        #[serde(default)]
        polar_mid: f64,
        /// See `polar_mid` (rad).
        #[serde(default = "polar_amplitude")]
        polar_amplitude: f64,
        /// Cartesian stiffness (N/m).
        kp: [f64; 3],
        /// Cartesian damping (N s/m).
        kd: [f64; 3],
        /// Joint damping `D` (N m s/rad), per joint or one value.
        #[serde(default)]
        joint_damping: f64,
        /// Add gravity compensation `g(q)` from the robot model.
        #[serde(default = "yes")]
        gravity_compensation: bool,
    },
    /// Joint trajectories that are finite Fourier series (Swevers et al.), tracked by joint PD
    /// (`τ = K_p e + K_d ė`) or computed torque (`τ = ID(q, q̇, q̈_d + K_p e + K_d ė)`).
    Fourier {
        /// Harmonics per joint.
        #[serde(default = "harmonics")]
        harmonics: usize,
        /// Fundamental frequency (Hz).
        #[serde(default = "base_frequency")]
        base_frequency: f64,
        /// Maximum excursion from `offset` per joint (rad) of the random coefficients drawn
        /// from the seed (not used with `coefficients`).
        #[serde(default)]
        amplitude: Vec<f64>,
        /// Centre of each joint's motion (rad).
        offset: Vec<f64>,
        /// Given coefficients instead of a random draw (`physid excite` writes them).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        coefficients: Option<FourierCoefficients>,
        /// Start and end at rest at `offset` (s): the motion fades in over the first `ramp` s
        /// and out over the last `ramp` s of the simulation (a septic smoothstep: velocity,
        /// acceleration and jerk zero at both ends). Without it the series starts mid-motion.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        ramp: Option<f64>,
        /// Computed torque also feeds forward the description's friction at the desired
        /// velocity (as a robot's own controller does), so that the tracking error does not
        /// kick at every reversal.
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        friction_feedforward: bool,
        /// Position gains: N m/rad for PD, 1/s² for computed torque.
        kp: Vec<f64>,
        /// Velocity gains: N m s/rad for PD, 1/s for computed torque.
        kd: Vec<f64>,
        /// Computed torque (true) or PD (false).
        #[serde(default = "yes")]
        computed_torque: bool,
    },
    /// No actuation: the robot swings freely from `initial_q`.
    Passive,
}

/// The coefficients of a Fourier excitation, per joint and harmonic `l = 1..L` (rad):
/// `q_j(t) = offset_j + Σ_l sin[j][l−1] sin(ω_l t) + cos[j][l−1] (cos(ω_l t) − 1)`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FourierCoefficients {
    /// Sine coefficients, one row per joint, one entry per harmonic (rad).
    pub sin: Vec<Vec<f64>>,
    /// Cosine coefficients, as `sin` (rad).
    pub cos: Vec<Vec<f64>>,
}

fn a_phi() -> f64 {
    12.0
}
fn a_theta() -> f64 {
    3.4
}
fn w_phi() -> f64 {
    1.63
}
fn w_theta() -> f64 {
    0.265
}
fn polar_amplitude() -> f64 {
    0.5
}
fn yes() -> bool {
    true
}
fn harmonics() -> usize {
    5
}
fn base_frequency() -> f64 {
    0.1
}

/// Sensors and actuators as on the robot.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    /// Encoder quantization step at the joint (rad); 0 = none.
    #[serde(default)]
    pub encoder_step: f64,
    /// Encoder noise, standard deviation (rad).
    #[serde(default)]
    pub encoder_noise: f64,
    /// Noise on the logged torque, standard deviation (N m): current sensing; it does not act.
    #[serde(default)]
    pub torque_noise: f64,
    /// The controller's velocity: `"finite_difference"` of the encoder (as on the robot; its
    /// noise then acts through the feedback) or `"true"`.
    #[serde(default)]
    pub velocity_feedback: VelocityFeedback,
    /// Motor torque constant (N m/A) for the back-EMF torque limit; needs all three motor keys.
    pub motor_kt: Option<f64>,
    /// Motor winding resistance (ohm).
    pub motor_resistance: Option<f64>,
    /// Supply voltage (V).
    pub supply_voltage: Option<f64>,
}

/// The velocity the controller sees.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum VelocityFeedback {
    /// Backward difference of the encoder at the control rate.
    #[default]
    FiniteDifference,
    /// The true velocity.
    True,
}

/// Offline processing of the logged encoder signal into q, q̇, q̈ for identification.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ProcessingSpec {
    /// `"butterworth"` (zero-phase low-pass of q, then of each derivative) or
    /// `"finite_difference"` (central differences, no filtering).
    #[serde(default)]
    pub method: Processing,
    /// Cutoff (Hz).
    #[serde(default = "cutoff")]
    pub cutoff: f64,
    /// Filter order per pass.
    #[serde(default = "order")]
    pub order: usize,
    /// Also low-pass the logged torque.
    #[serde(default)]
    pub filter_torque: bool,
}

impl Default for ProcessingSpec {
    fn default() -> Self {
        Self {
            method: Processing::default(),
            cutoff: cutoff(),
            order: order(),
            filter_torque: false,
        }
    }
}

fn cutoff() -> f64 {
    20.0
}
fn order() -> usize {
    2
}

/// Processing method.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Processing {
    /// Zero-phase Butterworth.
    #[default]
    Butterworth,
    /// Plain central differences.
    FiniteDifference,
}

/// A whole scenario file.
#[derive(Clone, Debug, Deserialize, serde::Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// The robot (see `docs/robot-format.md`).
    pub robot: robot_toml::RobotSpec,
    /// Numerical simulation.
    pub simulation: SimulationSpec,
    /// Excitation and controller.
    pub excitation: ExcitationSpec,
    /// Sensors and actuators.
    #[serde(default)]
    pub sensors: SensorSpec,
    /// Offline processing.
    #[serde(default)]
    pub processing: ProcessingSpec,
    /// Injected effects.
    #[serde(default)]
    pub effects: Vec<EffectSpec>,
    /// The sample-size experiment's `[experiment]` table, kept as read: the experiment floor
    /// above parses it (`experiment::ExperimentSpec::from_scenario`).
    pub experiment: Option<toml::Table>,
}

/// Most RK4 steps per control period (a finer step than 1e4 per period buys no accuracy and
/// only time).
pub const MAX_SUBSTEPS: usize = 10_000;
impl Scenario {
    /// Checks every value against the robot's joint count `n`.
    pub fn validate(&self, n: usize) -> Result<(), ScenarioError> {
        self.simulation.validate(n)?;
        self.sensors.validate()?;
        self.processing.validate(self.simulation.rate)?;
        self.excitation.validate(n, self.simulation.duration)?;
        for (i, e) in self.effects.iter().enumerate() {
            e.validate(i, n)?;
        }
        Ok(())
    }
}

impl SimulationSpec {
    /// The physid engine's Runge–Kutta method (RK4 unless the scenario names one).
    pub fn method(&self) -> super::Method {
        self.integrator.unwrap_or_default()
    }

    fn validate(&self, n: usize) -> Result<(), ScenarioError> {
        let s = self;
        positive(s.duration, "simulation.duration")?;
        positive(s.rate, "simulation.rate")?;
        check(
            (1..=MAX_SUBSTEPS).contains(&s.substeps),
            "simulation.substeps",
            || format!("{} must be 1 to {MAX_SUBSTEPS}", s.substeps),
        )?;
        check(
            s.engine == Engine::Physid || s.integrator.is_none(),
            "simulation.integrator",
            || "is the physid engine's; the rapier engine integrates with its own".into(),
        )?;
        positive(s.friction_velocity, "simulation.friction_velocity")?;
        positive(s.max_speed, "simulation.max_speed")?;
        check(s.duration * s.rate >= 2.0, "simulation.duration", || {
            "gives fewer than two samples at this rate".into()
        })?;
        check(s.duration * s.rate <= 1e8, "simulation.duration", || {
            "more than 1e8 samples".into()
        })?;
        if let Some(q) = &s.initial_q {
            per_joint(q, n, "simulation.initial_q")?;
        }
        Ok(())
    }
}

impl SensorSpec {
    fn validate(&self) -> Result<(), ScenarioError> {
        let se = self;
        non_negative(se.encoder_step, "sensors.encoder_step")?;
        non_negative(se.encoder_noise, "sensors.encoder_noise")?;
        non_negative(se.torque_noise, "sensors.torque_noise")?;
        let motor = [se.motor_kt, se.motor_resistance, se.supply_voltage];
        check(
            motor.iter().all(|m| m.is_some()) || motor.iter().all(|m| m.is_none()),
            "sensors.motor_kt",
            || "motor_kt, motor_resistance and supply_voltage go together".into(),
        )?;
        for (m, key) in motor.iter().zip([
            "sensors.motor_kt",
            "sensors.motor_resistance",
            "sensors.supply_voltage",
        ]) {
            if let Some(v) = m {
                positive(*v, key)?;
            }
        }
        Ok(())
    }
}

impl ProcessingSpec {
    /// Checks the filter against the sample `rate` (Hz).
    fn validate(&self, rate: f64) -> Result<(), ScenarioError> {
        let p = self;
        positive(p.cutoff, "processing.cutoff")?;
        check(p.cutoff < 0.5 * rate, "processing.cutoff", || {
            format!(
                "{} Hz must be below the Nyquist frequency {} Hz",
                p.cutoff,
                0.5 * rate
            )
        })?;
        check((1..=8).contains(&p.order), "processing.order", || {
            format!("{} must be 1 to 8", p.order)
        })?;
        Ok(())
    }
}

impl ExcitationSpec {
    fn validate(&self, n: usize, duration: f64) -> Result<(), ScenarioError> {
        match self {
            ExcitationSpec::Shell {
                radii,
                kp,
                kd,
                a_phi,
                a_theta,
                w_phi,
                w_theta,
                joint_damping,
                ..
            } => {
                for (i, r) in radii.iter().enumerate() {
                    positive(*r, &format!("excitation.radii[{i}]"))?;
                }
                for (i, (a, b)) in kp.iter().zip(kd).enumerate() {
                    non_negative(*a, &format!("excitation.kp[{i}]"))?;
                    non_negative(*b, &format!("excitation.kd[{i}]"))?;
                }
                for (v, k) in [(a_phi, "a_phi"), (a_theta, "a_theta")] {
                    non_negative(*v, &format!("excitation.{k}"))?;
                }
                for (v, k) in [(w_phi, "w_phi"), (w_theta, "w_theta")] {
                    positive(*v, &format!("excitation.{k}"))?;
                }
                non_negative(*joint_damping, "excitation.joint_damping")?;
            }
            ExcitationSpec::Fourier {
                harmonics,
                base_frequency,
                amplitude,
                offset,
                coefficients,
                kp,
                kd,
                ramp,
                ..
            } => {
                check_ramp(*ramp, duration)?;
                check((1..=50).contains(harmonics), "excitation.harmonics", || {
                    format!("{harmonics} must be 1 to 50")
                })?;
                positive(*base_frequency, "excitation.base_frequency")?;
                match coefficients {
                    None => per_joint(amplitude, n, "excitation.amplitude")?,
                    Some(c) => validate_coefficients(c, n, *harmonics)?,
                }
                per_joint(offset, n, "excitation.offset")?;
                per_joint(kp, n, "excitation.kp")?;
                per_joint(kd, n, "excitation.kd")?;
            }
            ExcitationSpec::Passive => {}
        }
        Ok(())
    }
}

/// Checks a Fourier excitation's ramp (s), if any: positive and at most half the simulation's
/// `duration` (s).
fn check_ramp(ramp: Option<f64>, duration: f64) -> Result<(), ScenarioError> {
    let Some(r) = ramp else {
        return Ok(());
    };
    check(
        r.is_finite() && r > 0.0 && 2.0 * r <= duration,
        "excitation.ramp",
        || {
            format!(
                "{r} must be positive and at most half the simulation's duration ({duration} s)"
            )
        },
    )
}

/// Checks explicit Fourier coefficients: one row per joint (`n`) of `harmonics` finite numbers,
/// for the sines and the cosines.
fn validate_coefficients(
    c: &FourierCoefficients,
    n: usize,
    harmonics: usize,
) -> Result<(), ScenarioError> {
    for (rows, key) in [
        (&c.sin, "excitation.coefficients.sin"),
        (&c.cos, "excitation.coefficients.cos"),
    ] {
        check(rows.len() == n, key, || {
            format!("has {} rows, the robot has {n} joints", rows.len())
        })?;
        for (j, row) in rows.iter().enumerate() {
            let key = format!("{key}[{j}]");
            check(row.len() == harmonics, &key, || {
                format!(
                    "has {} entries, the excitation has {harmonics} harmonics",
                    row.len()
                )
            })?;
            check(row.iter().all(|x| x.is_finite()), &key, || {
                "contains a non-finite number".into()
            })?;
        }
    }
    Ok(())
}

/// Reads a scenario file: the scenario, its robot (the ground truth), and the file's text.
/// Errors name the file, the line and the key.
pub fn load(
    path: &std::path::Path,
) -> Result<(Scenario, physid_core::model::Model, String), IoError> {
    let text = physid_io::read_to_string(path)?;
    let sc: Scenario = toml::from_str(&text).map_err(|e| robot_toml::toml_error(path, e))?;
    let model = robot_toml::from_spec(&sc.robot, path)?;
    sc.validate(model.dof())
        .map_err(|e| IoError::invalid(path, e.to_string()))?;
    Ok((sc, model, text))
}
