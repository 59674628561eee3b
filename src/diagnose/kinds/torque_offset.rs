//! `torque_offset`: Logged `τ += o` (N m per joint).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::{row, signed, Blind, ColumnCount::PerJoint, Kind, KindSpec};
use crate::sim::scenario::EffectSpec;

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("offset", "N m"),
    replay: |_, c, _, _| Some(EffectSpec::TorqueOffset { offset: c.to_vec() }),
    blind: Blind::SingleAndPair,
    draw: |m, rng, _| {
        let o: Vec<f64> = (0..m.dof()).map(|_| signed(rng, 1.0, 3.0)).collect();
        (Some(EffectSpec::TorqueOffset { offset: o.clone() }), o)
    },
    ..row(
        Kind::TorqueOffset,
        "torque_offset",
        PerJoint(1),
        |_, s, _, z, c| (0..s.n).for_each(|j| z[(j, c + j)] = 1.0),
    )
};
