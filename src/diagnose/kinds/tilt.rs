//! `tilt`: Gravity misaligned by a small base tilt (m/s² of the gravity vector's perpendicular
//! components; reported as an angle).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::{row, uniform, Blind, ColumnCount::Fixed, Kind, KindSpec};
use crate::diagnose::context::{Context, Sample, Scratch};
use crate::dynamics::{regressor, Data};
use crate::model::Model;
use crate::sim::scenario::EffectSpec;
use nalgebra::{DMatrix, Vector3};
use rand_chacha::ChaCha8Rng;

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("tilt angle", "rad"),
    linearized: true,
    magnitudes: |c, _, g| vec![(c[0].hypot(c[1]) / g).atan()],
    replay: |m, c, _, _| tilt_angles(m, c).map(|(roll, pitch)| EffectSpec::Tilt { roll, pitch }),
    blind: Blind::Single,
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
    let spec = EffectSpec::Tilt {
        roll: angle * dir.cos(),
        pitch: angle * dir.sin(),
    };
    (Some(spec), vec![angle])
}
