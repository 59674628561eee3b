//! The effect kinds of the library, one entry each in [`KIND_TABLE`]: its name, its regressor
//! columns, its magnitudes, its scenario form (to replay a calibrated robot in the simulator) and
//! the blind benchmark's draw. A new kind is one row here plus, if the simulator does not yet
//! make it, one `sim::scenario::EffectSpec` variant with its physics (the simulator's floor does
//! not know the diagnosis). Equations and units in `docs/diagnose.md`.
//!
//! Sign convention: a coefficient is the physical magnitude of the injected effect
//! (`crate::sim::effects`), e.g. the columns of an acting friction are `−∂τ_effect/∂c` because the
//! motor torque must overcome it.

use super::context::{backlash_widths, Context, Sample, Scratch};
use crate::dynamics::{regressor, sign, Data};
use crate::model::Model;
use crate::sim::scenario::EffectSpec;
use nalgebra::{DMatrix, Vector3};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// An effect kind the diagnosis can offer.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, schemars::JsonSchema, PartialOrd, Ord,
)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Logged `τ += o` (N m per joint).
    TorqueOffset,
    /// Logged `τ ×= 1 + δ` (per joint; a common δ is a scale of all inertial parameters).
    TorqueGain,
    /// Logged torque lags the kinematics by `d` (s, one for all joints).
    TimeDelay,
    /// `τ_acting = −k (q − q₀)` (N m/rad, rad per joint).
    Spring,
    /// `τ_acting = −F_s exp(−(q̇/v)²) sign(q̇)` (N m per joint; `v` searched).
    Stribeck,
    /// `τ_acting = −δ max(0, sign(q̇))` (N m per joint).
    AsymmetricCoulomb,
    /// `τ_acting = −μ |τ| sign(q̇)` (per joint; `|τ|` from the nominal prediction).
    LoadDependentFriction,
    /// `τ_acting = −A sin(h N q + φ)` (N m per joint; harmonic `h` searched).
    Cogging,
    /// Reflected rotor inertia `I_a q̈` left out of the model (kg m² per joint).
    RotorInertia,
    /// Gravity misaligned by a small base tilt (m/s² of the gravity vector's perpendicular
    /// components; reported as an angle).
    Tilt,
    /// Compliant transmission seen by a motor-side encoder: `q_logged = q + κ τ`
    /// (κ = 1/k, rad/(N m) per joint).
    Compliance,
    /// Backlash read by a motor-side encoder: `q_logged = q + s`, `s ∈ [−b/2, b/2]` the motor's
    /// offset in a dead zone of width `b` (rad per joint) that it crosses driven by its own
    /// torque (`sim::effects::DeadZone`).
    Backlash,
    /// An unmodelled payload on one body (searched over the bodies): ten inertial parameters
    /// `π_p` added to it (that body's own regressor columns; reported as its mass, kg), so also
    /// any change of one body's parameters. Its columns lie in the model's span, so only the
    /// test against the description can find it.
    Payload,
}

/// How many columns a kind adds for `n` joints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum ColumnCount {
    /// A fixed number, whatever the joint count.
    Fixed(usize),
    /// `k` per joint.
    PerJoint(usize),
}

/// The search grid of a kind's one-dimensional parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Grid {
    /// No parameter (one variant, `param = 0`).
    None,
    /// Stribeck velocities (rad/s): 0.04 · √2^i, i = 0..9.
    StribeckVelocity,
    /// Cogging harmonics per rotor revolution: 1..=8.
    CoggingHarmonic,
    /// The body it acts on, numbered from 1 in body order (0, the default: the last body).
    Body,
    /// Compliance `1/k` (rad/(N m)) the columns are a secant at: 0.5·10⁻³ · 2^i, i = 0..3
    /// (0, the default of a term: the tangent).
    Compliance,
    /// Backlash width (rad) the columns are a secant at: 0.01 · 2^i, i = 0..2 (0: the tangent).
    BacklashWidth,
}

/// Where the blind benchmark draws a kind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Blind {
    /// Not drawn (offered, not benchmarked).
    No,
    /// In single-effect cases.
    Single,
    /// In single-effect cases and in pairs (it acts on the torque and stays visible after
    /// identification at the benchmark's magnitudes).
    SingleAndPair,
}

