//! `rotor_inertia`: Reflected rotor inertia `I_a q̈` left out of the model (kg m² per joint).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::{row, Blind, ColumnCount::PerJoint, Kind, KindSpec, Property};
use physid_core::model::Model;

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("reflected inertia", "kg m^2"),
    properties: &[
        Property::RowLocal,
        Property::NonNegative,
        Property::RotorParameter,
        Property::Approximate,
    ],
    description: Some(Model::with_rotors_frozen),
    blind: Blind::Single,
    draw: |m, _, _| {
        let armature = (0..m.dof())
            .map(|i| physid_core::dynamics::armature(m, i))
            .collect();
        (None, armature)
    },
    ..row(
        Kind::RotorInertia,
        "rotor_inertia",
        PerJoint(1),
        |_, s, _, z, c| (0..s.n).for_each(|j| z[(j, c + j)] = s.qdd[j]),
    )
};
