//! `time_delay`: Logged torque lags the kinematics by `d` (s, one for all joints).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::physics::{self, Physics, ScenarioError};
use super::EffectSpec;
use super::{row, Blind, ColumnCount::Fixed, Kind, KindSpec, Property};
use rand::Rng;
use serde::{Deserialize, Serialize};

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("delay", "s"),
    properties: &[
        // The logged torque lags: a "negative delay" is no delay, and was the best single
        // column for a compliant transmission's encoder, which leads the link.
        Property::NonNegative,
        Property::Linearized,
        // On real KUKA logs at 200 Hz a lag of 125 ms doubles the description's error, yet the
        // re-identified model's friction and parameters take it in (cross-validation then selects
        // a spring); from the description its one column takes 70 % of the held-out mean square.
        Property::OfferedFromDescription,
    ],
    magnitudes: |c, _, _| vec![c[0]],
    replay: |_, c, _, dt| {
        let samples = (c[0] / dt).round();
        (samples >= 1.0).then_some(EffectSpec::TimeDelay(TimeDelay {
            samples: samples as usize,
        }))
    },
    blind: Blind::SingleAndPair,
    // In whole samples, at least one.
    scale: Some(|spec, s, rate, _| match spec {
        EffectSpec::TimeDelay(d) => {
            let samples = ((d.samples as f64 * s).round() as usize).max(1);
            Some((
                EffectSpec::TimeDelay(TimeDelay { samples }),
                vec![samples as f64 / rate],
            ))
        }
        _ => None,
    }),
    draw: |_, rng, rate| {
        let samples = rng.random_range(10..=30usize);
        let delay = vec![samples as f64 / rate];
        (Some(EffectSpec::TimeDelay(TimeDelay { samples })), delay)
    },
    ..row(Kind::TimeDelay, "time_delay", Fixed(1), |x, s, _, z, c| {
        (0..s.n).for_each(|j| z[(j, c)] = -x.pred_d[s.k * s.n + j])
    })
};

/// Longest torque-to-kinematics lag of a `time_delay` effect, in samples.
pub const MAX_DELAY_SAMPLES: usize = 100_000;

/// The logged torque lags the kinematics by `samples` control periods: a sensor effect.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TimeDelay {
    /// Delay in samples (≥ 1).
    pub samples: usize,
}

impl Physics for TimeDelay {
    fn toml_body(&self) -> String {
        format!("samples = {}", self.samples)
    }

    fn validate(&self, _: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError> {
        let samples = self.samples;
        physics::check(
            (1..=MAX_DELAY_SAMPLES).contains(&samples),
            &key("samples"),
            || format!("{samples} must be 1 to {MAX_DELAY_SAMPLES}"),
        )
    }

    fn delay_samples(&self) -> usize {
        self.samples
    }
}