/// Fills a kind's columns `c..` of `z` (`n × (p₀ + extra)`, the row block of one sample).
type Fill = fn(&Context, &Sample, &mut Scratch, &mut DMatrix<f64>, usize);
/// The magnitudes of a kind from its coefficients: `(c, n, |g|)`.
type Magnitudes = fn(&[f64], usize, f64) -> Vec<f64>;
/// The scenario effect a calibration's coefficients describe: `(model, c, param, dt)`.
type Replay = fn(&Model, &[f64], f64, f64) -> Option<EffectSpec>;
/// The blind benchmark's draw: `(model, rng, rate)` → the effect (`None` when it is a change of
/// the description instead) and its true magnitudes.
type Draw = fn(&Model, &mut ChaCha8Rng, f64) -> (Option<EffectSpec>, Vec<f64>);

/// Everything physid knows about one kind: one row of [`KIND_TABLE`].
pub(super) struct KindSpec {
    pub kind: Kind,
    /// snake_case name, as in scenario files.
    pub name: &'static str,
    pub columns: ColumnCount,
    /// The coefficients have a physical sign (≥ 0), kept in every fit.
    pub non_negative: bool,
    /// The magnitude's name and unit.
    pub magnitude: (&'static str, &'static str),
    /// Per-joint magnitude `i` needs columns `i` and `n + i` (an amplitude of a sine and a
    /// cosine); otherwise column `i` (a spring's rest term is not its stiffness).
    pub magnitude_pairs: bool,
    /// The columns lie in the span of the model's own (only the description test sees it).
    pub in_model_span: bool,
    /// The columns are linearized about the nominal model `θ̂₀`.
    pub linearized: bool,
    /// A model with rotors carries this effect among its own parameters (the rotors' inertia).
    pub rotor_parameter: bool,
    /// The columns approximate the effect by more than a linearization (reflected inertia
    /// without the rotor's gyroscopic terms).
    pub approximate: bool,
    /// A motor-side effect at the rotor's angle: offered only on joints whose rotor (and gear
    /// ratio) the description knows (cogging: a link-angle harmonic is not cogging).
    pub needs_rotor: bool,
    pub grid: Grid,
    pub fill: Fill,
    pub magnitudes: Magnitudes,
    pub replay: Replay,
    /// The description a user would give when this effect is present: `None` if unchanged
    /// (rotor inertia left out: its rotors frozen into their bodies).
    pub description: Option<fn(&Model) -> Model>,
    pub blind: Blind,
    pub draw: Draw,
}

const fn row(kind: Kind, name: &'static str, columns: ColumnCount, fill: Fill) -> KindSpec {
    KindSpec {
        kind,
        name,
        columns,
        non_negative: false,
        magnitude: ("", ""),
        magnitude_pairs: false,
        in_model_span: false,
        linearized: false,
        rotor_parameter: false,
        approximate: false,
        needs_rotor: false,
        grid: Grid::None,
        fill,
        magnitudes: same,
        replay: |_, _, _, _| None,
        description: None,
        blind: Blind::No,
        draw: |_, _, _| (None, vec![]),
    }
}

