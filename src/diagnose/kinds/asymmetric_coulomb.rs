//! `asymmetric_coulomb`: `τ_acting = −δ max(0, sign(q̇))` (N m per joint).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::{per_joint, row, Blind, ColumnCount::PerJoint, Kind, KindSpec};
use crate::dynamics::sign;
use crate::sim::scenario::EffectSpec;

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("forward excess delta", "N m"),
    replay: |_, c, _, _| Some(EffectSpec::AsymmetricCoulomb { delta: c.to_vec() }),
    blind: Blind::Single,
    draw: |m, rng, _| {
        let d = per_joint(rng, m.dof(), 1.0, 3.0);
        (Some(EffectSpec::AsymmetricCoulomb { delta: d.clone() }), d)
    },
    ..row(
        Kind::AsymmetricCoulomb,
        "asymmetric_coulomb",
        PerJoint(1),
        |_, s, _, z, c| (0..s.n).for_each(|j| z[(j, c + j)] = sign(s.qd[j]).max(0.0)),
    )
};
