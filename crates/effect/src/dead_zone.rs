//! The motor side of a backlash dead zone (the `backlash` kind's physics): shared by the
//! simulator, the semi-real benchmark's injection and the columns' per-data state
//! (`context`), which knows no kind.

use super::EffectSpec;
use physid_core::model::Model;

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
        let width = effects
            .iter()
            .find_map(|e| e.physics().dead_zone_width())?
            .to_vec();
        Some(Self::of_widths(model, width))
    }

    /// Dead zones of `width` (rad per joint) on `model`'s rotors.
    pub fn of_widths(model: &Model, width: Vec<f64>) -> Self {
        let n = width.len();
        Self {
            width,
            inertia: motor_inertia(model),
            offset: vec![0.0; n],
            rate: vec![0.0; n],
            started: false,
        }
    }

    /// The offsets at the start of a period in which `tau_mot` (N m) is held for `dt` (s), then
    /// advances them over the period. At the first call the motor rests against the side the
    /// torque pushes it to.
    pub fn step(&mut self, tau_mot: &[f64], dt: f64) -> Vec<f64> {
        let half = |j: usize| 0.5 * self.width[j];
        if !self.started {
            self.started = true;
            for (j, t) in tau_mot.iter().enumerate() {
                self.offset[j] = half(j) * physid_core::dynamics::sign(*t);
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

/// The inertia (kg m² or kg, at the joint) each joint's motor crosses a dead zone with: its
/// rotor's armature; zero without a rotor, which crosses at once ([`DeadZone::step`]).
pub(crate) fn motor_inertia(model: &Model) -> Vec<f64> {
    (model.bodies().iter())
        .map(|b| b.rotor.as_ref().map_or(0.0, |r| r.armature()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn zone(width: f64) -> (DeadZone, f64) {
        let leg = physid_core::model::cheetah3::leg();
        let j = leg.bodies()[1].rotor.as_ref().expect("rotor").armature();
        let zone = DeadZone::new(
            &leg,
            &[EffectSpec::Backlash(super::super::Backlash {
                width: vec![width; 3],
            })],
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
