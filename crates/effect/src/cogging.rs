//! `cogging`: `τ_acting = −A sin(h N q + φ)` (N m per joint; harmonic `h` searched).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::physics::{self, Physics, ScenarioError, State};
use super::EffectSpec;
use super::{per_joint, row, Blind, ColumnCount::PerJoint, Grid, Kind, KindSpec, Property};
use physid_core::model::Model;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("amplitude", "N m"),
    grid: Grid::CoggingHarmonic,
    properties: &[
        Property::RowLocal,
        Property::MagnitudePairs,
        Property::NeedsRotor,
    ],
    magnitudes: |c, n, _| (0..n).map(|j| c[j].hypot(c[n + j])).collect(),
    replay: replay_cogging,
    blind: Blind::SingleAndPair,
    draw: draw_cogging,
    // Joints without a rotor in the description keep zero columns.
    ..row(Kind::Cogging, "cogging", PerJoint(2), |x, s, _, z, c| {
        (0..s.n)
            .filter(|&j| x.model.bodies()[j].rotor.is_some())
            .for_each(|j| {
                let a = s.param * x.gear[j] * s.q[j];
                z[(j, c + j)] = a.sin();
                z[(j, c + s.n + j)] = a.cos();
            })
    })
};

/// Cogging's amplitude and phase from its sine and cosine coefficients.
fn replay_cogging(m: &Model, c: &[f64], h: f64, _: f64) -> Option<EffectSpec> {
    let n = m.dof();
    Some(EffectSpec::Cogging(Cogging {
        amplitude: (0..n).map(|j| c[j].hypot(c[n + j])).collect(),
        harmonic: vec![h; n],
        phase: (0..n).map(|j| c[n + j].atan2(c[j])).collect(),
    }))
}

/// Cogging of amplitude 0.2–0.8 N m at one harmonic 1–8 of N q, random phases.
fn draw_cogging(model: &Model, rng: &mut ChaCha8Rng, _: f64) -> (Option<EffectSpec>, Vec<f64>) {
    let n = model.dof();
    let a = per_joint(rng, n, 0.2, 0.8);
    let h = rng.random_range(1..=8u32) as f64;
    let phase = per_joint(rng, n, 0.0, std::f64::consts::TAU);
    let spec = EffectSpec::Cogging(Cogging {
        amplitude: a.clone(),
        harmonic: vec![h; n],
        phase,
    });
    (Some(spec), a)
}

/// Cogging / torque ripple at a harmonic of the rotor angle: acting `−A sin(h N q + φ)`,
/// `N` the joint's gear ratio (1 without a rotor).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Cogging {
    /// Amplitude per joint (N m).
    pub amplitude: Vec<f64>,
    /// Harmonic per joint (cycles per rotor revolution).
    pub harmonic: Vec<f64>,
    /// Phase per joint (rad); default 0.
    #[serde(default)]
    pub phase: Vec<f64>,
}

impl Physics for Cogging {
    fn toml_body(&self) -> String {
        let l = physics::toml_list;
        format!(
            "amplitude = {}\nharmonic = {}\nphase = {}",
            l(&self.amplitude),
            l(&self.harmonic),
            l(&self.phase)
        )
    }

    fn validate(&self, n: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError> {
        physics::per_joint(&self.amplitude, n, &key("amplitude"))?;
        physics::per_joint(&self.harmonic, n, &key("harmonic"))?;
        if !self.phase.is_empty() {
            physics::per_joint(&self.phase, n, &key("phase"))?;
        }
        Ok(())
    }

    fn act(&self, x: &State, out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate() {
            let gear = x.model.bodies()[j]
                .rotor
                .as_ref()
                .map_or(1.0, |r| r.gear_ratio);
            let ph = self.phase.get(j).copied().unwrap_or(0.0);
            *o -= self.amplitude[j] * (self.harmonic[j] * gear * x.q[j] + ph).sin();
        }
    }
}
