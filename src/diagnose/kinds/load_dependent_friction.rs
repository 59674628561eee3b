//! `load_dependent_friction`: `τ_acting = −μ |τ| sign(q̇)` (per joint; `|τ|` from the nominal
//! prediction).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::{per_joint, row, Blind, ColumnCount::PerJoint, Kind, KindSpec};
use crate::dynamics::sign;
use crate::sim::scenario::EffectSpec;

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    non_negative: true,
    magnitude: ("coefficient mu", "-"),
    linearized: true,
    replay: |_, c, _, _| {
        let coefficient = c.to_vec();
        Some(EffectSpec::LoadDependentFriction { coefficient })
    },
    blind: Blind::SingleAndPair,
    draw: |m, rng, _| {
        let mu = per_joint(rng, m.dof(), 0.1, 0.25);
        let coefficient = mu.clone();
        (Some(EffectSpec::LoadDependentFriction { coefficient }), mu)
    },
    // The predicted torque, not the measured one: a column carrying the measurement's
    // own noise would "explain" it.
    ..row(
        Kind::LoadDependentFriction,
        "load_dependent_friction",
        PerJoint(1),
        |x, s, _, z, c| {
            (0..s.n).for_each(|j| z[(j, c + j)] = x.pred[s.k * s.n + j].abs() * sign(s.qd[j]))
        },
    )
};
