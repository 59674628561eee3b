//! `spring`: `τ_acting = −k (q − q₀)` (N m/rad, rad per joint).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::physics::{self, Physics, ScenarioError, State};
use super::EffectSpec;
use super::{per_joint, row, uniform, Blind, ColumnCount::PerJoint, Kind, KindSpec, Property};
use physid_core::model::Model;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    properties: &[Property::RowLocal],
    magnitude: ("stiffness", "N m/rad"),
    magnitudes: |c, n, _| c[..n].to_vec(),
    replay: replay_spring,
    blind: Blind::SingleAndPair,
    draw: draw_spring,
    ..row(Kind::Spring, "spring", PerJoint(2), |_, s, _, z, c| {
        (0..s.n).for_each(|j| {
            z[(j, c + j)] = s.q[j];
            z[(j, c + s.n + j)] = 1.0;
        })
    })
};

/// A spring's stiffness and rest angle from its columns `[q, 1]`: `k q + b` with `q₀ = −b/k`.
fn replay_spring(m: &Model, c: &[f64], _: f64, _: f64) -> Option<EffectSpec> {
    let n = m.dof();
    let rest = (0..n)
        .map(|j| if c[j] != 0.0 { -c[n + j] / c[j] } else { 0.0 })
        .collect();
    Some(EffectSpec::Spring(Spring {
        stiffness: c[..n].to_vec(),
        rest,
    }))
}

/// A spring per joint: stiffness 3–10 N m/rad about a rest angle within ±0.3 rad of
/// the middle of the joint range.
fn draw_spring(model: &Model, rng: &mut ChaCha8Rng, _: f64) -> (Option<EffectSpec>, Vec<f64>) {
    let n = model.dof();
    let k = per_joint(rng, n, 3.0, 10.0);
    let rest = model
        .bodies()
        .iter()
        .map(|b| {
            let mid = if b.limits.lower.is_finite() && b.limits.upper.is_finite() {
                0.5 * (b.limits.lower + b.limits.upper)
            } else {
                0.0
            };
            mid + uniform(rng, -0.3, 0.3)
        })
        .collect();
    let spec = EffectSpec::Spring(Spring {
        stiffness: k.clone(),
        rest,
    });
    (Some(spec), k)
}

/// Acting `τ = −k (q − q_0)` (N m/rad, rad): a cable or hose.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Spring {
    /// Stiffness per joint (N m/rad).
    pub stiffness: Vec<f64>,
    /// Rest position per joint (rad).
    pub rest: Vec<f64>,
}

impl Physics for Spring {
    fn toml_body(&self) -> String {
        let l = physics::toml_list;
        format!(
            "stiffness = {}\nrest = {}",
            l(&self.stiffness),
            l(&self.rest)
        )
    }

    fn validate(&self, n: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError> {
        physics::per_joint(&self.stiffness, n, &key("stiffness"))?;
        physics::per_joint(&self.rest, n, &key("rest"))
    }

    fn act(&self, x: &State, out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate() {
            *o -= self.stiffness[j] * (x.q[j] - self.rest[j]);
        }
    }
}
