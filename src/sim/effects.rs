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
    let n = q.len();
    out.fill(0.0);
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
                let gear = model.bodies()[j]
                    .rotor
                    .as_ref()
                    .map_or(1.0, |r| r.gear_ratio);
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
/// with a `compliance` effect, plus the motor's offsets in a backlash dead zone (`dead_zone`,
/// from [`DeadZone::step`]), else `q`.
pub fn logged_angle(
    effects: &[EffectSpec],
    q: &[f64],
    tau_mot: &[f64],
    dead_zone: Option<&[f64]>,
) -> Vec<f64> {
    let mut out = q.to_vec();
    for e in effects {
        if let EffectSpec::Compliance { stiffness } = e {
            for (j, o) in out.iter_mut().enumerate() {
                if stiffness[j].is_finite() {
                    *o += tau_mot[j] / stiffness[j];
                }
            }
        }
    }
    if let Some(offset) = dead_zone {
        out.iter_mut().zip(offset).for_each(|(o, s)| *o += s);
    }
    out
}

/// The motor's side of a backlash dead zone, per joint: its offset `s ∈ [−b/2, b/2]` from the
/// link (rad at the joint). Inside the gap the motor (its rotor's spin inertia reflected to the
/// joint, `J = N² I_zz`) is driven by its own torque alone, `J s̈ = τ_mot`; against either side
/// it moves with the link while the torque pushes it there. So a torque that only chatters
/// about zero (the controller's quantization noise) does not carry the motor across the gap,
/// and a reversal crosses it in `≈ (6 J b / τ̇)^⅓` (tens of ms on the Cheetah leg). A joint
/// without a rotor crosses at once (`(b/2) sign(τ)`). The link's loss of torque while the
/// motor crosses is not simulated.
#[derive(Clone, Debug)]
pub struct DeadZone {
    width: Vec<f64>,
    inertia: Vec<f64>,
    offset: Vec<f64>,
    rate: Vec<f64>,
    started: bool,
}

impl DeadZone {
    /// The dead zones of `effects` on `model` (`None` without a backlash effect).
    pub fn new(model: &Model, effects: &[EffectSpec]) -> Option<Self> {
        let width = effects.iter().find_map(|e| match e {
            EffectSpec::Backlash { width } => Some(width.clone()),
            _ => None,
        })?;
        let n = width.len();
        let inertia = model
            .bodies()
            .iter()
            .map(|b| b.rotor.as_ref().map_or(0.0, |r| r.armature()))
            .collect();
        Some(Self {
            width,
            inertia,
            offset: vec![0.0; n],
            rate: vec![0.0; n],
            started: false,
        })
    }

    /// The offsets at the start of a period in which `tau_mot` (N m) is held for `dt` (s), then
    /// advances them over the period. At the first call the motor rests against the side the
    /// torque pushes it to.
    pub fn step(&mut self, tau_mot: &[f64], dt: f64) -> Vec<f64> {
        let half = |j: usize| 0.5 * self.width[j];
        if !self.started {
            self.started = true;
            for (j, t) in tau_mot.iter().enumerate() {
                self.offset[j] = half(j) * crate::dynamics::sign(*t);
            }
        }
        let now = self.offset.clone();
        for (j, &t) in tau_mot.iter().enumerate() {
            if self.inertia[j] <= 0.0 {
                if t != 0.0 {
                    self.offset[j] = half(j) * t.signum();
                }
                continue;
            }
            self.rate[j] += t / self.inertia[j] * dt;
            self.offset[j] += self.rate[j] * dt;
            if self.offset[j] >= half(j) {
                self.offset[j] = half(j);
                self.rate[j] = self.rate[j].min(0.0);
            } else if self.offset[j] <= -half(j) {
                self.offset[j] = -half(j);
                self.rate[j] = self.rate[j].max(0.0);
            }
        }
        now
    }
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
                m = m.clone().with_gravity(r.transpose() * m.gravity());
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
                let mut bodies = m.bodies().to_vec();
                bodies[on].inertia = InertialParams(bodies[on].inertia.0 + sphere.0);
                m = Model::new(m.name().to_string(), bodies, m.gravity())
                    .expect("adding a payload keeps the model valid")
                    .with_rotor_model(m.rotor_model());
            }
            _ => {}
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn zone(width: f64) -> (DeadZone, f64) {
        let leg = crate::model::cheetah3::leg();
        let j = leg.bodies()[1].rotor.as_ref().expect("rotor").armature();
        let zone = DeadZone::new(
            &leg,
            &[EffectSpec::Backlash {
                width: vec![width; 3],
            }],
        )
        .expect("backlash given");
        (zone, j)
    }

    #[test]
    fn a_constant_torque_crosses_the_gap_in_the_free_flight_time() {
        // From the −b/2 side at rest, a constant τ moves the motor by ½ (τ/J) t²: the far side
        // at t = √(2 b J / τ), then it stays there.
        let (b, tau, dt) = (0.02, 0.5, 1e-4);
        let (mut z, j) = zone(b);
        z.step(&[-1.0, -1.0, -1.0], dt);
        let want = (2.0 * b * j / tau).sqrt();
        let mut t = 0.0;
        let mut arrived = None;
        for _ in 0..200_000 {
            let s = z.step(&[0.0, tau, 0.0], dt);
            assert!(s[1].abs() <= 0.5 * b + 1e-15);
            if arrived.is_none() && s[1] >= 0.5 * b {
                arrived = Some(t);
            }
            t += dt;
        }
        let got = arrived.expect("crossed");
        assert!((got - want).abs() < 3.0 * dt, "{got} s vs {want} s");
        assert_eq!(z.step(&[0.0, tau, 0.0], dt)[1], 0.5 * b);
    }

    #[test]
    fn a_torque_chattering_about_zero_does_not_cross() {
        // ±0.15 N m alternating every millisecond (the controller's quantization noise about a
        // torque reversal) moves the motor by micro-radians, not across a 0.02 rad gap; the
        // instant model would jump by the whole width every sample.
        let (mut z, _) = zone(0.02);
        z.step(&[0.1, 0.1, 0.1], 1e-3);
        let mut lo = f64::INFINITY;
        for k in 0..1000 {
            let t = if k % 2 == 0 { -0.15 } else { 0.15 };
            lo = lo.min(z.step(&[t, t, t], 1e-3)[1]);
        }
        assert!(lo > 0.01 - 1e-3, "offset fell to {lo}");
    }
}
