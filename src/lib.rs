//! # physid
//!
//! Physically-consistent inertial parameter identification of robots, with ground truth.
//! The method is Wensing, Kim & Slotine, "Linear Matrix Inequalities for Physically-Consistent
//! Inertial Parameter Identification" (RA-L 2018).
//!
//! Data flows `io → model → spatial/dynamics → sim | ident → experiment → diagnose → io`:
//! - [`spatial`]: Featherstone's spatial algebra and the inertial parameters `π` with their
//!   consistency conditions;
//! - [`model`]: the immutable robot model (tree, joints, rotors, friction, ellipsoids), the
//!   built-in Cheetah-3 leg;
//! - [`dynamics`]: RNEA, CRBA, forward dynamics, the regressor, energy and kinematics;
//! - [`sim`]: scenario files, the closed-loop excitation simulator, signal processing, rapier;
//! - [`ident`]: identification under the paper's four constraint sets with Clarabel;
//! - [`experiment`]: the validation-error-versus-sample-size experiment, in parallel;
//! - [`diagnose`]: where the residual of a model lies (sim-to-real gap, in progress);
//! - [`io`]: robot descriptions (URDF, TOML) in, MJCF/URDF out, MCAP and CSV logs.
#![warn(missing_docs)]

pub mod diagnose;
pub mod dynamics;
pub mod experiment;
pub mod ident;
pub mod io;
pub mod linalg;
pub mod model;
pub mod signal;
pub mod sim;
pub mod spatial;
pub mod trajectory;
