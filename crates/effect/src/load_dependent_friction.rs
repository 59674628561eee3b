//! `load_dependent_friction`: `τ_acting = −μ |τ| sign(q̇)` (per joint; `|τ|` from the nominal
//! prediction).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::physics::{self, Physics, ScenarioError, State};
use super::EffectSpec;
use super::{per_joint, row, Blind, ColumnCount::PerJoint, Kind, KindSpec, Property};
use physid_core::dynamics::sign;
use serde::{Deserialize, Serialize};

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("coefficient mu", "-"),
    properties: &[
        Property::RowLocal,
        Property::NonNegative,
        Property::Linearized,
    ],
    replay: |_, c, _, _| {
        let coefficient = c.to_vec();
        Some(EffectSpec::LoadDependentFriction(LoadDependentFriction {
            coefficient,
        }))
    },
    blind: Blind::SingleAndPair,
    draw: |m, rng, _| {
        let mu = per_joint(rng, m.dof(), 0.1, 0.25);
        let coefficient = mu.clone();
        (
            Some(EffectSpec::LoadDependentFriction(LoadDependentFriction {
                coefficient,
            })),
            mu,
        )
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

/// Load-dependent friction: extra `μ |τ_mot| tanh(q̇/v_s)` (gear mesh losses).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LoadDependentFriction {
    /// Coefficient per joint (dimensionless).
    pub coefficient: Vec<f64>,
}

impl Physics for LoadDependentFriction {
    fn toml_body(&self) -> String {
        format!("coefficient = {}", physics::toml_list(&self.coefficient))
    }

    fn validate(&self, n: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError> {
        physics::per_joint_non_negative(&self.coefficient, n, &key("coefficient"))
    }

    fn act(&self, x: &State, out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate() {
            *o -= self.coefficient[j] * x.tau_mot[j].abs() * x.sign(x.qd[j]);
        }
    }
}
