//! `time_delay`: Logged torque lags the kinematics by `d` (s, one for all joints).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::{row, Blind, ColumnCount::Fixed, Kind, KindSpec};
use crate::sim::scenario::EffectSpec;
use rand::Rng;

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    // The logged torque lags: a "negative delay" is no delay, and was the best single
    // column for a compliant transmission's encoder, which leads the link.
    non_negative: true,
    magnitude: ("delay", "s"),
    linearized: true,
    // On real KUKA logs at 200 Hz a lag of 125 ms doubles the description's error, yet the
    // re-identified model's friction and parameters take it in (cross-validation then selects
    // a spring); from the description its one column takes 70 % of the held-out mean square.
    offered_from_description: true,
    magnitudes: |c, _, _| vec![c[0]],
    replay: |_, c, _, dt| {
        let samples = (c[0] / dt).round();
        (samples >= 1.0).then_some(EffectSpec::TimeDelay {
            samples: samples as usize,
        })
    },
    blind: Blind::SingleAndPair,
    draw: |_, rng, rate| {
        let samples = rng.random_range(10..=30usize);
        let delay = vec![samples as f64 / rate];
        (Some(EffectSpec::TimeDelay { samples }), delay)
    },
    ..row(Kind::TimeDelay, "time_delay", Fixed(1), |x, s, _, z, c| {
        (0..s.n).for_each(|j| z[(j, c)] = -x.pred_d[s.k * s.n + j])
    })
};
