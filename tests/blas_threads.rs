//! OpenBLAS's worker threads, started when it is loaded, are stopped by
//! `physid::spatial::single_threaded_blas_without_workers` (they would spin against rayon's threads), and BLAS
//! still works on the caller's thread afterwards. One test in its own process: nothing else may
//! have called BLAS first.

extern "C" {
    fn openblas_get_num_threads() -> std::ffi::c_int;
}

/// The threads of this process (Linux).
fn threads() -> usize {
    std::fs::read_dir("/proc/self/task").unwrap().count()
}

/// The threads of this process once they number `expected`, or after two seconds: a joined
/// thread has exited, but the kernel may list it under `/proc/self/task` a moment longer (its
/// join returns when the thread clears its id, before the kernel releases the task).
fn threads_settling_at(expected: usize) -> usize {
    for _ in 0..200 {
        if threads() == expected {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    threads()
}

#[test]
#[cfg(target_os = "linux")]
fn stopping_openblas_workers_leaves_one_thread_that_still_computes() {
    // SAFETY: a plain getter of OpenBLAS.
    let started = unsafe { openblas_get_num_threads() } as usize;
    let before = threads();
    physid::spatial::single_threaded_blas_without_workers();
    // SAFETY: as above.
    assert_eq!(unsafe { openblas_get_num_threads() }, 1);
    // OpenBLAS runs `started` threads including the caller's: the others are gone.
    assert_eq!(
        threads_settling_at(before - (started - 1)),
        before - (started - 1),
        "{started} OpenBLAS threads at start"
    );
    // Calling again changes nothing; BLAS (through an identification's normal equations and
    // the solver's PSD cones) still gives the answer.
    physid::spatial::single_threaded_blas_without_workers();
    assert_eq!(threads(), before - (started - 1));
    // The minimum-volume ellipsoid of a box (Clarabel's PSD cone, through LAPACK and BLAS) has
    // semi-axes √3 times the box's half sizes.
    use nalgebra::Vector3;
    use physid::spatial::bounding::{box_corners, minimum_volume_ellipsoid};
    let e = minimum_volume_ellipsoid(&box_corners(&Vector3::new(0.2, 0.4, 1.0))).unwrap();
    let squared = Vector3::new(0.1f64, 0.2, 0.5).map(|h| 3.0 * h * h);
    assert!((e.qs.diagonal() - squared).norm() < 1e-6, "{}", e.qs);
    assert_eq!(threads(), before - (started - 1));
}
