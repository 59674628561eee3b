//! `torque_offset`: Logged `τ += o` (N m per joint).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::physics::{self, Physics, ScenarioError};
use super::EffectSpec;
use super::{row, signed, times, Blind, ColumnCount::PerJoint, Kind, KindSpec, Property};
use serde::{Deserialize, Serialize};

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    properties: &[Property::RowLocal],
    magnitude: ("offset", "N m"),
    replay: |_, c, _, _| {
        Some(EffectSpec::TorqueOffset(TorqueOffset {
            offset: c.to_vec(),
        }))
    },
    blind: Blind::SingleAndPair,
    scale: Some(|spec, s, _, m| match spec {
        EffectSpec::TorqueOffset(o) => Some((
            EffectSpec::TorqueOffset(TorqueOffset {
                offset: times(&o.offset, s),
            }),
            times(m, s),
        )),
        _ => None,
    }),
    draw: |m, rng, _| {
        let o: Vec<f64> = (0..m.dof()).map(|_| signed(rng, 1.0, 3.0)).collect();
        (
            Some(EffectSpec::TorqueOffset(TorqueOffset { offset: o.clone() })),
            o,
        )
    },
    ..row(
        Kind::TorqueOffset,
        "torque_offset",
        PerJoint(1),
        |_, s, _, z, c| (0..s.n).for_each(|j| z[(j, c + j)] = 1.0),
    )
};

/// Logged torque `+= offset` (N m): a sensor effect, it does not act.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TorqueOffset {
    /// Offset per joint (N m).
    pub offset: Vec<f64>,
}

impl Physics for TorqueOffset {
    fn toml_body(&self) -> String {
        format!("offset = {}", physics::toml_list(&self.offset))
    }

    fn validate(&self, n: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError> {
        physics::per_joint(&self.offset, n, &key("offset"))
    }

    fn log_torque(&self, tau: &mut [f64]) {
        tau.iter_mut().zip(&self.offset).for_each(|(t, o)| *t += o)
    }
}
