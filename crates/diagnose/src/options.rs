//! The diagnosis's options (each checked by [`Options::validate`]) and its errors.

use super::select;
use physid_effect::library::Kind;
use physid_ident::{ConstraintSet, IdentError};

/// Diagnosis options.
#[derive(Clone, Debug)]
pub struct Options {
    /// Constraint set of the nominal model and of every fit with effects.
    pub constraints: ConstraintSet,
    /// The forward selection's settings.
    pub selection: select::Settings,
    /// The kinds offered.
    pub kinds: Vec<Kind>,
    /// Joint-samples slower than this (rad/s) are left out of every fit and error (the
    /// model's `sign(q̇)` Coulomb friction does not describe friction near zero speed).
    pub min_speed: f64,
    /// Low-pass cutoff (Hz) of the data's processing, for the compliance columns.
    pub processing_cutoff: f64,
    /// The ladder from the description's settings.
    pub ladder: LadderSettings,
    /// The residual counts as unexplained when its validation mean square exceeds the noise
    /// floor's by this factor.
    pub unexplained_ratio: f64,
    /// The final residual has structure outside the library when a generic smooth function
    /// of each joint's speed and angle, fitted on training, lowers its validation mean square
    /// significantly and by at least this fraction ([`super::structure::StructureLeft`]).
    pub structure_threshold: f64,
    /// Relative uncertainty `ε` of the description's inertial parameters: when given, effects
    /// that identification absorbs are tested against the description ([`super::anchor`]).
    pub description_uncertainty: Option<f64>,
    /// The description's information matrix (precision of its parameters, `θ` layout, in
    /// 1/(parameter unit)²), when the description is itself identified ([`super::anchor::information`]):
    /// the ladder's prior becomes this plus the `ε` prior, so parameters the description's own
    /// data did not determine are free to move and those it did are held.
    pub description_information: Option<nalgebra::DMatrix<f64>>,
    /// Training data shorter than this (s) cannot support "unexplained" or "no effect": the
    /// cross-validation blocks and the noise floor rest on too few repetitions of the motion
    /// (the verdicts were measured on 20 s and more). Such a verdict becomes
    /// [`super::diagnosis::Verdict::Undecided`].
    pub min_decisive_seconds: f64,
    /// Search effects that act on one body (a payload) over every body; otherwise only the
    /// last body is offered (inner bodies' parameters are often not separable from their
    /// neighbours', and the search then claims more falsely: docs/diagnose.md).
    pub every_body: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            constraints: ConstraintSet::Consistent,
            selection: select::Settings::default(),
            kinds: Kind::ALL.to_vec(),
            min_speed: 0.05,
            processing_cutoff: 20.0,
            ladder: Default::default(),
            unexplained_ratio: 1.45,
            structure_threshold: 0.002,
            description_uncertainty: None,
            description_information: None,
            min_decisive_seconds: 10.0,
            every_body: false,
        }
    }
}

impl Options {
    /// Checks every value against its range (the CLI relies on this, and so can any caller).
    pub fn validate(&self) -> Result<(), DiagnoseError> {
        let invalid = |option, expected, value| DiagnoseError::InvalidOption {
            option,
            expected,
            value,
        };
        if let Some(e) = self.description_uncertainty {
            if !(e.is_finite() && e > 0.0) {
                return Err(invalid(
                    "description_uncertainty",
                    "a positive fraction (0.1 = 10 %)",
                    e,
                ));
            }
        }
        let cutoff = self.processing_cutoff;
        if !(cutoff.is_finite() && cutoff > 0.0) {
            return Err(invalid(
                "processing_cutoff",
                "a positive frequency in Hz",
                cutoff,
            ));
        }
        if !(self.min_speed.is_finite() && self.min_speed >= 0.0) {
            return Err(invalid(
                "min_speed",
                "a finite speed >= 0 (rad/s)",
                self.min_speed,
            ));
        }
        if !(self.min_decisive_seconds.is_finite() && self.min_decisive_seconds >= 0.0) {
            let s = self.min_decisive_seconds;
            return Err(invalid(
                "min_decisive_seconds",
                "a finite duration >= 0 (s)",
                s,
            ));
        }
        let st = self.structure_threshold;
        if !(st.is_finite() && st > 0.0 && st < 1.0) {
            return Err(invalid("structure_threshold", "a fraction in (0, 1)", st));
        }
        if !(self.unexplained_ratio.is_finite() && self.unexplained_ratio >= 1.0) {
            let ratio = self.unexplained_ratio;
            return Err(invalid("unexplained_ratio", "a finite number >= 1", ratio));
        }
        if self.kinds.is_empty() {
            return Err(invalid("kinds", "at least one effect kind", 0.0));
        }
        Ok(())
    }
}

