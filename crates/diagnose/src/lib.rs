//! Sim-to-real gap diagnosis: where the residual of a model lies, which unmodelled effect causes
//! it, and how far it shrinks once modelled.
//!
//! - **Where** ([`mod@breakdown`], [`spectrum`]): the validation residual `τ − Y θ̂₀` of the nominal
//!   constrained model per joint, per motion regime (near-zero velocity and reversals, speed,
//!   acceleration and torque levels, configuration) and over frequency (spectrum, coherence with
//!   the motion).
//! - **Which** ([`library`], [`select`]): each effect of the library offered as extra regressor
//!   columns, scored by the cross-validated reduction of the error, forward selection with a
//!   stopping rule; magnitudes with block-jackknife standard errors; effects the data cannot tell
//!   apart reported together.
//! - **Absorbed** ([`anchor`]): effects identification absorbs, tested against the description.
//! - **How far** (`gap`): per-joint validation RMS before and after each added effect, the
//!   fraction of the gap to the noise floor ([`noise`]) closed, whether each effect is confirmed
//!   on the held-out data, and the verdict (`verdict`).
//!
//! [`diagnose`] runs the steps in that order on a training and a validation trajectory, over a
//! shared `Stage` (the data, the nominal fit and the effect columns); [`diagnose_runs`] joins
//! runs first. The blind benchmark that scores it is `bench::blind`.
//!
//! A floor of physid (docs/architecture.md §6) of its own crate, `physid-diagnose`; the `physid`
//! crate re-exports it as `physid::diagnose`.
#![warn(missing_docs)]

pub mod anchor;
pub mod baseline;
pub mod breakdown;
pub mod calibrate;
mod described;
mod diagnosis;
mod explain;
pub mod floating;
mod gap;
pub mod ladder;
pub mod magnitude;
pub mod noise;
mod options;
mod pipeline;
pub mod report;
mod residual;
mod rows;
pub mod select;
pub mod spectrum;
pub(crate) mod stage;
mod stats;
mod structure;
mod verdict;

pub use breakdown::{breakdown, Breakdown, Regime};
pub use diagnosis::{
    DescriptionStep, Diagnosis, EffectEstimate, Evidence, JointGap, Magnitude, Verdict,
    IDENTIFIABLE,
};
pub use magnitude::magnitudes_of;
pub use options::{DiagnoseError, Options};
pub use physid_effect::separate_by;
/// The effect library the diagnosis reads (its floor is `physid_effect`).
pub use physid_effect::{context, library};
pub use physid_ident::analysis::residuals;
pub use pipeline::{diagnose, diagnose_runs};
pub use residual::{finite_mean_square, mask_slow, residual_rms};
pub use stage::{fit_nominal, MIN_SAMPLES};
pub use structure::StructureLeft;
