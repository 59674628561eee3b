//! `payload`: An unmodelled payload on one body (searched over the bodies): ten inertial
//! parameters `π_p` added to it (that body's own regressor columns; reported as its mass, kg),
//! so also any change of one body's parameters. Its columns lie in the model's span, so only
//! the test against the description can find it.
//!
//! One row of the effect table (`super::KIND_TABLE`); equations and units in docs/diagnose.md.

use super::physics::{self, Physics, ScenarioError};
use super::EffectSpec;
use super::{body_index, row, uniform, Blind, ColumnCount::Fixed, Grid, Kind, KindSpec, Property};
use physid_core::model::Model;
use physid_core::spatial::InertialParams;
use nalgebra::Matrix3;
use nalgebra::Vector3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The kind's row: name, columns, magnitudes, replay and the blind benchmark's draw.
pub(super) const SPEC: KindSpec = KindSpec {
    magnitude: ("payload mass", "kg"),
    properties: &[
        Property::InModelSpan,
    ],
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
    let spec = EffectSpec::Payload(Payload {
        mass,
        com: [s * tip.x, s * tip.y, s * tip.z],
        radius: 0.03,
        body: None,
    });
    (Some(spec), vec![mass])
}

/// Largest payload CoM offset from its body's frame (m).
pub const MAX_PAYLOAD_OFFSET: f64 = 100.0;
/// Heaviest payload (kg).
pub const MAX_PAYLOAD_MASS: f64 = 1e6;

/// An unmodelled payload: a solid sphere of `mass` (kg) and `radius` (m) centred at `com`
/// (m, in the frame of body number `body`, 1 = the first moving body; default the last).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Payload {
    /// Mass (kg).
    pub mass: f64,
    /// Centre in the body's frame (m).
    pub com: [f64; 3],
    /// Radius (m).
    #[serde(default)]
    pub radius: f64,
    /// The body carrying it, numbered from 1 in body order (default: the last).
    #[serde(default)]
    pub body: Option<usize>,
}

impl Physics for Payload {
    fn toml_body(&self) -> String {
        let on = self.body.map_or(String::new(), |b| format!("\nbody = {b}"));
        format!(
            "mass = {:.6e}\ncom = {}\nradius = {:.6e}{on}",
            self.mass,
            physics::toml_list(&self.com),
            self.radius
        )
    }

    /// Its body among the `n`, a positive mass within [`MAX_PAYLOAD_MASS`], a non-negative
    /// radius, the centre of mass within [`MAX_PAYLOAD_OFFSET`] (m).
    fn validate(&self, n: usize, key: &dyn Fn(&str) -> String) -> Result<(), ScenarioError> {
        let Payload {
            mass,
            com,
            radius,
            body,
        } = *self;
        if let Some(b) = body {
            physics::check((1..=n).contains(&b), &key("body"), || {
                format!("{b} is not a body number 1 to {n}")
            })?;
        }
        physics::positive(mass, &key("mass"))?;
        physics::non_negative(radius, &key("radius"))?;
        physics::check(
            com.iter()
                .all(|c| c.is_finite() && c.abs() <= MAX_PAYLOAD_OFFSET),
            &key("com"),
            || format!("each coordinate must be finite and within ±{MAX_PAYLOAD_OFFSET} m"),
        )?;
        physics::check(mass <= MAX_PAYLOAD_MASS, &key("mass"), || {
            format!("{mass} kg exceeds {MAX_PAYLOAD_MASS} kg")
        })
    }

    fn on_robot(&self, model: &Model) -> Option<Model> {
        let Payload {
            mass,
            com,
            radius,
            body,
        } = *self;
        let on = body.map_or(model.dof() - 1, |b| b - 1);
        let sphere = InertialParams::from_mass_com_inertia(
            mass,
            &Vector3::from(com),
            &(Matrix3::identity() * (0.4 * mass * radius * radius)),
        );
        let mut bodies = model.bodies().to_vec();
        bodies[on].inertia = InertialParams(bodies[on].inertia.0 + sphere.0);
        let m = Model::new(model.name().to_string(), bodies, model.gravity())
            .expect("adding a payload keeps the model valid")
            .with_rotor_model(model.rotor_model());
        Some(m)
    }
}

/// The semi-real benchmark's payload: 0.5–3 kg on a random body after the first (the first's
/// mass acts on no joint of an arm whose first axis is vertical), a 4 cm sphere centred at a
/// random point of the body's bounding ellipsoid (within 10 cm of its frame without one).
/// Returns the effect, the body (index from 0) and the mass (kg).
pub fn payload_on_any_body(model: &Model, rng: &mut ChaCha8Rng) -> (EffectSpec, usize, f64) {
    payload_on_any_body_within(model, rng, PAYLOAD_MASS)
}

/// The payload masses [`payload_on_any_body`] draws from (kg): an arm's tool or part.
pub const PAYLOAD_MASS: (f64, f64) = (0.5, 3.0);

/// [`payload_on_any_body`] with its mass uniform in `mass` (kg, `lo..hi`), for robots of
/// another size.
pub fn payload_on_any_body_within(
    model: &Model,
    rng: &mut ChaCha8Rng,
    (lo, hi): (f64, f64),
) -> (EffectSpec, usize, f64) {
    let n = model.dof();
    let body = rng.random_range(1.min(n - 1)..n);
    let mass = lo + (hi - lo) * rng.random::<f64>();
    let unit = loop {
        let u = Vector3::new(
            2.0 * rng.random::<f64>() - 1.0,
            2.0 * rng.random::<f64>() - 1.0,
            2.0 * rng.random::<f64>() - 1.0,
        );
        if u.norm() <= 1.0 {
            break u;
        }
    };
    let com = match &model.bodies()[body].bounding {
        Some(e) => {
            let l =
                e.qs.cholesky()
                    .map_or(nalgebra::Matrix3::zeros(), |c| c.l());
            e.center + l * unit
        }
        None => unit * 0.1,
    };
    let spec = EffectSpec::Payload(Payload {
        mass,
        com: [com.x, com.y, com.z],
        radius: 0.04,
        body: Some(body + 1),
    });
    (spec, body, mass)
}
