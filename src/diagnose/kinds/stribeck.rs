//! `stribeck`: `τ_acting = −F_s exp(−(q̇/v)²) sign(q̇)` (N m per joint; `v` searched).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::{per_joint, row, uniform, Blind, ColumnCount::PerJoint, Grid, Kind, KindSpec};
use crate::dynamics::sign;
use crate::sim::scenario::EffectSpec;

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    non_negative: true,
    magnitude: ("static excess F_s", "N m"),
    grid: Grid::StribeckVelocity,
    replay: |m, c, v, _| {
        Some(EffectSpec::Stribeck {
            static_extra: c.to_vec(),
            velocity: vec![v; m.dof()],
        })
    },
    blind: Blind::SingleAndPair,
    draw: |m, rng, _| {
        let fs = per_joint(rng, m.dof(), 0.5, 2.0);
        let v = uniform(rng, 0.1, 0.4);
        let velocity = vec![v; m.dof()];
        let spec = EffectSpec::Stribeck {
            static_extra: fs.clone(),
            velocity,
        };
        (Some(spec), fs)
    },
    ..row(Kind::Stribeck, "stribeck", PerJoint(1), |_, s, _, z, c| {
        (0..s.n).for_each(|j| z[(j, c + j)] = (-(s.qd[j] / s.param).powi(2)).exp() * sign(s.qd[j]))
    })
};