/// One row per kind, in report order ([`Kind::ALL`], whose length is this table's).
pub(super) const KIND_TABLE: &[KindSpec] = {
    use ColumnCount::{Fixed, PerJoint};
    &[
        KindSpec {
            magnitude: ("offset", "N m"),
            replay: |_, c, _, _| Some(EffectSpec::TorqueOffset { offset: c.to_vec() }),
            blind: Blind::SingleAndPair,
            draw: |m, rng, _| {
                let o: Vec<f64> = (0..m.dof()).map(|_| signed(rng, 1.0, 3.0)).collect();
                (Some(EffectSpec::TorqueOffset { offset: o.clone() }), o)
            },
            ..row(
                Kind::TorqueOffset,
                "torque_offset",
                PerJoint(1),
                |_, s, _, z, c| (0..s.n).for_each(|j| z[(j, c + j)] = 1.0),
            )
        },
        KindSpec {
            magnitude: ("gain error relative to the median joint", "-"),
            linearized: true,
            magnitudes: gain_magnitudes,
            // The column is the nominal prediction, which already carries the gain.
            replay: |_, c, _, _| {
                let gain = c.iter().map(|b| 1.0 / (1.0 - b)).collect();
                Some(EffectSpec::TorqueGain { gain })
            },
            blind: Blind::Single,
            draw: draw_gain,
            ..row(
                Kind::TorqueGain,
                "torque_gain",
                PerJoint(1),
                |x, s, _, z, c| (0..s.n).for_each(|j| z[(j, c + j)] = x.pred[s.k * s.n + j]),
            )
        },
        KindSpec {
            // The logged torque lags: a "negative delay" is no delay, and was the best single
            // column for a compliant transmission's encoder, which leads the link.
            non_negative: true,
            magnitude: ("delay", "s"),
            linearized: true,
            magnitudes: |c, _, _| vec![c[0]],
            replay: |_, c, _, dt| {
                let samples = (c[0] / dt).round();
                (samples >= 1.0).then_some(EffectSpec::TimeDelay {
                    samples: samples as usize,
                })
            },
            blind: Blind::SingleAndPair,
            draw: |_, rng, rate| {
                let samples = rng.random_range(10..=30usize);
                let delay = vec![samples as f64 / rate];
                (Some(EffectSpec::TimeDelay { samples }), delay)
            },
            ..row(Kind::TimeDelay, "time_delay", Fixed(1), |x, s, _, z, c| {
                (0..s.n).for_each(|j| z[(j, c)] = -x.pred_d[s.k * s.n + j])
            })
        },
        KindSpec {
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
        },
        KindSpec {
            non_negative: true,
            magnitude: ("static excess F_s", "N m"),
            grid: Grid::StribeckVelocity,
            replay: |m, c, v, _| {
                Some(EffectSpec::Stribeck {
                    static_extra: c.to_vec(),
                    velocity: vec![v; m.dof()],
                })
            },
            blind: Blind::SingleAndPair,
            draw: |m, rng, _| {
                let fs = per_joint(rng, m.dof(), 0.5, 2.0);
                let v = uniform(rng, 0.1, 0.4);
                let velocity = vec![v; m.dof()];
                let spec = EffectSpec::Stribeck {
                    static_extra: fs.clone(),
                    velocity,
                };
                (Some(spec), fs)
            },
            ..row(Kind::Stribeck, "stribeck", PerJoint(1), |_, s, _, z, c| {
                (0..s.n).for_each(|j| {
                    z[(j, c + j)] = (-(s.qd[j] / s.param).powi(2)).exp() * sign(s.qd[j])
                })
            })
        },
        KindSpec {
            magnitude: ("forward excess delta", "N m"),
            replay: |_, c, _, _| Some(EffectSpec::AsymmetricCoulomb { delta: c.to_vec() }),
            blind: Blind::Single,
            draw: |m, rng, _| {
                let d = per_joint(rng, m.dof(), 1.0, 3.0);
                (Some(EffectSpec::AsymmetricCoulomb { delta: d.clone() }), d)
            },
            ..row(
                Kind::AsymmetricCoulomb,
                "asymmetric_coulomb",
                PerJoint(1),
                |_, s, _, z, c| (0..s.n).for_each(|j| z[(j, c + j)] = sign(s.qd[j]).max(0.0)),
            )
        },
        KindSpec {
            non_negative: true,
            magnitude: ("coefficient mu", "-"),
            linearized: true,
            replay: |_, c, _, _| {
                let coefficient = c.to_vec();
                Some(EffectSpec::LoadDependentFriction { coefficient })
            },
            blind: Blind::SingleAndPair,
            draw: |m, rng, _| {
                let mu = per_joint(rng, m.dof(), 0.1, 0.25);
                let coefficient = mu.clone();
                (Some(EffectSpec::LoadDependentFriction { coefficient }), mu)
            },
            // The predicted torque, not the measured one: a column carrying the measurement's
            // own noise would "explain" it.
            ..row(
                Kind::LoadDependentFriction,
                "load_dependent_friction",
                PerJoint(1),
                |x, s, _, z, c| {
                    (0..s.n)
                        .for_each(|j| z[(j, c + j)] = x.pred[s.k * s.n + j].abs() * sign(s.qd[j]))
                },
            )
        },
        KindSpec {
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
        },
        KindSpec {
            non_negative: true,
            magnitude: ("reflected inertia", "kg m^2"),
            rotor_parameter: true,
            approximate: true,
            description: Some(Model::with_rotors_frozen),
            blind: Blind::Single,
            draw: |m, _, _| {
                let armature = (0..m.dof())
                    .map(|i| crate::dynamics::armature(m, i))
                    .collect();
                (None, armature)
            },
            ..row(
                Kind::RotorInertia,
                "rotor_inertia",
                PerJoint(1),
                |_, s, _, z, c| (0..s.n).for_each(|j| z[(j, c + j)] = s.qdd[j]),
            )
        },
        KindSpec {
            magnitude: ("tilt angle", "rad"),
            linearized: true,
            magnitudes: |c, _, g| vec![(c[0].hypot(c[1]) / g).atan()],
            replay: |m, c, _, _| {
                tilt_angles(m, c).map(|(roll, pitch)| EffectSpec::Tilt { roll, pitch })
            },
            blind: Blind::Single,
            draw: draw_tilt,
            ..row(Kind::Tilt, "tilt", Fixed(2), fill_tilt)
        },
        KindSpec {
            non_negative: true,
            magnitude: ("compliance 1/k", "rad/(N m)"),
            linearized: true,
            replay: |_, c, _, _| {
                let stiffness = c.iter().map(|k| 1.0 / k).collect();
                Some(EffectSpec::Compliance { stiffness })
            },
            blind: Blind::Single,
            draw: |m, rng, _| {
                let k = per_joint(rng, m.dof(), 300.0, 1000.0);
                let kappa = k.iter().map(|k| 1.0 / k).collect();
                (Some(EffectSpec::Compliance { stiffness: k }), kappa)
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
        },
        KindSpec {
            non_negative: true,
            magnitude: ("dead-zone width b", "rad"),
            linearized: true,
            replay: |_, c, _, _| {
                let width = c.iter().map(|b| b.max(0.0)).collect();
                Some(EffectSpec::Backlash { width })
            },
            blind: Blind::Single,
            draw: |m, rng, _| {
                let b = per_joint(rng, m.dof(), 0.01, 0.03);
                (Some(EffectSpec::Backlash { width: b.clone() }), b)
            },
            // −d/db_j ID(q − b_j s_j, q̇ − b_j ṡ_j, q̈ − b_j s̈_j) as a secant at the grid's
            // width b_g, s the unit-width offset of a dead zone of width b_g driven by the
            // low-passed logged torque, processed like the encoder (the tangent: s = ½ sign τ).
            grid: Grid::BacklashWidth,
            ..row(Kind::Backlash, "backlash", PerJoint(1), |x, s, w, z, c| {
                let cols = x.encoder_shift_columns(x.slack(s.param), s.param, s, w);
                z.columns_mut(c, s.n).copy_from(&cols);
            })
        },
        KindSpec {
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
        },
    ]
};

impl Kind {
    /// Every kind, in report order.
    pub const ALL: [Kind; KIND_TABLE.len()] = {
        let mut all = [Kind::TorqueOffset; KIND_TABLE.len()];
        let mut i = 0;
        while i < KIND_TABLE.len() {
            all[i] = KIND_TABLE[i].kind;
            i += 1;
        }
        all
    };

    /// The kind's row of [`KIND_TABLE`].
    pub(super) fn spec(&self) -> &'static KindSpec {
        KIND_TABLE
            .iter()
            .find(|s| s.kind == *self)
            .expect("every kind has a row")
    }

    /// snake_case name (as in scenario files).
    pub fn name(&self) -> &'static str {
        self.spec().name
    }

    /// Columns for `n` joints.
    pub fn columns(&self, n: usize) -> usize {
        match self.spec().columns {
            ColumnCount::Fixed(c) => c,
            ColumnCount::PerJoint(k) => k * n,
        }
    }

    /// Whether the coefficients have a physical sign (≥ 0), kept in every fit: Stribeck's
    /// static excess, load-dependent friction, reflected rotor inertia, compliance, backlash. A
    /// fit that needs the opposite sign is not this effect.
    pub fn non_negative(&self) -> bool {
        self.spec().non_negative
    }

    /// The magnitude's name and unit, per joint (or for the whole robot).
    pub fn magnitude(&self) -> (&'static str, &'static str) {
        self.spec().magnitude
    }

    /// The columns (offsets within the kind's own) magnitude `i` of `n` joints depends on.
    pub fn magnitude_columns(&self, i: usize, n: usize) -> Vec<usize> {
        if self.spec().magnitude_pairs {
            vec![i, n + i]
        } else {
            vec![i]
        }
    }

    /// The physical magnitudes (the unit of [`Kind::magnitude`]) of coefficients `c` for `n`
    /// joints under gravity of norm `gravity` (m/s²).
    pub fn magnitudes(&self, c: &[f64], n: usize, gravity: f64) -> Vec<f64> {
        (self.spec().magnitudes)(c, n, gravity)
    }

    /// Whether the columns lie in the span of the model's own (its parameters express the
    /// effect exactly): cross-validation cannot see it and does not offer it.
    pub fn in_model_span(&self) -> bool {
        self.spec().in_model_span
    }

    /// Whether the columns are linearized about the nominal model (they need `θ̂₀`).
    pub fn linearized(&self) -> bool {
        self.spec().linearized
    }

    /// Whether the columns only approximate the effect (linearized about the nominal model, or
    /// reflected rotor inertia without gyroscopic terms): what they miss biases the parameters,
    /// so the test against the description does not run beside such an effect.
    pub fn approximate(&self) -> bool {
        self.spec().linearized || self.spec().approximate
    }

    /// Whether a model with rotors carries this effect among its own parameters (reflected
    /// rotor inertia): testing it against the description would test the description.
    pub fn is_rotor_parameter(&self) -> bool {
        self.spec().rotor_parameter
    }

    /// The grid of the one-dimensional search for a robot of `n` joints, if any: Stribeck
    /// velocities (rad/s, ratio √2), cogging harmonics (per rotor revolution), bodies (numbered
    /// from 1).
    pub fn grid(&self, n: usize) -> Vec<f64> {
        match self.spec().grid {
            Grid::StribeckVelocity => (0..10).map(|i| 0.04 * 2f64.powf(i as f64 / 2.0)).collect(),
            Grid::CoggingHarmonic => (1..=8).map(f64::from).collect(),
            Grid::Body => (1..=n).map(|b| b as f64).collect(),
            Grid::Compliance => (0..4).map(|i| 0.5e-3 * 2f64.powi(i)).collect(),
            Grid::BacklashWidth => backlash_widths(),
            Grid::None => vec![0.0],
        }
    }

    /// Whether the kind acts at the rotor's angle and needs the description's rotors.
    pub fn needs_rotor(&self) -> bool {
        self.spec().needs_rotor
    }

    /// Whether the kind has a grid.
    pub fn gridded(&self) -> bool {
        self.spec().grid != Grid::None
    }

    /// The grid value a term takes when none is given (`None`: one must be given).
    pub fn default_param(&self) -> Option<f64> {
        match self.spec().grid {
            Grid::None | Grid::Body | Grid::Compliance | Grid::BacklashWidth => Some(0.0),
            Grid::StribeckVelocity | Grid::CoggingHarmonic => None,
        }
    }

    /// Whether `param` is a valid grid value of this kind for `n` joints (a Stribeck velocity
    /// or harmonic in (0, 1000], a compliance in [0, 1] rad/(N m): beyond, no transmission).
    pub fn valid_param(&self, param: f64, n: usize) -> bool {
        match self.spec().grid {
            Grid::None => param == 0.0,
            Grid::Body => param.fract() == 0.0 && param >= 0.0 && param <= n as f64,
            Grid::StribeckVelocity | Grid::CoggingHarmonic => param > 0.0 && param <= 1e3,
            Grid::Compliance => (0.0..=1.0).contains(&param),
            Grid::BacklashWidth => param == 0.0 || self.grid(n).contains(&param),
        }
    }

    /// What the grid's value is, for messages.
    pub fn grid_meaning(&self) -> &'static str {
        match self.spec().grid {
            Grid::StribeckVelocity => "Stribeck velocity, rad/s",
            Grid::CoggingHarmonic => "harmonic per rotor revolution",
            Grid::Body => "body number from 1, default the last",
            Grid::Compliance => "compliance 1/k of the secant, rad/(N m); 0: the tangent",
            Grid::BacklashWidth => "width of the secant, rad: 0.01, 0.02 or 0.04; 0: the tangent",
            Grid::None => "",
        }
    }

    /// The body (index) a single magnitude belongs to, for kinds searched over bodies.
    pub fn body(&self, param: f64, n: usize) -> Option<usize> {
        (self.spec().grid == Grid::Body).then(|| body_index(param, n))
    }

    /// The scenario effect that replays calibrated coefficients `c` (grid value `param`, data
    /// sample period `dt` s) in the simulator; `None` if the kind has no scenario form (a
    /// rotor inertia, a payload, a tilt under a gravity not along −z, a delay under a sample).
    pub fn replay(&self, model: &Model, c: &[f64], param: f64, dt: f64) -> Option<EffectSpec> {
        (self.spec().replay)(model, c, param, dt)
    }

    /// The description a user would give of `model` when this effect is present (the model
    /// itself unless the effect is something the description leaves out).
    pub fn description(&self, model: &Model) -> Model {
        self.spec()
            .description
            .map_or_else(|| model.clone(), |f| f(model))
    }

    /// The kind a change of one body's own parameters is found as (a payload: the kind searched
    /// over bodies).
    pub fn body_change() -> Option<Kind> {
        KIND_TABLE
            .iter()
            .find(|s| s.grid == Grid::Body)
            .map(|s| s.kind)
    }

    /// Whether the kind frees one body's ten parameters (a payload or change of the body).
    pub fn is_body_change(&self) -> bool {
        self.spec().grid == Grid::Body
    }

    /// The kinds the semi-real benchmark injects on real logs (`experiment::semireal`): those
    /// whose injection needs no model of the robot beyond its description.
    pub fn semi_real_singles() -> Vec<Kind> {
        use Kind::*;
        vec![
            TorqueGain,
            TimeDelay,
            Tilt,
            TorqueOffset,
            Backlash,
            Compliance,
        ]
    }

    /// The kinds the blind benchmark draws in single-effect cases, in report order.
    pub fn blind_singles() -> Vec<Kind> {
        KIND_TABLE
            .iter()
            .filter(|s| s.blind != Blind::No)
            .map(|s| s.kind)
            .collect()
    }

    /// The kinds the blind benchmark pairs in two-effect cases, in report order.
    pub fn blind_pairs() -> Vec<Kind> {
        KIND_TABLE
            .iter()
            .filter(|s| s.blind == Blind::SingleAndPair)
            .map(|s| s.kind)
            .collect()
    }

    /// The blind benchmark's draw of this kind for `model` (the simulated robot, with rotors)
    /// at sample rate `rate` (Hz): the scenario effect (`None` when it is a change of the
    /// description, see [`Kind::description`]) and its true magnitudes. Ranges, per joint unless
    /// said: offset ±1–3 N m; one joint's gain 1 ± 0.15–0.3; delay 10–30 samples; spring
    /// 3–10 N m/rad about the middle ± 0.3 rad; Stribeck 0.5–2 N m at one velocity 0.1–0.4 rad/s;
    /// forward Coulomb excess 1–3 N m; load-dependent 0.1–0.25; cogging 0.2–0.8 N m at one
    /// harmonic 1–8 with random phases; the model's own reflected rotor inertia; tilt
    /// 0.2–0.35 rad in a random direction; compliance 300–1000 N m/rad; backlash 0.01–0.03 rad;
    /// a 0.3–1 kg payload. Smaller effects are mostly absorbed by the identified inertial and
    /// friction parameters and leave a residual below the 0.3 N m torque noise.
    pub fn draw(
        &self,
        model: &Model,
        rng: &mut ChaCha8Rng,
        rate: f64,
    ) -> (Option<EffectSpec>, Vec<f64>) {
        (self.spec().draw)(model, rng, rate)
    }
}

