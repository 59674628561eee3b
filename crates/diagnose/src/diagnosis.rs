//! What a diagnosis reports: the selected effects with their magnitudes, the gap per joint, the
//! verdict, and the whole [`Diagnosis`] (serialized as `report.json` and `--json`).

use super::anchor;
use super::breakdown::Breakdown;
use super::select;
use super::spectrum;
use physid_effect::library::Kind;
use physid_ident::ConstraintSet;
use serde::Serialize;

/// One estimated magnitude.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Magnitude {
    /// Joint name, or `"robot"` for one value for the whole robot.
    pub joint: String,
    /// Value in `unit`.
    pub value: f64,
    /// Standard error: block jackknife (cross-validation evidence) or posterior (description
    /// evidence).
    pub se: f64,
    /// Unit.
    pub unit: String,
    /// Fraction of the effect's column not explained by the rigid-body regressor (1: fully
    /// identifiable; near 0: absorbed by the inertial parameters, the value is meaningless).
    /// Absorbed effects found against the description are identified through it: 1, their
    /// precision is in `se`.
    pub identifiable: f64,
}

/// Smallest identifiable fraction of a magnitude worth reporting as a number (its column's part
/// outside the rigid-body regressor's span carries at least 3 % of its RMS).
pub const IDENTIFIABLE: f64 = 1e-3;

impl Magnitude {
    /// Whether the value means something: its identifiable fraction is at least
    /// [`IDENTIFIABLE`].
    pub fn is_identifiable(&self) -> bool {
        self.identifiable >= IDENTIFIABLE
    }
}

/// What an effect was found by.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Evidence {
    /// It lowers the cross-validated torque error ([`select`]).
    CrossValidation,
    /// Identification absorbs it, but the identified parameters depart from the description
    /// as it dictates ([`anchor`]).
    Description,
}

/// One selected effect with its magnitudes.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct EffectEstimate {
    /// The kind.
    pub kind: Kind,
    /// What it was found by.
    pub evidence: Evidence,
    /// Its grid value (Stribeck velocity in rad/s, cogging harmonic), 0 otherwise.
    pub param: f64,
    /// What the magnitude is.
    pub magnitude_name: String,
    /// Magnitudes per joint (or one for the robot).
    pub magnitudes: Vec<Magnitude>,
    /// Kinds the data cannot tell apart from this one.
    pub ambiguous_with: Vec<Kind>,
    /// What data would separate them.
    pub separate_by: Option<String>,
    /// An explanation of the ladder from the description is stated as weighed at its step;
    /// where the steps after it moved a magnitude by more than [`super::ladder::MOVED`]
    /// standard errors (the larger of the two fits'), its magnitudes with every explanation
    /// free: the later steps trade off with it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub after_later_steps: Option<Vec<Magnitude>>,
}

impl EffectEstimate {
    /// The kept kind, then those the data cannot tell apart from it.
    pub fn group(&self) -> impl Iterator<Item = Kind> + '_ {
        std::iter::once(self.kind).chain(self.ambiguous_with.iter().copied())
    }
}

/// One step of the gap from the description explained ([`super::explain`]): what it adds to
/// the description (whose inertial parameters stay pinned until the last step) and the
/// validation RMS with everything added so far.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct DescriptionStep {
    /// `+ <effect>`, `friction re-identified` or `inertial parameters re-identified`.
    pub step: String,
    /// The effect added (`None` for the friction and the inertial parameters).
    pub kind: Option<Kind>,
    /// Its grid value (0 without a grid).
    pub param: f64,
    /// Validation RMS per joint (N m).
    pub rms: Vec<f64>,
    /// Over all joints (N m).
    pub overall: f64,
}

/// Validation error of one joint along the selection.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct JointGap {
    /// Joint name.
    pub joint: String,
    /// The description's validation RMS as given, before any fit (N m): the sim-to-real gap.
    pub description: f64,
    /// Nominal model's validation RMS: the description's structure with its inertial
    /// parameters and friction re-identified on the training data (N m).
    pub nominal: f64,
    /// RMS after each selected effect, cumulatively (N m).
    pub after: Vec<f64>,
    /// Estimated noise floor (N m RMS).
    pub noise_floor: f64,
    /// Fraction of the gap `nominal² − floor²` closed by all selected effects.
    pub gap_closed: f64,
}

