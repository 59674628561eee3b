//! The simulator's form of an effect kind ([`Physics`]: what it does to the robot and to the
//! log, its scenario keys, their checks and TOML) and the checks the kinds share. Each kind's
//! struct and its physics live in the kind's own file; `super::EffectSpec` lists them once.

use physid_core::model::Model;

/// The state an acting effect reads at one instant of the simulation.
pub struct State<'a> {
    /// The simulated robot (its rotors' gear ratios).
    pub model: &'a Model,
    /// Joint angles (rad).
    pub q: &'a [f64],
    /// Joint rates (rad/s).
    pub qd: &'a [f64],
    /// The torque the motors deliver (N m).
    pub tau_mot: &'a [f64],
    /// The friction's regularization velocity (rad/s): `sign(q̇) ≈ tanh(q̇/v_s)`.
    pub vs: f64,
}

impl State<'_> {
    /// The regularized sign of a joint rate `w` (rad/s).
    pub fn sign(&self, w: f64) -> f64 {
        (w / self.vs).tanh()
    }
}

/// What one kind of effect does in the simulator, and its scenario form. The defaults do
/// nothing: a kind implements the parts it acts through (an acting torque, the logged torque,
/// the logged angle, a delay, the robot itself).
pub trait Physics {
    /// The keys as lines of a scenario's `[[effects]]` table (without `kind = …`).
    fn toml_body(&self) -> String;
    /// Checks the values against `n` joints; `key` names a key as the scenario does.
    fn validate(&self, n: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError>;
    /// Adds the torque the effect exerts on the joints (N m, in the direction of motion's
    /// torque: a resisting effect subtracts) at `state` to `out`.
    fn act(&self, _state: &State, _out: &mut [f64]) {}
    /// Changes a sample's logged torque (N m) in place.
    fn log_torque(&self, _tau: &mut [f64]) {}
    /// Changes a sample's logged encoder angles (rad) in place, under delivered torque
    /// `tau_mot` (N m).
    fn log_angle(&self, _q: &mut [f64], _tau_mot: &[f64]) {}
    /// The width (rad per joint) of a dead zone the motor crosses in the transmission, read on
    /// the motor side (`super::DeadZone`).
    fn dead_zone_width(&self) -> Option<&[f64]> {
        None
    }
    /// The logged torque's lag (samples).
    fn delay_samples(&self) -> usize {
        0
    }
    /// The robot as it really is under this effect (`None`: the model unchanged).
    fn on_robot(&self, _model: &Model) -> Option<Model> {
        None
    }
}

/// A scenario value that cannot be simulated, with the key and the reason.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{key}: {reason}")]
pub struct ScenarioError {
    /// Dotted key, e.g. `sensors.encoder_noise`.
    pub key: String,
    /// Why it is rejected.
    pub reason: String,
}

/// `Ok` if `ok`, else the error of `key` with the reason.
pub fn check(ok: bool, key: &str, reason: impl FnOnce() -> String) -> Result<(), ScenarioError> {
    if ok {
        Ok(())
    } else {
        Err(ScenarioError {
            key: key.into(),
            reason: reason(),
        })
    }
}

/// A finite number ≥ 0.
pub fn non_negative(v: f64, key: &str) -> Result<(), ScenarioError> {
    check(v.is_finite() && v >= 0.0, key, || {
        format!("{v} must be a finite number >= 0")
    })
}

/// A finite number > 0.
pub fn positive(v: f64, key: &str) -> Result<(), ScenarioError> {
    check(v.is_finite() && v > 0.0, key, || {
        format!("{v} must be a finite number > 0")
    })
}

/// One finite number per joint.
pub fn per_joint(v: &[f64], n: usize, key: &str) -> Result<(), ScenarioError> {
    check(v.len() == n, key, || {
        format!("has {} entries, the robot has {n} joints", v.len())
    })?;
    check(v.iter().all(|x| x.is_finite()), key, || {
        "contains a non-finite number".into()
    })
}

/// One finite number ≥ 0 per joint.
pub(crate) fn per_joint_non_negative(v: &[f64], n: usize, key: &str) -> Result<(), ScenarioError> {
    per_joint(v, n, key)?;
    check(v.iter().all(|c| *c >= 0.0), key, || "must be >= 0".into())
}

/// A TOML array of numbers in the scenario snippets physid writes (`[1.000000e0, …]`, six
/// significant decimals).
pub fn toml_list(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| format!("{x:.6e}")).collect();
    format!("[{}]", items.join(", "))
}