/// A diagnosis failed.
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    /// Identification failed.
    #[error("identification failed: {0}")]
    Ident(#[from] IdentError),
    /// A data set has another number of joints than the robot.
    #[error("{which} data have {data} joints, the robot {robot}")]
    JointCount {
        /// `training` or `validation`.
        which: &'static str,
        /// Joints in the data.
        data: usize,
        /// Joints of the robot.
        robot: usize,
    },
    /// A data set has no accelerations.
    #[error("{which} data carry no accelerations (ddq columns)")]
    NoAcceleration {
        /// `training` or `validation`.
        which: &'static str,
    },
    /// A data set is too short for the diagnosis.
    #[error("{which} data have {samples} samples; the diagnosis needs at least {min}")]
    TooShort {
        /// `training` or `validation`.
        which: &'static str,
        /// Samples given.
        samples: usize,
        /// Samples needed.
        min: usize,
    },
    /// A data set whose time stamps span no time (its sample period is not positive).
    #[error("{which} data span {span} s over {samples} samples: the diagnosis needs time stamps that advance (a positive sample period)")]
    NoSamplePeriod {
        /// `training` or `validation`.
        which: &'static str,
        /// Last time stamp minus the first (s).
        span: f64,
        /// Samples given.
        samples: usize,
    },
    /// No joint moves fast enough to estimate the noise floor.
    #[error(
        "no joint moves faster than {min_speed} rad/s often enough to estimate the noise floor"
    )]
    NoNoiseFloor {
        /// The speed threshold (rad/s).
        min_speed: f64,
    },
    /// No training run was given.
    #[error("no training data given")]
    NoData,
    /// A model built from a calibration is not valid.
    #[error("the calibrated description is not a valid model: {0}")]
    Model(#[from] physid_core::model::ModelError),
    /// A baseline without a stated description uncertainty.
    #[error("a baseline (--baseline-data) needs --description-uncertainty: the change is found against the description calibrated on the baseline, within that uncertainty")]
    BaselineWithoutUncertainty,
    /// The held-out fraction is outside (0, 1).
    #[error("the held-out fraction {0} must lie strictly between 0 and 1")]
    Holdout(f64),
    /// An option value out of its range.
    #[error("{option} must be {expected}, got {value}")]
    InvalidOption {
        /// The option (its field in [`Options`]).
        option: &'static str,
        /// Its valid range.
        expected: &'static str,
        /// The value given.
        value: f64,
    },
}

physid_core::options::option_error!(DiagnoseError);

/// The ladder's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct LadderSettings {
    /// Held-out blocks of the t statistic.
    pub blocks: usize,
    /// Smallest block t statistic of a step's held-out improvement.
    pub min_t: f64,
    /// Smallest relative reduction of the held-out mean square a step must bring.
    pub min_reduction: f64,
    /// Candidates within this fraction of the winner's reduction (and leaving at most twice the
    /// held-out error it leaves) are ambiguous with it.
    pub tie: f64,
    /// At most this many steps.
    pub max_steps: usize,
}

impl Default for LadderSettings {
    fn default() -> Self {
        Self {
            blocks: 10,
            min_t: 3.0,
            min_reduction: 0.02,
            tie: 0.1,
            max_steps: 6,
        }
    }
}
