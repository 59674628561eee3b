//! `backlash`: Backlash read by a motor-side encoder: `q_logged = q + s`, `s ∈ [−b/2, b/2]` the
//! motor's offset in a dead zone of width `b` (rad per joint) that it crosses driven by its own
//! torque (`effect::DeadZone`).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::physics::{self, Physics, ScenarioError};
use super::EffectSpec;
use super::{per_joint, row, times, Blind, ColumnCount::PerJoint, Grid, Kind, KindSpec, Property};
use serde::{Deserialize, Serialize};

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("dead-zone width b", "rad"),
    properties: &[
        Property::NonNegative,
        Property::Linearized,
        // Offered from the description for the reason compliance is (its file).
        Property::OfferedFromDescription,
    ],
    replay: |_, c, _, _| {
        let width = c.iter().map(|b| b.max(0.0)).collect();
        Some(EffectSpec::Backlash(Backlash { width }))
    },
    blind: Blind::Single,
    scale: Some(|spec, s, _, m| match spec {
        EffectSpec::Backlash(b) => Some((
            EffectSpec::Backlash(Backlash {
                width: times(&b.width, s),
            }),
            times(m, s),
        )),
        _ => None,
    }),
    draw: |m, rng, _| {
        let b = per_joint(rng, m.dof(), 0.01, 0.03);
        (Some(EffectSpec::Backlash(Backlash { width: b.clone() })), b)
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

/// Backlash (a dead zone of `width` in the transmission) read on the motor side: the motor
/// rests against the side of the gap its torque pushes it to and crosses the gap driven by its
/// own torque ([`super::DeadZone`]), so the logged encoder reads `q + s`, `|s| ≤ b/2`; a sensor
/// effect like compliance (the link's loss of torque while the motor crosses is not
/// simulated).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Backlash {
    /// Dead-zone width per joint (rad, motor side seen at the joint, ≥ 0).
    pub width: Vec<f64>,
}

impl Physics for Backlash {
    fn toml_body(&self) -> String {
        format!("width = {}", physics::toml_list(&self.width))
    }

    fn validate(&self, n: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError> {
        let width = &self.width;
        physics::check(width.len() == n, &key("width"), || {
            format!("has {} entries for {n} joints", width.len())
        })?;
        physics::check(
            width.iter().all(|b| b.is_finite() && *b >= 0.0 && *b < 1.0),
            &key("width"),
            || "widths must be finite, >= 0 and < 1 rad".into(),
        )
    }

    fn dead_zone_width(&self) -> Option<&[f64]> {
        Some(&self.width)
    }
}