/// What data separates two kinds the data could not tell apart.
pub fn separate_by(a: Kind, b: Kind) -> String {
    use Kind::*;
    let pair = if a <= b { (a, b) } else { (b, a) };
    match pair {
        (TorqueOffset, AsymmetricCoulomb) => "rests under load (q̇ = 0 with τ ≠ 0): an offset persists at rest, direction-dependent friction vanishes; without rests δ·max(0, sign q̇) = δ/2 + (δ/2) sign q̇ is an offset plus Coulomb friction".into(),
        (TorqueOffset, Spring) => "a wider range of joint angles (the spring's torque varies with q, an offset does not)".into(),
        (TorqueGain, LoadDependentFriction) => "braking motion (τ and q̇ of opposite sign) as often as driving".into(),
        (Stribeck, AsymmetricCoulomb) | (TorqueOffset, Stribeck) => "slow motion in both directions (q̇ within the Stribeck velocity)".into(),
        (RotorInertia, Compliance) | (TimeDelay, Compliance) | (TimeDelay, RotorInertia) => "faster excitation (the terms scale with q̈, τ̇ and τ̈ differently with frequency)".into(),
        _ => "an excitation on which their regressor columns differ more (other joint ranges, speeds and torque levels)".into(),
    }
}

/// The body index of a body-grid value (numbered from 1; 0: the last of `n`).
fn body_index(param: f64, n: usize) -> usize {
    if param >= 1.0 {
        (param as usize - 1).min(n - 1)
    } else {
        n - 1
    }
}

