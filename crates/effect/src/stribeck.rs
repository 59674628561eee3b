//! `stribeck`: `τ_acting = −F_s exp(−(q̇/v)²) sign(q̇)` (N m per joint; `v` searched).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::physics::{self, Physics, ScenarioError, State};
use super::EffectSpec;
use super::{per_joint, row, uniform, Blind, ColumnCount::PerJoint, Grid, Kind, KindSpec, Property};
use physid_core::dynamics::sign;
use serde::{Deserialize, Serialize};

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    properties: &[
        Property::RowLocal,
        Property::NonNegative,
    ],
    magnitude: ("static excess F_s", "N m"),
    grid: Grid::StribeckVelocity,
    replay: |m, c, v, _| {
        Some(EffectSpec::Stribeck(Stribeck {
            static_extra: c.to_vec(),
            velocity: vec![v; m.dof()],
        }))
    },
    blind: Blind::SingleAndPair,
    draw: |m, rng, _| {
        let fs = per_joint(rng, m.dof(), 0.5, 2.0);
        let v = uniform(rng, 0.1, 0.4);
        let velocity = vec![v; m.dof()];
        let spec = EffectSpec::Stribeck(Stribeck {
            static_extra: fs.clone(),
            velocity,
        });
        (Some(spec), fs)
    },
    ..row(Kind::Stribeck, "stribeck", PerJoint(1), |_, s, _, z, c| {
        (0..s.n).for_each(|j| z[(j, c + j)] = (-(s.qd[j] / s.param).powi(2)).exp() * sign(s.qd[j]))
    })
};

/// Stribeck friction: extra resistance `F_s exp(−(q̇/v_st)²) tanh(q̇/v_s)` at low speed.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Stribeck {
    /// Static excess over Coulomb per joint (N m).
    pub static_extra: Vec<f64>,
    /// Stribeck velocity per joint (rad/s).
    pub velocity: Vec<f64>,
}

impl Physics for Stribeck {
    fn toml_body(&self) -> String {
        let l = physics::toml_list;
        format!(
            "static_extra = {}\nvelocity = {}",
            l(&self.static_extra),
            l(&self.velocity)
        )
    }

    fn validate(&self, n: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError> {
        physics::per_joint(&self.static_extra, n, &key("static_extra"))?;
        physics::per_joint(&self.velocity, n, &key("velocity"))?;
        physics::check(
            self.velocity.iter().all(|v| *v > 0.0),
            &key("velocity"),
            || "Stribeck velocities must be > 0".into(),
        )
    }

    fn act(&self, x: &State, out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate() {
            let qd = x.qd[j];
            *o -= self.static_extra[j] * (-(qd / self.velocity[j]).powi(2)).exp() * x.sign(qd);
        }
    }
}
