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

/// Clarabel's PSD cones and physid's normal equations call OpenBLAS, which would spread each
/// small product over a thread per core. One thread keeps results independent of the
/// machine's thread count, and the parallelism belongs to the experiment level (rayon): this
/// sets OpenBLAS to one thread, before physid's first BLAS call. Idempotent.
pub fn single_threaded_blas() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    extern "C" {
        fn openblas_set_num_threads(n: std::ffi::c_int);
    }
    // SAFETY: a plain setter of OpenBLAS, linked through clarabel's `sdp-openblas`.
    ONCE.call_once(|| unsafe { openblas_set_num_threads(1) });
}

/// [`single_threaded_blas`], and the worker threads OpenBLAS started when it was loaded (one
/// per core, before `main`, each spinning about 0.1 s on `sched_yield`, the length of a short
/// command, against rayon's threads) joined through its `blas_thread_shutdown_`, found at run
/// time: a build of OpenBLAS without it, such as its OpenMP one, keeps its idle workers.
///
/// For a process that owns its OpenBLAS, called before anything else runs (the `physid`
/// binary does, as it starts): the workers must not be at work for another caller, so a
/// library, or the Python module, whose host may share the same OpenBLAS, does not call it.
pub fn single_threaded_blas_without_workers() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    single_threaded_blas();
    ONCE.call_once(stop_blas_workers);
}

/// Joins OpenBLAS's worker threads, if this OpenBLAS can
/// (see [`single_threaded_blas_without_workers`]).
fn stop_blas_workers() {
    #[cfg(target_os = "linux")]
    {
        extern "C" {
            fn dlsym(
                handle: *mut std::ffi::c_void,
                symbol: *const std::ffi::c_char,
            ) -> *mut std::ffi::c_void;
        }
        // RTLD_DEFAULT on Linux: search the process's global symbols.
        let rtld_default = std::ptr::null_mut();
        // SAFETY: dlsym with RTLD_DEFAULT and a NUL-terminated name only looks a symbol up.
        let symbol = unsafe { dlsym(rtld_default, c"blas_thread_shutdown_".as_ptr()) };
        if !symbol.is_null() {
            // SAFETY: OpenBLAS's own `int blas_thread_shutdown_(void)` (used by its fork
            // handler): it asks each worker to exit and joins them, under OpenBLAS's lock;
            // with one thread set, later calls run on the caller's thread.
            let shutdown: extern "C" fn() -> std::ffi::c_int =
                unsafe { std::mem::transmute(symbol) };
            shutdown();
        }
    }
}
