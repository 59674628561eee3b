//! The effect library: every effect the rigid-body model leaves out, one file per kind
//! (`effect/<name>.rs`). A kind's file holds all physid knows about it: its row of
//! [`KIND_TABLE`] (name, regressor columns, magnitudes, search grid, replay as a scenario
//! effect, the blind benchmark's draw and, for the semi-real benchmark, its scaling), and its
//! simulator form (the scenario's `[[effects]]` struct, its checks and TOML, and its physics
//! behind [`Physics`]: an acting torque, the logged torque or angle, a delay, the robot itself).
//! A new kind is one file here plus its entry in the `effect_kinds!` list below (its `Kind`
//! variant, table row and, if the simulator makes it, [`EffectSpec`] variant, all from it).
//! The per-data state the columns read is [`context`], the columns over a data set
//! [`library`]. Both the simulator (`sim`) and the diagnosis (`diagnose`) stand on this floor.
//! Equations and units in `docs/diagnose.md`. A floor of physid (docs/architecture.md §6) of
//! its own crate, standing on `physid-core` only; the `physid` crate re-exports it as
//! `physid::effect`.
//!
//! Sign convention: a coefficient is the physical magnitude of the injected effect (each
//! kind's [`Physics`]), e.g. the columns of an acting friction are `−∂τ_effect/∂c` because the
//! motor torque must overcome it.
#![warn(missing_docs)]

