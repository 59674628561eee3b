//! `quadratic_damping`: quadratic (fluid) damping `−c q̇ |q̇|` (N m s²/rad²). A simulator-only
//! effect: not in the diagnosis's library (no row of `super::KIND_TABLE`), for testing that an
//! unexplained residual is reported as such; the blind benchmark's out-of-library cases draw it.

use super::physics::{self, Physics, ScenarioError, State};
use super::EffectSpec;
use physid_core::model::Model;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// Quadratic (fluid) damping `−c q̇ |q̇|` (N m s²/rad²): not in the diagnosis's library,
/// for testing that an unexplained residual is reported as such.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct QuadraticDamping {
    /// Coefficient per joint (N m s²/rad²).
    pub coefficient: Vec<f64>,
}

impl QuadraticDamping {
    /// The blind benchmark's out-of-library draw: 0.5–1.5 N m s²/rad² per joint; the effect
    /// and its coefficients.
    pub fn draw(model: &Model, rng: &mut ChaCha8Rng) -> (EffectSpec, Vec<f64>) {
        let c: Vec<f64> = (0..model.dof())
            .map(|_| 0.5 + rng.random::<f64>())
            .collect();
        let spec = EffectSpec::QuadraticDamping(QuadraticDamping {
            coefficient: c.clone(),
        });
        (spec, c)
    }
}

impl Physics for QuadraticDamping {
    fn toml_body(&self) -> String {
        format!("coefficient = {}", physics::toml_list(&self.coefficient))
    }

    fn validate(&self, n: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError> {
        physics::per_joint_non_negative(&self.coefficient, n, &key("coefficient"))
    }

    fn act(&self, x: &State, out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate() {
            *o -= self.coefficient[j] * x.qd[j] * x.qd[j].abs();
        }
    }
}
