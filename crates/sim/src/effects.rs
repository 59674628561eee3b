//! The effect library, injection side: effects the rigid-body model leaves out, applied by the
//! simulator (each kind's equation in its file of `physid_effect`, behind
//! [`physid_effect::Physics`]). Physical effects act on the robot and are logged as the ground
//! truth's `effects` torque; sensor effects change only the logged torque or angle; tilt and
//! payload change the simulated robot itself. Here only the loops over a scenario's effects.

use physid_core::model::Model;
pub use physid_effect::DeadZone;
use physid_effect::{EffectSpec, State};

/// The acting torque of the physical effects at `(q, q̇)` with delivered torque `tau_mot`
/// (N m per joint); `vs` is the friction regularization velocity (rad/s).
pub fn physical_torque(
    effects: &[EffectSpec],
    model: &Model,
    q: &[f64],
    qd: &[f64],
    tau_mot: &[f64],
    vs: f64,
) -> Vec<f64> {
    let mut out = vec![0.0; q.len()];
    physical_torque_into(effects, model, (q, qd), tau_mot, vs, &mut out);
    out
}

/// [`physical_torque`] written into `out` (one entry per joint), without allocating: the
/// simulator calls it at every stage of every integration step.
pub fn physical_torque_into(
    effects: &[EffectSpec],
    model: &Model,
    (q, qd): (&[f64], &[f64]),
    tau_mot: &[f64],
    vs: f64,
    out: &mut [f64],
) {
    out.fill(0.0);
    let state = State {
        model,
        q,
        qd,
        tau_mot,
        vs,
    };
    for e in effects {
        e.physics().act(&state, out);
    }
}

/// The logged torque for a delivered (possibly delayed) torque: each effect's change of it
/// (gains, offsets) in the scenario's order.
pub fn logged_torque(effects: &[EffectSpec], tau: &[f64]) -> Vec<f64> {
    let mut out = tau.to_vec();
    logged_torque_into(effects, tau, &mut out);
    out
}

/// [`logged_torque`] written into `out` (one entry per joint), without allocating.
pub fn logged_torque_into(effects: &[EffectSpec], tau: &[f64], out: &mut [f64]) {
    out.copy_from_slice(tau);
    for e in effects {
        e.physics().log_torque(out);
    }
}

/// The logged encoder angle for link angle `q` under delivered torque `tau_mot`: `q + τ/k`
/// with a `compliance` effect, plus the motor's offsets in a backlash dead zone (`dead_zone`,
/// from [`DeadZone::step`]), else `q`.
pub fn logged_angle(
    effects: &[EffectSpec],
    q: &[f64],
    tau_mot: &[f64],
    dead_zone: Option<&[f64]>,
) -> Vec<f64> {
    let mut out = q.to_vec();
    logged_angle_into(effects, (q, tau_mot), dead_zone, &mut out);
    out
}

/// [`logged_angle`] written into `out` (one entry per joint), without allocating.
pub fn logged_angle_into(
    effects: &[EffectSpec],
    (q, tau_mot): (&[f64], &[f64]),
    dead_zone: Option<&[f64]>,
    out: &mut [f64],
) {
    out.copy_from_slice(q);
    for e in effects {
        e.physics().log_angle(out, tau_mot);
    }
    if let Some(offset) = dead_zone {
        out.iter_mut().zip(offset).for_each(|(o, s)| *o += s);
    }
}

/// The delay of the logged torque in samples (0 without a `time_delay` effect).
pub fn delay_samples(effects: &[EffectSpec]) -> usize {
    effects.iter().map(|e| e.physics().delay_samples()).sum()
}

/// The robot as it really is: the model with the base tilt (gravity rotated) and the payload.
pub fn true_robot(model: &Model, effects: &[EffectSpec]) -> Model {
    let mut m = model.clone();
    for e in effects {
        if let Some(changed) = e.physics().on_robot(&m) {
            m = changed;
        }
    }
    m
}
