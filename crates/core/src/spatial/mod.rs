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

/// OpenBLAS's kernels for the CPU's instruction set, where the OpenBLAS loaded did not know
/// the CPU and fell back to older ones: Debian 12's OpenBLAS 0.3.21 does not know recent
/// models (a cloud VM's "Intel(R) Xeon(R) Processor" with AVX-512) and runs its Prescott (SSE3)
/// kernels there, markedly slower on the diagnosis's small dense products. With AVX-512 (F,
/// CD, BW, DQ, VL) its SkylakeX kernels are selected, with AVX2 and FMA its Haswell ones, as
/// `OPENBLAS_CORETYPE` selects them when the library loads. Nothing changes when the user set
/// `OPENBLAS_CORETYPE`, when the build has one set of kernels (no `DYNAMIC_ARCH`), or when
/// OpenBLAS runs kernels of the AVX2 generation or later. Returns the kernels selected.
///
/// For a process that owns its OpenBLAS, before its first BLAS call: the selection replaces
/// the kernel table a concurrent call would read. The `physid` binary calls it as it starts,
/// the Python module as it is imported when it brought OpenBLAS into the process.
pub fn openblas_kernels_for_this_cpu() -> Option<&'static str> {
    #[cfg(all(target_os = "linux", target_arch = "x86_64"))]
    {
        if std::env::var_os("OPENBLAS_CORETYPE").is_some() {
            return None;
        }
        let wanted = kernels_for(&openblas_corename(), cpu_level())?;
        select_openblas_kernels(wanted).then_some(wanted)
    }
    #[cfg(not(all(target_os = "linux", target_arch = "x86_64")))]
    None
}

/// The instruction sets OpenBLAS's kernel generations need, as this CPU (and its OS) supports
/// them.
#[cfg(all(target_os = "linux", target_arch = "x86_64"))]
fn cpu_level() -> CpuLevel {
    let avx512 = is_x86_feature_detected!("avx512f")
        && is_x86_feature_detected!("avx512cd")
        && is_x86_feature_detected!("avx512bw")
        && is_x86_feature_detected!("avx512dq")
        && is_x86_feature_detected!("avx512vl");
    let avx2 = is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma");
    match (avx512, avx2) {
        (true, true) => CpuLevel::Avx512,
        (_, true) => CpuLevel::Avx2,
        _ => CpuLevel::Older,
    }
}

/// What a CPU offers OpenBLAS's kernels.
#[derive(Clone, Copy, Debug, PartialEq)]
enum CpuLevel {
    /// AVX-512 F, CD, BW, DQ and VL (with AVX2 and FMA).
    Avx512,
    /// AVX2 and FMA.
    Avx2,
    /// Neither.
    Older,
}

/// The kernels to select where OpenBLAS runs its `loaded` ones (its core name) on a CPU of
/// `level`: none when `loaded` is of the AVX2 generation or later, or the CPU is older.
fn kernels_for(loaded: &str, level: CpuLevel) -> Option<&'static str> {
    const CURRENT: [&str; 6] = [
        "haswell",
        "zen",
        "excavator",
        "skylakex",
        "cooperlake",
        "sapphirerapids",
    ];
    if CURRENT.contains(&loaded.to_ascii_lowercase().as_str()) {
        return None;
    }
    match level {
        CpuLevel::Avx512 => Some("SkylakeX"),
        CpuLevel::Avx2 => Some("Haswell"),
        CpuLevel::Older => None,
    }
}

