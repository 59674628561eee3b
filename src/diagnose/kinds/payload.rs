//! `payload`: An unmodelled payload on one body (searched over the bodies): ten inertial
//! parameters `π_p` added to it (that body's own regressor columns; reported as its mass, kg),
//! so also any change of one body's parameters. Its columns lie in the model's span, so only
//! the test against the description can find it.
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::{body_index, row, uniform, Blind, ColumnCount::Fixed, Grid, Kind, KindSpec};
use crate::model::Model;
use crate::sim::scenario::EffectSpec;
use nalgebra::Vector3;
use rand_chacha::ChaCha8Rng;

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("payload mass", "kg"),
    in_model_span: true,
    grid: Grid::Body,
    magnitudes: |c, _, _| vec![c[0]],
    blind: Blind::Single,
    draw: draw_payload,
    // The body's own columns (links come first in θ, ten each).
    ..row(Kind::Payload, "payload", Fixed(10), |_, s, _, z, c| {
        let at = 10 * body_index(s.param, s.n);
        for i in 0..s.n {
            for m in 0..10 {
                z[(i, c + m)] = z[(i, at + m)];
            }
        }
    })
};

/// A 0.3–1 kg sphere of 3 cm radius on the last body, between the middle and the far end of
/// it (taken as twice its bounding ellipsoid's centre from the joint). (Inner bodies are not
/// drawn: on the leg their payloads are mostly not separable from the neighbours' parameters,
/// docs/diagnose.md.)
fn draw_payload(model: &Model, rng: &mut ChaCha8Rng, _: f64) -> (Option<EffectSpec>, Vec<f64>) {
    let n = model.dof();
    let mass = uniform(rng, 0.3, 1.0);
    let body = n;
    let tip = model.bodies()[body - 1]
        .bounding
        .as_ref()
        .map_or(Vector3::zeros(), |e| e.center * 2.0);
    let s = uniform(rng, 0.5, 1.0);
    let spec = EffectSpec::Payload {
        mass,
        com: [s * tip.x, s * tip.y, s * tip.z],
        radius: 0.03,
        body: None,
    };
    (Some(spec), vec![mass])
}