/// The coefficients themselves.
fn same(c: &[f64], _: usize, _: f64) -> Vec<f64> {
    c.to_vec()
}

/// Torque gains relative to the median joint: the column is the nominal prediction, which
/// already carries the gain, so `τ = Y θ + β τ̂` with `τ̂ ≈ τ` gives `1 + g = 1/(1 − β)`.
fn gain_magnitudes(c: &[f64], _: usize, _: f64) -> Vec<f64> {
    let g: Vec<f64> = c.iter().map(|b| b / (1.0 - b)).collect();
    super::stats::relative_to_median(&g)
}

/// A spring's stiffness and rest angle from its columns `[q, 1]`: `k q + b` with `q₀ = −b/k`.
fn replay_spring(m: &Model, c: &[f64], _: f64, _: f64) -> Option<EffectSpec> {
    let n = m.dof();
    let rest = (0..n)
        .map(|j| if c[j] != 0.0 { -c[n + j] / c[j] } else { 0.0 })
        .collect();
    Some(EffectSpec::Spring {
        stiffness: c[..n].to_vec(),
        rest,
    })
}

/// Cogging's amplitude and phase from its sine and cosine coefficients.
fn replay_cogging(m: &Model, c: &[f64], h: f64, _: f64) -> Option<EffectSpec> {
    let n = m.dof();
    Some(EffectSpec::Cogging {
        amplitude: (0..n).map(|j| c[j].hypot(c[n + j])).collect(),
        harmonic: vec![h; n],
        phase: (0..n).map(|j| c[n + j].atan2(c[j])).collect(),
    })
}