/// Has a `DYNAMIC_ARCH` OpenBLAS select the kernels `name` (a core name it knows) as it would
/// at load under `OPENBLAS_CORETYPE`; whether it now runs them. The variable is set for the
/// selection only.
#[cfg(all(target_os = "linux", target_arch = "x86_64"))]
fn select_openblas_kernels(name: &str) -> bool {
    let (Some(quit), Some(init)) = (
        openblas_symbol(c"gotoblas_dynamic_quit"),
        openblas_symbol(c"gotoblas_dynamic_init"),
    ) else {
        return false;
    };
    // SAFETY: OpenBLAS's own `void gotoblas_dynamic_quit(void)` (clears its kernel table) and
    // `void gotoblas_dynamic_init(void)` (selects one, by OPENBLAS_CORETYPE when set, and
    // sets its block sizes), as its constructor calls them; the caller owns the process's
    // OpenBLAS, which no other thread is calling.
    unsafe {
        let quit: extern "C" fn() = std::mem::transmute(quit);
        let init: extern "C" fn() = std::mem::transmute(init);
        std::env::set_var("OPENBLAS_CORETYPE", name);
        quit();
        init();
        std::env::remove_var("OPENBLAS_CORETYPE");
    }
    openblas_corename() == name
}

/// The name of the kernels OpenBLAS runs (`Prescott`, `Haswell`, `SkylakeX`, ...).
#[cfg(all(target_os = "linux", target_arch = "x86_64"))]
fn openblas_corename() -> String {
    extern "C" {
        fn openblas_get_corename() -> *const std::ffi::c_char;
    }
    // SAFETY: OpenBLAS's getter of a static, NUL-terminated name.
    let name = unsafe { std::ffi::CStr::from_ptr(openblas_get_corename()) };
    name.to_string_lossy().into_owned()
}

/// The address of OpenBLAS's routine `symbol`, where this OpenBLAS has it (looked up at run
/// time among the process's global symbols, so that a build without it still links).
#[cfg(target_os = "linux")]
fn openblas_symbol(symbol: &std::ffi::CStr) -> Option<*mut std::ffi::c_void> {
    extern "C" {
        fn dlsym(
            handle: *mut std::ffi::c_void,
            symbol: *const std::ffi::c_char,
        ) -> *mut std::ffi::c_void;
    }
    // RTLD_DEFAULT on Linux: search the process's global symbols.
    let rtld_default = std::ptr::null_mut();
    // SAFETY: dlsym with RTLD_DEFAULT and a NUL-terminated name only looks a symbol up.
    let address = unsafe { dlsym(rtld_default, symbol.as_ptr()) };
    (!address.is_null()).then_some(address)
}

/// Joins OpenBLAS's worker threads, if this OpenBLAS can
/// (see [`single_threaded_blas_without_workers`]).
fn stop_blas_workers() {
    #[cfg(target_os = "linux")]
    {
        if let Some(symbol) = openblas_symbol(c"blas_thread_shutdown_") {
            // SAFETY: OpenBLAS's own `int blas_thread_shutdown_(void)` (used by its fork
            // handler): it asks each worker to exit and joins them, under OpenBLAS's lock;
            // with one thread set, later calls run on the caller's thread.
            let shutdown: extern "C" fn() -> std::ffi::c_int =
                unsafe { std::mem::transmute(symbol) };
            shutdown();
        }
    }
}

#[cfg(test)]
mod kernel_tests {
    use super::{kernels_for, CpuLevel};

    #[test]
    fn kernels_of_an_older_generation_give_way_to_the_cpus() {
        // Debian 12's OpenBLAS on an AVX-512 VM it does not know: Prescott, SSE3.
        assert_eq!(kernels_for("Prescott", CpuLevel::Avx512), Some("SkylakeX"));
        assert_eq!(kernels_for("Nehalem", CpuLevel::Avx2), Some("Haswell"));
        assert_eq!(kernels_for("Sandybridge", CpuLevel::Avx2), Some("Haswell"));
        assert_eq!(kernels_for("Unknown", CpuLevel::Avx512), Some("SkylakeX"));
    }

    #[test]
    fn current_kernels_and_older_cpus_are_left_alone() {
        for current in ["Haswell", "Zen", "SkylakeX", "Cooperlake", "SAPPHIRERAPIDS"] {
            assert_eq!(kernels_for(current, CpuLevel::Avx512), None, "{current}");
        }
        assert_eq!(kernels_for("Prescott", CpuLevel::Older), None);
    }
}
