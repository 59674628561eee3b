//! The effect library, injection side: effects the rigid-body model leaves out, applied by the
//! simulator (see [`EffectSpec`] for each equation). Physical effects act on the robot and are
//! logged as the ground truth's `effects` torque; sensor effects change only the logged torque;
//! tilt and payload change the simulated robot itself.

use super::scenario::EffectSpec;
use crate::model::Model;
use crate::spatial::{rot_axis_angle, InertialParams};
use nalgebra::{Matrix3, Vector3};

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
    let n = q.len();
    let mut out = vec![0.0; n];
    let sgn = |w: f64| (w / vs).tanh();
    for e in effects {
        match e {
            EffectSpec::Spring { stiffness, rest } => {
                (0..n).for_each(|j| out[j] -= stiffness[j] * (q[j] - rest[j]))
            }
            EffectSpec::Stribeck {
                static_extra,
                velocity,
            } => (0..n).for_each(|j| {
                out[j] -= static_extra[j] * (-(qd[j] / velocity[j]).powi(2)).exp() * sgn(qd[j])
            }),
            EffectSpec::AsymmetricCoulomb { delta } => {
                (0..n).for_each(|j| out[j] -= delta[j] * sgn(qd[j]).max(0.0))
            }
            EffectSpec::LoadDependentFriction { coefficient } => {
                (0..n).for_each(|j| out[j] -= coefficient[j] * tau_mot[j].abs() * sgn(qd[j]))
            }
            EffectSpec::Cogging {
                amplitude,
                harmonic,
                phase,
            } => (0..n).for_each(|j| {
                let gear = model.bodies[j].rotor.as_ref().map_or(1.0, |r| r.gear_ratio);
                let ph = phase.get(j).copied().unwrap_or(0.0);
                out[j] -= amplitude[j] * (harmonic[j] * gear * q[j] + ph).sin();
            }),
            EffectSpec::QuadraticDamping { coefficient } => {
                (0..n).for_each(|j| out[j] -= coefficient[j] * qd[j] * qd[j].abs())
            }
            EffectSpec::TorqueOffset { .. }
            | EffectSpec::TorqueGain { .. }
            | EffectSpec::TimeDelay { .. }
            | EffectSpec::Compliance { .. }
            | EffectSpec::Backlash { .. } => {}
            EffectSpec::Tilt { .. } | EffectSpec::Payload { .. } => {}
        }
    }
    out
}

/// The logged torque for a delivered (possibly delayed) torque: gains, then offsets.
pub fn logged_torque(effects: &[EffectSpec], tau: &[f64]) -> Vec<f64> {
    let mut out = tau.to_vec();
    for e in effects {
        match e {
            EffectSpec::TorqueGain { gain } => out.iter_mut().zip(gain).for_each(|(t, g)| *t *= g),
            EffectSpec::TorqueOffset { offset } => {
                out.iter_mut().zip(offset).for_each(|(t, o)| *t += o)
            }
            _ => {}
        }
    }
    out
}

/// The logged encoder angle for link angle `q` under delivered torque `tau_mot`: `q + τ/k`
/// with a `compliance` effect, `q + (b/2) sign(τ)` with `backlash`, else `q`.
pub fn logged_angle(effects: &[EffectSpec], q: &[f64], tau_mot: &[f64]) -> Vec<f64> {
    let mut out = q.to_vec();
    for e in effects {
        match e {
            EffectSpec::Compliance { stiffness } => {
                for (j, o) in out.iter_mut().enumerate() {
                    if stiffness[j].is_finite() {
                        *o += tau_mot[j] / stiffness[j];
                    }
                }
            }
            EffectSpec::Backlash { width } => {
                for (j, o) in out.iter_mut().enumerate() {
                    if tau_mot[j] != 0.0 {
                        *o += 0.5 * width[j] * tau_mot[j].signum();
                    }
                }
            }
            _ => {}
        }
    }
    out
}

/// The delay of the logged torque in samples (0 without a `time_delay` effect).
pub fn delay_samples(effects: &[EffectSpec]) -> usize {
    effects
        .iter()
        .map(|e| {
            if let EffectSpec::TimeDelay { samples } = e {
                *samples
            } else {
                0
            }
        })
        .sum()
}

/// The robot as it really is: the model with the base tilt (gravity rotated) and the payload.
pub fn true_robot(model: &Model, effects: &[EffectSpec]) -> Model {
    let mut m = model.clone();
    for e in effects {
        match e {
            EffectSpec::Tilt { roll, pitch } => {
                let r =
                    rot_axis_angle(&Vector3::y(), *pitch) * rot_axis_angle(&Vector3::x(), *roll);
                m = m.clone().with_gravity(r.transpose() * m.gravity);
            }
            EffectSpec::Payload {
                mass,
                com,
                radius,
                body,
            } => {
                let on = body.map_or(m.dof() - 1, |b| b - 1);
                let sphere = InertialParams::from_mass_com_inertia(
                    *mass,
                    &Vector3::from(*com),
                    &(Matrix3::identity() * (0.4 * mass * radius * radius)),
                );
                let mut bodies = m.bodies.clone();
                bodies[on].inertia = InertialParams(bodies[on].inertia.0 + sphere.0);
                m = Model::new(m.name.clone(), bodies, m.gravity)
                    .expect("adding a payload keeps the model valid")
                    .with_rotor_model(m.rotor_model);
            }
            _ => {}
        }
    }
    m
}