/// The verdict.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// No effect selected and the residual is at the noise floor.
    NoEffect,
    /// Effects selected and what remains is at the noise floor.
    Explained,
    /// Effects selected but a residual above the noise floor remains.
    PartiallyExplained,
    /// Nothing in the library explains a residual above the noise floor.
    Unexplained,
    /// The residual is at the noise floor, but identification absorbs an effect that the
    /// description reveals.
    Absorbed,
    /// Nothing was selected, and the data are too short to tell "unexplained" from "no
    /// effect" ([`super::Options::min_decisive_seconds`]).
    Undecided,
}

/// A whole diagnosis.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Diagnosis {
    /// Robot name.
    pub robot: String,
    /// Joint names.
    pub joints: Vec<String>,
    /// Training and validation samples.
    pub samples: [usize; 2],
    /// Constraint set.
    pub constraints: ConstraintSet,
    /// Whether the nominal model satisfies its constraints.
    pub nominal_constraints_hold: bool,
    /// Where: the nominal validation residual by regime.
    pub breakdown: Breakdown,
    /// Where in frequency: the nominal validation residual per joint.
    pub spectra: Vec<spectrum::Spectrum>,
    /// Spectra of the final residual (after the selected effects).
    pub spectra_after: Vec<spectrum::Spectrum>,
    /// Which: the selection.
    pub selection: select::Selection,
    /// Which, for absorbed effects: the description test (with a stated uncertainty).
    pub description_test: Option<anchor::Report>,
    /// Why the description test did not run although an uncertainty was stated (`None` when
    /// it ran or was not asked for).
    pub description_test_skipped: Option<String>,
    /// Joints whose backlash was not tested: without a rotor, their torque within its noise of
    /// zero on most samples of the training or validation data (a wheel in the air), so the
    /// log cannot tell their dead zone's side from that noise.
    #[serde(default)]
    pub backlash_untested: Vec<String>,
    /// The ladder from the description (when its uncertainty is stated): every explanation
    /// (effects, a payload or change on any body, friction) competing from the description as
    /// given, scored on the held-out data.
    pub ladder: Option<super::ladder::Ladder>,
    /// Each effect the ladder chose (a payload or body change included), its magnitudes
    /// estimated from the description (its inertial parameters within their uncertainty): what
    /// the effect is relative to the user's model. `effects` holds the cross-validated
    /// estimates, relative to the re-identified model, which may have absorbed part of it.
    /// Empty without a stated uncertainty.
    pub described_effects: Vec<EffectEstimate>,
    /// The selected effects and their magnitudes.
    pub effects: Vec<EffectEstimate>,
    /// How far: per joint.
    pub gap: Vec<JointGap>,
    /// Validation RMS over all joints of the description as given (N m): the sim-to-real gap
    /// before anything is re-identified.
    pub description_overall: f64,
    /// The description's gap explained step by step, largest first (the description pinned,
    /// then each selected effect or the friction freed; last, the inertial parameters
    /// re-identified).
    pub explained_from_description: Vec<DescriptionStep>,
    /// Validation RMS over all joints: nominal, then after each effect (N m).
    pub overall: Vec<f64>,
    /// Per selected effect: whether adding it lowered the validation RMS (held-out data, not
    /// used by the selection); an unconfirmed effect fits the training runs only.
    pub confirmed: Vec<bool>,
    /// Noise floor over all joints (N m RMS).
    pub noise_floor: f64,
    /// Fraction of the overall gap closed.
    pub gap_closed: f64,
    /// Whether a generic smooth function of each joint's speed and angle still predicts the
    /// final validation residual (an effect outside the library).
    pub structure_left: super::structure::StructureLeft,
    /// Validation RMS per joint and overall (N m) with the confirmed effects only (refitted),
    /// when some selected effect is not confirmed.
    pub confirmed_only: Option<(Vec<f64>, f64)>,
    /// The verdict.
    pub verdict: Verdict,
    /// The verdict in words.
    pub summary: String,
}

impl Diagnosis {
    /// The effects the "how far" steps add, in order (`gap[j].after[i]` and `overall[i + 1]`
    /// are after the `i`-th): the cross-validated ones and the description test's. The
    /// ladder's first explanation, appended to `effects` when neither named it, has no step
    /// there (its own rung is in `explained_from_description`).
    pub fn how_far_effects(&self) -> &[EffectEstimate] {
        let steps = self.overall.len().saturating_sub(1);
        &self.effects[..steps.min(self.effects.len())]
    }
}
