//! # physid
//!
//! Physically-consistent inertial parameter identification of robots, with ground truth.
//! The method is Wensing, Kim & Slotine, "Linear Matrix Inequalities for Physically-Consistent
//! Inertial Parameter Identification" (RA-L 2018).
//!
//! The library is built in floors, each a crate of the workspace that depends only on the
//! floors below its own (docs/architecture.md §6); this crate is the `api` floor and
//! re-exports every floor below as a module:
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
//!    limits, ellipsoids), the built-in Cheetah-3 leg;
//! 3. [`io`] (URDF, robot TOML, MJCF, CSV, MCAP, plot style) and [`dynamics`] (RNEA, CRBA,
//!    forward dynamics, the regressor `Y θ` of the paper's eq. 9, energy, kinematics);
//! 4. [`sim`] (scenarios, the closed-loop ground-truth simulator, rapier) and [`ident`] (the
//!    four constraint sets of the paper's eq. 10, solved with Clarabel from samples, never
//!    from files);
//! 5. [`diagnose`]: the sim-to-real diagnosis as named steps (breakdown, selection, the
//!    description test, magnitudes, gap, verdict);
//! 6. [`experiment`]: the sample-size experiment of the paper's last figure, motions compared,
//!    sweeps, the CI comparison of results, their tables and plots;
//! 7. [`bench`]: the diagnosis's benchmarks (simulated blind, semi-real, generalization);
//! 8. [`api`]: the library's entry point per command, typed options in, typed reports out;
//! 9. the `physid` binary (its own crate, `cli/`): one clap `Args` per command, errors printed
//!    once.
#![warn(missing_docs)]

pub mod api;

// The ground floors are their own crate (crates/core): Cargo keeps them from reaching up.
pub use physid_core::{conic, dynamics, linalg, model, options, signal, spatial, trajectory};
// So is the io floor (crates/io: file formats and the data pipeline).
pub use physid_io::{self as io, prepare};
// And the effect library (crates/effect), identification, simulation, the diagnosis and the
// experiments and the diagnosis's benchmarks (crates/ident, sim, diagnose, experiment, bench).
pub use physid_bench as bench;
pub use physid_diagnose as diagnose;
pub use physid_effect as effect;
pub use physid_experiment as experiment;
pub use physid_ident as ident;
pub use physid_sim as sim;