/// The kinds, one entry each in report order (the order of [`Kind`] and [`KIND_TABLE`]): the
/// kind's file (`mod`), its [`Kind`] variant and table row (`kind`, when the diagnosis offers
/// it) and its [`EffectSpec`] variant with the struct of that name re-exported (`effect`, when
/// the simulator makes it). The table is checked at compile time to list each file's own row.
macro_rules! effect_kinds {
    ($(
        $module:ident {
            $( kind $(#[$kind_doc:meta])* $kind:ident, )?
            $( effect $(#[$effect_doc:meta])* $effect:ident, )?
        }
    )*) => {
        $( mod $module; )*
        $( $( pub use $module::$effect; )? )*

        /// An effect the rigid-body model leaves out, injected into the simulation (equations
        /// and units in `docs/scenario-format.md` and each kind's file). Per-joint lists have
        /// one entry per joint. Unknown kinds and keys are rejected.
        #[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
        #[serde(tag = "kind", rename_all = "snake_case")]
        pub enum EffectSpec {
            $( $( $(#[$effect_doc])* $effect($effect), )? )*
        }

        impl EffectSpec {
            /// The effect's physics and scenario form.
            pub fn physics(&self) -> &dyn Physics {
                match self {
                    $( $( EffectSpec::$effect(e) => e, )? )*
                }
            }
        }

        /// An effect kind the diagnosis can offer.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        #[derive(Serialize, serde::Deserialize, schemars::JsonSchema)]
        #[serde(rename_all = "snake_case")]
        pub enum Kind {
            $( $( $(#[$kind_doc])* $kind, )? )*
        }

        /// One row per kind, in report order ([`Kind::ALL`], whose length is this table's).
        pub(crate) const KIND_TABLE: &[KindSpec] = &[
            $( $( own_row($module::SPEC, Kind::$kind), )? )*
        ];
    };
}

/// `spec`, checked (at compile time, in [`KIND_TABLE`]) to be the row of `kind`.
const fn own_row(spec: KindSpec, kind: Kind) -> KindSpec {
    assert!(
        spec.kind as u8 == kind as u8,
        "a kind file's SPEC names another kind"
    );
    spec
}

effect_kinds! {
    torque_offset {
        kind
            /// Logged `τ += o` (N m per joint).
            TorqueOffset,
        effect
            /// Logged torque `+= offset` (N m): a sensor effect, it does not act.
            TorqueOffset,
    }
    torque_gain {
        kind
            /// Logged `τ ×= 1 + δ` (per joint; a common δ is a scale of all inertial parameters).
            TorqueGain,
        effect
            /// Logged torque `×= gain` (a torque-constant error): a sensor effect.
            TorqueGain,
    }
    time_delay {
        kind
            /// Logged torque lags the kinematics by `d` (s, one for all joints).
            TimeDelay,
        effect
            /// The logged torque lags the kinematics by whole control periods: a sensor effect.
            TimeDelay,
    }
    spring {
        kind
            /// `τ_acting = −k (q − q₀)` (N m/rad, rad per joint).
            Spring,
        effect
            /// Acting `τ = −k (q − q_0)` (N m/rad, rad): a cable or hose.
            Spring,
    }
    stribeck {
        kind
            /// `τ_acting = −F_s exp(−(q̇/v)²) sign(q̇)` (N m per joint; `v` searched).
            Stribeck,
        effect
            /// Stribeck friction: extra resistance `F_s exp(−(q̇/v_st)²) tanh(q̇/v_s)` at low speed.
            Stribeck,
    }
    asymmetric_coulomb {
        kind
            /// `τ_acting = −δ max(0, sign(q̇))` (N m per joint).
            AsymmetricCoulomb,
        effect
            /// Direction-dependent Coulomb friction: extra `δ max(0, tanh(q̇/v_s))`.
            AsymmetricCoulomb,
    }
    load_dependent_friction {
        kind
            /// `τ_acting = −μ |τ| sign(q̇)` (per joint; `|τ|` from the nominal prediction).
            LoadDependentFriction,
        effect
            /// Load-dependent friction: extra `μ |τ_mot| tanh(q̇/v_s)` (gear mesh losses).
            LoadDependentFriction,
    }
    cogging {
        kind
            /// `τ_acting = −A sin(h N q + φ)` (N m per joint; harmonic `h` searched).
            Cogging,
        effect
            /// Cogging / torque ripple at a harmonic of the rotor angle: acting `−A sin(h N q + φ)`.
            Cogging,
    }
    rotor_inertia {
        kind
            /// Reflected rotor inertia `I_a q̈` left out of the model (kg m² per joint).
            RotorInertia,
    }
    tilt {
        kind
            /// Gravity misaligned by a small base tilt (m/s² of the gravity vector's perpendicular
            /// components; reported as an angle).
            Tilt,
        effect
            /// The base is tilted: gravity rotated by roll and pitch.
            Tilt,
    }
    compliance {
        kind
            /// Compliant transmission seen by a motor-side encoder: `q_logged = q + κ τ`
            /// (κ = 1/k, rad/(N m) per joint).
            Compliance,
        effect
            /// A compliant transmission read on the motor side: the encoder reads `q + τ_mot / k`.
            Compliance,
    }
    backlash {
        kind
            /// Backlash read by a motor-side encoder: `q_logged = q + s`, `s ∈ [−b/2, b/2]` the motor's
            /// offset in a dead zone of width `b` (rad per joint) that it crosses driven by its own
            /// torque (`effect::DeadZone`).
            Backlash,
        effect
            /// Backlash read on the motor side: the encoder reads `q + s`, `|s| ≤ b/2`.
            Backlash,
    }
    quadratic_damping {
        effect
            /// Quadratic (fluid) damping `−c q̇ |q̇|`: not in the diagnosis's library.
            QuadraticDamping,
    }
    payload {
        kind
            /// An unmodelled payload on one body (searched over the bodies): ten inertial parameters
            /// `π_p` added to it (that body's own regressor columns; reported as its mass, kg), so also
            /// any change of one body's parameters. Its columns lie in the model's span, so only the
            /// test against the description can find it.
            Payload,
        effect
            /// An unmodelled payload: a solid sphere on one body.
            Payload,
    }
}

pub mod context;
mod dead_zone;
pub mod library;
pub mod physics;
mod shifted;

pub use dead_zone::DeadZone;
pub use payload::{
    payload_on_any_body, payload_on_any_body_within, MAX_PAYLOAD_MASS, MAX_PAYLOAD_OFFSET,
    PAYLOAD_MASS,
};
pub use physics::{toml_list, Physics, ScenarioError, State};
pub use time_delay::MAX_DELAY_SAMPLES;
pub use torque_gain::{relative_to_median, MAX_GAIN_ERROR};

use context::{backlash_widths, Context, Sample, Scratch};
use nalgebra::DMatrix;
use physid_core::model::Model;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

impl EffectSpec {
    /// The effect's keys as the lines of a scenario's `[[effects]]` table, without its
    /// `kind = …` line (numbers as [`toml_list`] writes them).
    pub fn toml_body(&self) -> String {
        self.physics().toml_body()
    }

    /// Checks effect `i` of a scenario against the robot's `n` joints (its keys are named
    /// `effects[i].…`).
    pub fn validate(&self, i: usize, n: usize) -> Result<(), ScenarioError> {
        self.physics()
            .validate(n, &|f: &str| format!("effects[{i}].{f}"))
    }
}

/// How many columns a kind adds for `n` joints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum ColumnCount {
    /// A fixed number, whatever the joint count.
    Fixed(usize),
    /// `k` per joint.
    PerJoint(usize),
}

/// The search grid of a kind's one-dimensional parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Grid {
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
pub(crate) enum Blind {
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
/// The semi-real benchmark's scaling of a drawn effect about "no effect": `(spec, s, rate,
/// magnitudes)` → the effect `s` times as strong and its magnitudes (`None`: not this kind).
type Scale = fn(&EffectSpec, f64, f64, &[f64]) -> Option<(EffectSpec, Vec<f64>)>;

/// A yes-or-no property of a kind; a row of [`KIND_TABLE`] lists those that hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Property {
    /// The coefficients have a physical sign (≥ 0), kept in every fit.
    NonNegative,
    /// Per-joint magnitude `i` needs columns `i` and `n + i` (an amplitude of a sine and a
    /// cosine); without it, column `i` (a spring's rest term is not its stiffness).
    MagnitudePairs,
    /// The columns lie in the span of the model's own (only the description test sees it).
    InModelSpan,
    /// The columns are linearized about the nominal model `θ̂₀`.
    Linearized,
    /// Equal coefficients on every joint give a combination of the model's own columns (a
    /// torque gain common to every joint is a scale of all of `θ`): fitted beside `θ`, the
    /// coefficients' mean is a gauge the data do not determine, pinned at zero.
    CommonModeInSpan,
    /// The ladder from the description offers it even when cross-validation did not select
    /// it: the re-identified model absorbs its signature (friction and inertial parameters fit
    /// a delay's `−d τ̇`), while no body's parameters mimic it from the description.
    OfferedFromDescription,
    /// A model with rotors carries this effect among its own parameters (the rotors' inertia).
    RotorParameter,
    /// The columns approximate the effect by more than a linearization (reflected inertia
    /// without the rotor's gyroscopic terms).
    Approximate,
    /// A motor-side effect at the rotor's angle: offered only on joints whose rotor (and gear
    /// ratio) the description knows (cogging: a link-angle harmonic is not cogging).
    NeedsRotor,
    /// Per-joint columns that touch only their own joint's row: column `c·n + j` is zero in
    /// every row but joint `j`'s (friction-like terms, a joint's own gain, offset, spring,
    /// cogging, reflected inertia; not compliance or backlash, whose shifted encoder moves
    /// every joint's torque).
    RowLocal,
}

/// Everything physid knows about one kind: one row of [`KIND_TABLE`].
pub(crate) struct KindSpec {
    pub kind: Kind,
    /// snake_case name, as in scenario files.
    pub name: &'static str,
    pub columns: ColumnCount,
    /// The magnitude's name and unit.
    pub magnitude: (&'static str, &'static str),
    /// What holds of its columns and of its place in the diagnosis (none by default).
    pub properties: &'static [Property],
    pub grid: Grid,
    pub fill: Fill,
    pub magnitudes: Magnitudes,
    /// The magnitude's name, unit and rule from the ladder from the description, whose
    /// columns are built about a model that does not carry the effect, where they differ from
    /// `magnitude` and `magnitudes` (`None`: the same).
    pub anchored: Option<Anchored>,
    pub replay: Replay,
    /// The description a user would give when this effect is present: `None` if unchanged
    /// (rotor inertia left out: its rotors frozen into their bodies).
    pub description: Option<fn(&Model) -> Model>,
    pub blind: Blind,
    pub draw: Draw,
    /// How the semi-real benchmark scales it to be visible on a real log (`None`: not
    /// injected there).
    pub scale: Option<Scale>,
}

/// A kind's magnitude read against the description ([`KindSpec::anchored`]).
pub(crate) struct Anchored {
    /// The magnitude's name and unit.
    pub magnitude: (&'static str, &'static str),
    /// Its rule.
    pub magnitudes: Magnitudes,
}

/// `v` times `s`, element by element.
fn times(v: &[f64], s: f64) -> Vec<f64> {
    v.iter().map(|x| x * s).collect()
}

const fn row(kind: Kind, name: &'static str, columns: ColumnCount, fill: Fill) -> KindSpec {
    KindSpec {
        kind,
        name,
        columns,
        magnitude: ("", ""),
        properties: &[],
        grid: Grid::None,
        fill,
        magnitudes: same,
        anchored: None,
        replay: |_, _, _, _| None,
        description: None,
        blind: Blind::No,
        draw: |_, _, _| (None, vec![]),
        scale: None,
    }
}

impl KindSpec {
    /// Whether `property` holds of the kind.
    fn has(&self, property: Property) -> bool {
        self.properties.contains(&property)
    }
}

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
    pub(crate) fn spec(&self) -> &'static KindSpec {
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

    /// The columns (from the kind's first, ascending) that can be nonzero in joint `j`'s row
    /// of `n`: the joint's own for a [`Property::RowLocal`] kind, every column otherwise.
    pub fn columns_of_row(&self, n: usize, j: usize) -> Vec<usize> {
        match self.spec().columns {
            ColumnCount::PerJoint(k) if self.spec().has(Property::RowLocal) => {
                (0..k).map(|c| c * n + j).collect()
            }
            _ => (0..self.columns(n)).collect(),
        }
    }

    /// Whether the coefficients have a physical sign (≥ 0), kept in every fit: Stribeck's
    /// static excess, load-dependent friction, reflected rotor inertia, compliance, backlash. A
    /// fit that needs the opposite sign is not this effect.
    pub fn non_negative(&self) -> bool {
        self.spec().has(Property::NonNegative)
    }

    /// The magnitude's name and unit, per joint (or for the whole robot).
    pub fn magnitude(&self) -> (&'static str, &'static str) {
        self.spec().magnitude
    }

    /// The columns (offsets within the kind's own) magnitude `i` of `n` joints depends on.
    pub fn magnitude_columns(&self, i: usize, n: usize) -> Vec<usize> {
        if self.spec().has(Property::MagnitudePairs) {
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

    /// The magnitude's name and unit as the ladder from the description reads it (its
    /// columns built about a model that does not carry the effect).
    pub fn anchored_magnitude(&self) -> (&'static str, &'static str) {
        self.spec()
            .anchored
            .as_ref()
            .map_or(self.spec().magnitude, |a| a.magnitude)
    }

    /// The magnitudes of coefficients `c` as the ladder from the description reads them
    /// ([`Kind::magnitudes`] unless the kind's row says otherwise).
    pub fn anchored_magnitudes(&self, c: &[f64], n: usize, gravity: f64) -> Vec<f64> {
        let rule = self
            .spec()
            .anchored
            .as_ref()
            .map_or(self.spec().magnitudes, |a| a.magnitudes);
        rule(c, n, gravity)
    }

    /// Whether equal coefficients on every joint lie in the span of the model's columns, so
    /// that their mean is pinned at zero wherever the kind is fitted beside `θ`
    /// ([`KindSpec::common_mode_in_span`]).
    pub fn common_mode_in_span(&self) -> bool {
        self.spec().has(Property::CommonModeInSpan)
    }

    /// Whether the columns lie in the span of the model's own (its parameters express the
    /// effect exactly): cross-validation cannot see it and does not offer it.
    pub fn in_model_span(&self) -> bool {
        self.spec().has(Property::InModelSpan)
    }

    /// Whether the columns are linearized about the nominal model (they need `θ̂₀`).
    pub fn linearized(&self) -> bool {
        self.spec().has(Property::Linearized)
    }

    /// Whether the ladder from the description offers it whatever cross-validation selected
    /// (see `ladder::candidates`).
    pub fn offered_from_description(&self) -> bool {
        self.spec().has(Property::OfferedFromDescription)
    }

    /// Whether the columns only approximate the effect (linearized about the nominal model, or
    /// reflected rotor inertia without gyroscopic terms): what they miss biases the parameters,
    /// so the test against the description does not run beside such an effect.
    pub fn approximate(&self) -> bool {
        self.spec().has(Property::Linearized) || self.spec().has(Property::Approximate)
    }

    /// Whether a model with rotors carries this effect among its own parameters (reflected
    /// rotor inertia): testing it against the description would test the description.
    pub fn is_rotor_parameter(&self) -> bool {
        self.spec().has(Property::RotorParameter)
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
        self.spec().has(Property::NeedsRotor)
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

    /// Whether the kind refines the model's own viscous and Coulomb friction (its shape at low
    /// speed, by direction, by load) rather than adding another effect: a change
    /// of the friction is first the friction re-identified.
    pub fn refines_friction(&self) -> bool {
        use Kind::*;
        matches!(self, Stribeck | AsymmetricCoulomb | LoadDependentFriction)
    }

    /// The kinds the semi-real benchmark injects on real logs (`bench::semireal`): those
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

    /// `spec` (an effect of this kind) `s` times as strong about "no effect", with its
    /// magnitudes scaled alike, for the semi-real benchmark (sample rate `rate`, Hz); `None`
    /// if the kind is not injected there or `spec` is not of this kind.
    pub fn scaled(
        &self,
        spec: &EffectSpec,
        s: f64,
        rate: f64,
        magnitudes: &[f64],
    ) -> Option<(EffectSpec, Vec<f64>)> {
        (self.spec().scale?)(spec, s, rate, magnitudes)
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
        let model = physid_core::model::cheetah3::leg();
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

    #[test]
    fn a_scenario_effect_with_an_unknown_key_or_kind_is_rejected_by_name() {
        // Each kind's struct rejects keys it does not have (the enum only reads the tag).
        let err = |text: &str| toml::from_str::<EffectSpec>(text).unwrap_err().to_string();
        let e = err("kind = \"backlash\"\nwidth = [0.01]\nbogus = 1\n");
        assert!(
            e.contains("unknown field `bogus`") && e.contains("width"),
            "{e}"
        );
        let e = err(
            "kind = \"payload\"\nmass = 1.0\ncom = [0, 0, 0]\nradius = 0.1\nbody = 1\nspin = 2\n",
        );
        assert!(e.contains("unknown field `spin`"), "{e}");
        let e = err("kind = \"friction_drift\"\ncoefficient = [1.0]\n");
        assert!(e.contains("friction_drift"), "{e}");
        // And a value out of range names its key with the effect's index.
        let spec: EffectSpec = toml::from_str("kind = \"time_delay\"\nsamples = 0\n").unwrap();
        let e = spec.validate(3, 2).unwrap_err();
        assert_eq!(e.key, "effects[3].samples");
    }

    #[test]
    fn the_semi_real_kinds_are_those_with_a_scaling() {
        // `Kind::semi_real_singles` keeps the benchmark's order by hand; a kind listed there
        // without its row's `scale` would be injected unscaled, silently.
        let mut scaled: Vec<Kind> = KIND_TABLE
            .iter()
            .filter(|s| s.scale.is_some())
            .map(|s| s.kind)
            .collect();
        let mut listed = Kind::semi_real_singles();
        listed.sort();
        scaled.sort();
        assert_eq!(listed, scaled);
    }
}