/// Tilt columns: the gravity torque of the nominal model under gravity along each of the two
/// directions perpendicular to the model's.
fn fill_tilt(x: &Context, s: &Sample, w: &mut Scratch, z: &mut DMatrix<f64>, c: usize) {
    let tilted = w.tilted.get_or_insert_with(|| {
        x.perp
            .iter()
            .map(|u| {
                let gm = x.model().clone().with_gravity(*u);
                let gd = Data::new(&gm);
                (gm, gd)
            })
            .collect()
    });
    for (i, (gm, gd)) in tilted.iter_mut().enumerate() {
        regressor(gm, gd, s.q, &w.zeros, &w.zeros, &mut w.yg);
        let col = &w.yg * &x.theta0;
        (0..s.n).for_each(|j| z[(j, c + i)] = col[j]);
    }
}

/// Roll and pitch (rad) of the scenario's tilt whose gravity has the calibrated components
/// `c₀, c₁` (m/s²) along the library's tilt directions `u₁, u₂`; `None` if the model's gravity
/// is not along −z.
fn tilt_angles(model: &Model, c: &[f64]) -> Option<(f64, f64)> {
    let g = model.gravity();
    let g0 = g.norm();
    if g0 == 0.0 || (g / g0 + Vector3::z()).norm() > 1e-9 {
        return None;
    }
    // The library's directions for g along −z: u₁ = x, u₂ = ĝ × u₁ = −y; the coefficients are
    // the tilted gravity's components along them (m/s²).
    let (dx, dy) = (c[0] / g0, -c[1] / g0);
    if dx * dx + dy * dy >= 1.0 {
        return None;
    }
    let d = Vector3::new(dx, dy, -(1.0 - dx * dx - dy * dy).sqrt());
    // The scenario's gravity is R_xᵀ(roll) R_yᵀ(pitch) g = g₀ (sin p, −sin r cos p, −cos r cos p).
    let pitch = d.x.asin();
    let roll = (-d.y).atan2(-d.z);
    Some((roll, pitch))
}

