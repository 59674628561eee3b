//! `compliance`: Compliant transmission seen by a motor-side encoder: `q_logged = q + κ τ` (κ =
//! 1/k, rad/(N m) per joint).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::physics::{self, Physics, ScenarioError};
use super::EffectSpec;
use super::{per_joint, row, times, Blind, ColumnCount::PerJoint, Grid, Kind, KindSpec, Property};
use serde::{Deserialize, Serialize};

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("compliance 1/k", "rad/(N m)"),
    properties: &[
        Property::NonNegative,
        Property::Linearized,
        // A deflection `κ τ` shifts the gravity torque by `−κ ∂g/∂q τ`, which a spring and the
        // re-identified inertial parameters take in: on the real KUKA runs cross-validation named
        // neither this nor backlash, while from the description their columns take 60–95 % of the
        // held-out mean square (semi-real benchmark).
        Property::OfferedFromDescription,
    ],
    replay: |_, c, _, _| {
        let stiffness = c.iter().map(|k| 1.0 / k).collect();
        Some(EffectSpec::Compliance(Compliance { stiffness }))
    },
    blind: Blind::Single,
    // A compliance `1/k` scaled: the stiffness divided.
    scale: Some(|spec, s, _, m| match spec {
        EffectSpec::Compliance(c) => Some((
            EffectSpec::Compliance(Compliance {
                stiffness: c.stiffness.iter().map(|k| k / s).collect(),
            }),
            times(m, s),
        )),
        _ => None,
    }),
    draw: |m, rng, _| {
        let k = per_joint(rng, m.dof(), 300.0, 1000.0);
        let kappa = k.iter().map(|k| 1.0 / k).collect();
        (
            Some(EffectSpec::Compliance(Compliance { stiffness: k })),
            kappa,
        )
    },
    grid: Grid::Compliance,
    // −d/dκ_j ID(q − κ_j τ_j e_j, q̇ − κ_j τ̇_j e_j, q̈ − κ_j τ̈_j e_j), as a secant at the
    // grid's κ (Coulomb friction at the shifted velocity) or the tangent at 0.
    ..row(
        Kind::Compliance,
        "compliance",
        PerJoint(1),
        |x, s, w, z, c| {
            let cols = x.encoder_shift_columns(&x.defl, s.param, s, w);
            z.columns_mut(c, s.n).copy_from(&cols);
        },
    )
};

/// A compliant transmission read on the motor side: the logged encoder reads
/// `q + τ_mot / k` (the link lags the motor by the deflection); a sensor effect, the
/// controller runs on the link angle.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Compliance {
    /// Transmission stiffness per joint (N m/rad); `inf` for a rigid joint.
    pub stiffness: Vec<f64>,
}

impl Physics for Compliance {
    fn toml_body(&self) -> String {
        format!("stiffness = {}", physics::toml_list(&self.stiffness))
    }

    fn validate(&self, n: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError> {
        let stiffness = &self.stiffness;
        physics::check(stiffness.len() == n, &key("stiffness"), || {
            format!("has {} entries for {n} joints", stiffness.len())
        })?;
        physics::check(
            stiffness.iter().all(|s| *s > 0.0),
            &key("stiffness"),
            || "stiffnesses must be > 0 (inf for a rigid joint)".into(),
        )
    }

    fn log_angle(&self, q: &mut [f64], tau_mot: &[f64]) {
        for (j, o) in q.iter_mut().enumerate() {
            if self.stiffness[j].is_finite() {
                *o += tau_mot[j] / self.stiffness[j];
            }
        }
    }
}
