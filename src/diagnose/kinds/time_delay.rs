//! `time_delay`: Logged torque lags the kinematics by `d` (s, one for all joints).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::{row, Blind, ColumnCount::Fixed, Grid, Kind, KindSpec};
use crate::sim::scenario::EffectSpec;
use rand::Rng;

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    // The logged torque lags: a "negative delay" is no delay, and was the best single
    // column for a compliant transmission's encoder, which leads the link.
    non_negative: true,
    magnitude: ("delay", "s"),
    linearized: true,
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
    // The tangent `−τ̂̇` (without the Coulomb jumps) for lags short against the motion, and
    // secants at the grid's lags `d_g`, `(τ̂(t − d_g) − τ̂(t))/d_g` with the jumps, for lags
    // that are not (on a slow arm a lag of a quarter second reads as a spring through the
    // tangent: a lagged viscous torque `B q̇(t − d)` is `B q̇ + B d ω² q` on a sine).
    grid: Grid::Lag,
    ..row(Kind::TimeDelay, "time_delay", Fixed(1), |x, s, _, z, c| {
        if s.param == 0.0 {
            (0..s.n).for_each(|j| z[(j, c)] = -x.pred_d[s.k * s.n + j])
        } else {
            (0..s.n).for_each(|j| z[(j, c)] = x.lag_secant(s.k, j, s.n, s.param))
        }
    })
};
