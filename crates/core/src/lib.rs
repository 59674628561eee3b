//! # physid-core
//!
//! The ground floors of physid (docs/architecture.md §6), a crate of their own so that Cargo
//! keeps them from reaching up:
//!
//! 0. [`conic`]: the one builder of conic programs for Clarabel (PSD, second-order and
//!    exponential cones, the log-det device), used by identification and the bounding
//!    ellipsoids;
//! 1. [`spatial`] (Featherstone's spatial algebra, the inertial parameters `π` with `I(π)`,
//!    `J(π)` and the ellipsoid conditions), [`signal`] (filters, differentiation), [`linalg`]
//!    (scaling, least squares, minimum-norm solves), [`trajectory`] (joint time series,
//!    recordings, sample rate, hold-out split, concatenation), [`options`] (the invalid-option
//!    report every `Options::validate` shares);
//! 2. [`model`]: the immutable robot (tree, joints, rotors with their armature, friction,
//!    limits, ellipsoids), the built-in Cheetah-3 leg, random trees;
//! 3. [`dynamics`]: RNEA, CRBA, forward dynamics, generalized gravity, the regressor `Y θ` of
//!    the paper's eq. 9, energy, kinematics, one algorithm per file.
//!
//! The `physid` crate re-exports each module under its own name (`physid::spatial`, …).
#![warn(missing_docs)]

pub mod conic;
pub mod dynamics;
pub mod linalg;
pub mod model;
pub mod options;
pub mod signal;
pub mod spatial;
pub mod trajectory;

/// The OpenBLAS library file the build linked (build.rs), for provenance records.
pub const OPENBLAS_LIBRARY: &str = env!("PHYSID_OPENBLAS");
