//! `torque_gain`: Logged `τ ×= 1 + δ` (per joint; a common δ is a scale of all inertial
//! parameters).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::{row, signed, Blind, ColumnCount::PerJoint, Kind, KindSpec};
use crate::model::Model;
use crate::sim::scenario::EffectSpec;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("gain error relative to the median joint", "-"),
    linearized: true,
    magnitudes: gain_magnitudes,
    // The column is the nominal prediction, which already carries the gain.
    replay: |_, c, _, _| {
        let gain = c.iter().map(|b| 1.0 / (1.0 - b)).collect();
        Some(EffectSpec::TorqueGain { gain })
    },
    blind: Blind::Single,
    draw: draw_gain,
    ..row(
        Kind::TorqueGain,
        "torque_gain",
        PerJoint(1),
        |x, s, _, z, c| (0..s.n).for_each(|j| z[(j, c + j)] = x.pred[s.k * s.n + j]),
    )
};

/// Torque gains relative to the median joint: the column is the nominal prediction, which
/// already carries the gain, so `τ = Y θ + β τ̂` with `τ̂ ≈ τ` gives `1 + g = 1/(1 − β)`.
fn gain_magnitudes(c: &[f64], _: usize, _: f64) -> Vec<f64> {
    let g: Vec<f64> = c.iter().map(|b| b / (1.0 - b)).collect();
    crate::diagnose::stats::relative_to_median(&g)
}

/// One joint's torque constant off by 15–30 %, reported relative to the median joint.
fn draw_gain(m: &Model, rng: &mut ChaCha8Rng, _: f64) -> (Option<EffectSpec>, Vec<f64>) {
    let n = m.dof();
    let j = rng.random_range(0..n);
    let mut gain = vec![1.0; n];
    gain[j] += signed(rng, 0.15, 0.3);
    let relative = crate::diagnose::stats::relative_to_median(&gain);
    (Some(EffectSpec::TorqueGain { gain }), relative)
}
