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
//!    report every `Options::validate` shares).
//!
//! The `physid` crate re-exports each module under its own name (`physid::spatial`, …).
#![warn(missing_docs)]

pub mod conic;
pub mod linalg;
pub mod options;
pub mod signal;
pub mod spatial;
pub mod trajectory;

/// The OpenBLAS library file the build linked (build.rs), for provenance records.
pub const OPENBLAS_LIBRARY: &str = env!("PHYSID_OPENBLAS");
