//! `asymmetric_coulomb`: `τ_acting = −δ max(0, sign(q̇))` (N m per joint).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::physics::{self, Physics, ScenarioError, State};
use super::EffectSpec;
use super::{per_joint, row, Blind, ColumnCount::PerJoint, Kind, KindSpec, Property};
use physid_core::dynamics::sign;
use serde::{Deserialize, Serialize};

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    properties: &[Property::RowLocal],
    magnitude: ("forward excess delta", "N m"),
    replay: |_, c, _, _| {
        Some(EffectSpec::AsymmetricCoulomb(AsymmetricCoulomb {
            delta: c.to_vec(),
        }))
    },
    blind: Blind::Single,
    draw: |m, rng, _| {
        let d = per_joint(rng, m.dof(), 1.0, 3.0);
        (
            Some(EffectSpec::AsymmetricCoulomb(AsymmetricCoulomb {
                delta: d.clone(),
            })),
            d,
        )
    },
    ..row(
        Kind::AsymmetricCoulomb,
        "asymmetric_coulomb",
        PerJoint(1),
        |_, s, _, z, c| (0..s.n).for_each(|j| z[(j, c + j)] = sign(s.qd[j]).max(0.0)),
    )
};

/// Direction-dependent Coulomb friction: extra `δ max(0, tanh(q̇/v_s))`, i.e. `B_c + δ`
/// moving forward, `B_c` moving back, nothing at rest.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AsymmetricCoulomb {
    /// Extra forward Coulomb friction per joint (N m).
    pub delta: Vec<f64>,
}

impl Physics for AsymmetricCoulomb {
    fn toml_body(&self) -> String {
        format!("delta = {}", physics::toml_list(&self.delta))
    }

    fn validate(&self, n: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError> {
        physics::per_joint(&self.delta, n, &key("delta"))
    }

    fn act(&self, x: &State, out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate() {
            *o -= self.delta[j] * x.sign(x.qd[j]).max(0.0);
        }
    }
}
