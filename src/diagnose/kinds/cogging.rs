//! `cogging`: `τ_acting = −A sin(h N q + φ)` (N m per joint; harmonic `h` searched).
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::{per_joint, row, Blind, ColumnCount::PerJoint, Grid, Kind, KindSpec};
use crate::model::Model;
use crate::sim::scenario::EffectSpec;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("amplitude", "N m"),
    magnitude_pairs: true,
    grid: Grid::CoggingHarmonic,
    needs_rotor: true,
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
    Some(EffectSpec::Cogging {
        amplitude: (0..n).map(|j| c[j].hypot(c[n + j])).collect(),
        harmonic: vec![h; n],
        phase: (0..n).map(|j| c[n + j].atan2(c[j])).collect(),
    })
}

/// Cogging of amplitude 0.2–0.8 N m at one harmonic 1–8 of N q, random phases.
fn draw_cogging(model: &Model, rng: &mut ChaCha8Rng, _: f64) -> (Option<EffectSpec>, Vec<f64>) {
    let n = model.dof();
    let a = per_joint(rng, n, 0.2, 0.8);
    let h = rng.random_range(1..=8u32) as f64;
    let phase = per_joint(rng, n, 0.0, std::f64::consts::TAU);
    let spec = EffectSpec::Cogging {
        amplitude: a.clone(),
        harmonic: vec![h; n],
        phase,
    };
    (Some(spec), a)
}
