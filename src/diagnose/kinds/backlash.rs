//! `backlash`: Backlash read by a motor-side encoder: `q_logged = q + s`, `s ∈ [−b/2, b/2]` the
//! motor's offset in a dead zone of width `b` (rad per joint) that it crosses driven by its own
//! torque (`sim::effects::DeadZone`).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::{per_joint, row, Blind, ColumnCount::PerJoint, Grid, Kind, KindSpec};
use crate::sim::scenario::EffectSpec;

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    non_negative: true,
    magnitude: ("dead-zone width b", "rad"),
    linearized: true,
    // Offered from the description for the reason compliance is (its file).
    offered_from_description: true,
    replay: |_, c, _, _| {
        let width = c.iter().map(|b| b.max(0.0)).collect();
        Some(EffectSpec::Backlash { width })
    },
    blind: Blind::Single,
    draw: |m, rng, _| {
        let b = per_joint(rng, m.dof(), 0.01, 0.03);
        (Some(EffectSpec::Backlash { width: b.clone() }), b)
    },
    // −d/db_j ID(q − b_j s_j, q̇ − b_j ṡ_j, q̈ − b_j s̈_j) as a secant at the grid's
    // width b_g, s the unit-width offset of a dead zone of width b_g driven by the
    // low-passed logged torque, processed like the encoder (the tangent: s = ½ sign τ).
    grid: Grid::BacklashWidth,
    ..row(Kind::Backlash, "backlash", PerJoint(1), |x, s, w, z, c| {
        let cols = x.encoder_shift_columns(x.slack(s.param), s.param, s, w);
        z.columns_mut(c, s.n).copy_from(&cols);
    })
};
