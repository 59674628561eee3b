//! Spatial (6D) vector algebra, in the notation of Featherstone's *Rigid Body Dynamics
//! Algorithms* (RBDA, 2008), chapter 2.
//!
//! # Conventions (one place, used everywhere in physid)
//! - Spatial vectors are **angular first**: a motion vector is `[ω; v]` (rad/s; m/s, the
//!   velocity of the body-fixed point at the frame origin), a force vector is `[n; f]` (N m about
//!   the frame origin; N).
//! - A Plücker transform `B_X_A` maps motion vectors from A coordinates to B coordinates. It is
//!   stored as the rotation `E` (B coordinates of a vector given in A coordinates) and the
//!   position `r` of B's origin relative to A's origin, in A coordinates (RBDA eq. 2.24):
//!   `X = [E 0; -E r× E]`. Forces use `X* = X^{-T}`.
//! - Inertial parameters of a body are `π = [m, hx, hy, hz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz]`
//!   (the paper's order; `h = m c`, inertia about the frame origin): see [`InertialParams`].

pub mod bounding;
mod ellipsoid;
mod inertia;
mod motion;
mod transform;

pub use ellipsoid::Ellipsoid;
pub use inertia::{ConsistencyReport, InertialParams, ParamError, RigidInertia, PARAM_NAMES};
pub use motion::{Force, Motion};
pub use transform::{rot_axis_angle, rpy_to_matrix, Transform};

use nalgebra::{Matrix3, Vector3};

/// The cross-product matrix `S(x)`, with `S(x) y = x × y`.
#[inline]
pub fn skew(x: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -x.z, x.y, x.z, 0.0, -x.x, -x.y, x.x, 0.0)
}

/// Clarabel's PSD cones call OpenBLAS, which starts as many threads as cores by default and
/// spins them on every small product. One thread keeps results independent of the machine's
/// thread count, and the parallelism belongs to the experiment level (rayon).
pub(crate) fn single_threaded_blas() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    extern "C" {
        fn openblas_set_num_threads(n: std::ffi::c_int);
    }
    // SAFETY: a plain setter of OpenBLAS, linked through clarabel's `sdp-openblas`.
    ONCE.call_once(|| unsafe { openblas_set_num_threads(1) });
}