fn uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

fn signed(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    let v = uniform(rng, lo, hi);
    if rng.random::<bool>() {
        v
    } else {
        -v
    }
}

/// `n` independent uniform draws in `[lo, hi)`.
fn per_joint(rng: &mut ChaCha8Rng, n: usize, lo: f64, hi: f64) -> Vec<f64> {
    (0..n).map(|_| uniform(rng, lo, hi)).collect()
}

/// One joint's torque constant off by 15–30 %, reported relative to the median joint.
fn draw_gain(m: &Model, rng: &mut ChaCha8Rng, _: f64) -> (Option<EffectSpec>, Vec<f64>) {
    let n = m.dof();
    let j = rng.random_range(0..n);
    let mut gain = vec![1.0; n];
    gain[j] += signed(rng, 0.15, 0.3);
    let relative = super::stats::relative_to_median(&gain);
    (Some(EffectSpec::TorqueGain { gain }), relative)
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
    let spec = EffectSpec::Spring {
        stiffness: k.clone(),
        rest,
    };
    (Some(spec), k)
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

/// A base tilt of 0.2–0.35 rad in a random direction.
fn draw_tilt(_: &Model, rng: &mut ChaCha8Rng, _: f64) -> (Option<EffectSpec>, Vec<f64>) {
    let angle = uniform(rng, 0.2, 0.35);
    let dir = uniform(rng, 0.0, std::f64::consts::TAU);
    let spec = EffectSpec::Tilt {
        roll: angle * dir.cos(),
        pitch: angle * dir.sin(),
    };
    (Some(spec), vec![angle])
}

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

#[cfg(test)]
mod tests {
    use super::*;

    /// Each variant's number, written out by hand. The match is exhaustive: a new variant does
    /// not compile until it is numbered here (the next number, with `variants` below raised),
    /// and the test then fails until it has its row in the effect table. `Kind::ALL` takes its
    /// length from the table, so a row cannot be left out of it.
    fn number(k: Kind) -> usize {
        match k {
            Kind::TorqueOffset => 0,
            Kind::TorqueGain => 1,
            Kind::TimeDelay => 2,
            Kind::Spring => 3,
            Kind::Stribeck => 4,
            Kind::AsymmetricCoulomb => 5,
            Kind::LoadDependentFriction => 6,
            Kind::Cogging => 7,
            Kind::RotorInertia => 8,
            Kind::Tilt => 9,
            Kind::Compliance => 10,
            Kind::Backlash => 11,
            Kind::Payload => 12,
        }
    }

    #[test]
    fn every_variant_has_a_row_and_is_in_all() {
        let variants = 13;
        let mut seen = vec![false; variants];
        for k in Kind::ALL {
            let i = number(k);
            assert!(
                i < variants && !seen[i],
                "{k:?} numbered {i}, twice or past {variants}"
            );
            seen[i] = true;
        }
        assert!(
            seen.iter().all(|s| *s),
            "variants without a row in KIND_TABLE: {seen:?}"
        );
        assert_eq!(KIND_TABLE.len(), variants);
    }

    #[test]
    fn every_kind_has_one_row_with_a_unique_name() {
        for k in Kind::ALL {
            assert_eq!(
                KIND_TABLE.iter().filter(|s| s.kind == k).count(),
                1,
                "{k:?}"
            );
            assert!(
                !k.magnitude().0.is_empty() && !k.magnitude().1.is_empty(),
                "{k:?}"
            );
        }
        let mut names: Vec<&str> = Kind::ALL.iter().map(|k| k.name()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), Kind::ALL.len());
        // The names are serde's: the JSON report spells kinds the same way.
        for k in Kind::ALL {
            assert_eq!(
                serde_json::to_string(&k).unwrap(),
                format!("\"{}\"", k.name())
            );
        }
        assert_eq!(Kind::Cogging.columns(3), 6);
        assert_eq!(Kind::Payload.columns(7), 10);
        assert_eq!(Kind::Stribeck.grid(3).len(), 10);
        assert_eq!(
            Kind::Payload.grid(7),
            vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]
        );
        assert_eq!(
            (body_index(0.0, 7), body_index(1.0, 7), body_index(7.0, 7)),
            (6, 0, 6)
        );
    }

    #[test]
    fn every_drawn_effect_is_replayed_by_its_own_kind() {
        // Draw → the scenario effect the simulator makes; replay of the coefficients that
        // describe it → the same effect kind (the scenario's name is the library's).
        let model = crate::model::cheetah3::leg();
        let mut rng = <ChaCha8Rng as rand::SeedableRng>::seed_from_u64(7);
        for k in Kind::ALL {
            let (spec, mags) = k.draw(&model, &mut rng, 1000.0);
            assert!(!mags.is_empty(), "{k:?}");
            let Some(spec) = spec else {
                assert_eq!(k, Kind::RotorInertia);
                continue;
            };
            let name = serde_json::to_value(&spec).unwrap()["kind"].clone();
            assert_eq!(name, k.name(), "{k:?}");
            // Its TOML form (what `identify --out-effects` writes) reads back as the same
            // effect to the six decimals it keeps.
            let text = format!("kind = \"{}\"\n{}", k.name(), spec.toml_body());
            let back: EffectSpec = toml::from_str(&text).unwrap();
            let (a, b) = (
                serde_json::to_value(&spec).unwrap(),
                serde_json::to_value(&back).unwrap(),
            );
            for (key, va) in a.as_object().unwrap() {
                let vb = &b[key];
                let nums = |v: &serde_json::Value| -> Vec<f64> {
                    match v {
                        serde_json::Value::Array(x) => {
                            x.iter().map(|e| e.as_f64().unwrap()).collect()
                        }
                        serde_json::Value::Number(x) => vec![x.as_f64().unwrap()],
                        _ => vec![],
                    }
                };
                let (na, nb) = (nums(va), nums(vb));
                assert_eq!(na.len(), nb.len(), "{k:?}.{key}");
                for (x, y) in na.iter().zip(&nb) {
                    assert!(
                        (x - y).abs() <= 1e-6 * x.abs().max(1e-300),
                        "{k:?}.{key}: {x} vs {y}"
                    );
                }
            }
        }
    }
}
