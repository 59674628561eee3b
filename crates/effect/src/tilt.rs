//! `tilt`: Gravity misaligned by a small base tilt (m/s² of the gravity vector's perpendicular
//! components; reported as an angle).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::context::{Context, Sample, Scratch};
use super::physics::{self, Physics, ScenarioError};
use super::EffectSpec;
use super::{row, times, uniform, Blind, ColumnCount::Fixed, Kind, KindSpec, Property};
use physid_core::dynamics::{regressor, Data};
use physid_core::model::Model;
use physid_core::spatial::rot_axis_angle;
use nalgebra::{DMatrix, Vector3};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("tilt angle", "rad"),
    properties: &[
        Property::Linearized,
    ],
    magnitudes: |c, _, g| vec![(c[0].hypot(c[1]) / g).atan()],
    replay: |m, c, _, _| {
        tilt_angles(m, c).map(|(roll, pitch)| EffectSpec::Tilt(Tilt { roll, pitch }))
    },
    blind: Blind::Single,
    scale: Some(|spec, s, _, m| match spec {
        EffectSpec::Tilt(t) => Some((
            EffectSpec::Tilt(Tilt {
                roll: t.roll * s,
                pitch: t.pitch * s,
            }),
            times(m, s),
        )),
        _ => None,
    }),
    draw: draw_tilt,
    ..row(Kind::Tilt, "tilt", Fixed(2), fill_tilt)
};

/// Tilt columns: the gravity torque of the nominal model under gravity along each of the two
/// directions perpendicular to the model's.
fn fill_tilt(x: &Context, s: &Sample, w: &mut Scratch, z: &mut DMatrix<f64>, c: usize) {
    let tilted = w.tilted.get_or_insert_with(|| {
        x.perp
            .iter()
            .map(|u| {
                let gm = x.model().clone().with_gravity(*u);
                let gd = Data::new(&gm);
                (gm, gd)
            })
            .collect()
    });
    for (i, (gm, gd)) in tilted.iter_mut().enumerate() {
        regressor(gm, gd, s.q, &w.zeros, &w.zeros, &mut w.yg);
        let col = &w.yg * &x.theta0;
        (0..s.n).for_each(|j| z[(j, c + i)] = col[j]);
    }
}

/// Roll and pitch (rad) of the scenario's tilt whose gravity has the calibrated components
/// `c₀, c₁` (m/s²) along the library's tilt directions `u₁, u₂`; `None` if the model's gravity
/// is not along −z.
fn tilt_angles(model: &Model, c: &[f64]) -> Option<(f64, f64)> {
    let g = model.gravity();
    let g0 = g.norm();
    if g0 == 0.0 || (g / g0 + Vector3::z()).norm() > 1e-9 {
        return None;
    }
    // The library's directions for g along −z: u₁ = x, u₂ = ĝ × u₁ = −y; the coefficients are
    // the tilted gravity's components along them (m/s²).
    let (dx, dy) = (c[0] / g0, -c[1] / g0);
    if dx * dx + dy * dy >= 1.0 {
        return None;
    }
    let d = Vector3::new(dx, dy, -(1.0 - dx * dx - dy * dy).sqrt());
    // The scenario's gravity is R_xᵀ(roll) R_yᵀ(pitch) g = g₀ (sin p, −sin r cos p, −cos r cos p).
    let pitch = d.x.asin();
    let roll = (-d.y).atan2(-d.z);
    Some((roll, pitch))
}

/// A base tilt of 0.2–0.35 rad in a random direction.
fn draw_tilt(_: &Model, rng: &mut ChaCha8Rng, _: f64) -> (Option<EffectSpec>, Vec<f64>) {
    let angle = uniform(rng, 0.2, 0.35);
    let dir = uniform(rng, 0.0, std::f64::consts::TAU);
    let spec = EffectSpec::Tilt(Tilt {
        roll: angle * dir.cos(),
        pitch: angle * dir.sin(),
    });
    (Some(spec), vec![angle])
}

/// The base is tilted: the true gravity is the model's rotated by roll (about x) and pitch
/// (about y) (rad).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Tilt {
    /// Roll (rad).
    pub roll: f64,
    /// Pitch (rad).
    pub pitch: f64,
}

impl Physics for Tilt {
    fn toml_body(&self) -> String {
        format!("roll = {:.6e}\npitch = {:.6e}", self.roll, self.pitch)
    }

    fn validate(&self, _: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError> {
        let (roll, pitch) = (self.roll, self.pitch);
        physics::check(
            roll.is_finite() && pitch.is_finite() && roll.abs() < 1.0 && pitch.abs() < 1.0,
            &key("roll"),
            || "roll and pitch must be finite and below 1 rad".into(),
        )
    }

    fn on_robot(&self, model: &Model) -> Option<Model> {
        let r =
            rot_axis_angle(&Vector3::y(), self.pitch) * rot_axis_angle(&Vector3::x(), self.roll);
        Some(model.clone().with_gravity(r.transpose() * model.gravity()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tilt_angles_invert_the_simulators_tilt() {
        let model = physid_core::model::cheetah3::leg();
        for (roll, pitch) in [(0.01, -0.02), (-0.003, 0.0), (0.05, 0.04)] {
            let spec = EffectSpec::Tilt(Tilt { roll, pitch });
            let tilted = spec.physics().on_robot(&model).expect("tilted").gravity();
            // The library's coefficients: Δg along u₁ = x and u₂ = −y.
            let dg = tilted - model.gravity();
            let Some(EffectSpec::Tilt(Tilt { roll: r, pitch: p })) =
                Kind::Tilt.replay(&model, &[dg.x, -dg.y], 0.0, 1e-3)
            else {
                panic!("no tilt replayed")
            };
            assert!((r - roll).abs() < 1e-12, "{r} {roll}");
            assert!(
                (p - pitch).abs() < 1e-4 * pitch.abs().max(1e-3),
                "{p} {pitch}"
            );
        }
    }
}
