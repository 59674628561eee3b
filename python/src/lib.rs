//! `physid._physid`: the Python extension over physid's library entry points (`physid::api`).
//!
//! Arrays cross as numpy arrays of float64: joint quantities as `(samples, n)` (a 1-D array of
//! `n` is one sample), results likewise. Errors raise `ValueError` with the library's message;
//! long calls release the GIL.

mod arrays;
mod compare;
mod convert;
mod data;
mod diagnose;
mod errors;
mod excite;
mod experiment;
mod floating;
mod identify;
mod notebook;
mod pickle;
mod robot;
mod simulate;
mod sweep;
mod work;

use pyo3::prelude::*;

/// physid's version.
#[pyfunction]
fn version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

/// OpenBLAS's kernels for the CPU's instruction set where it did not know the CPU
/// (`physid::api::openblas_kernels_for_this_cpu`): the kernels selected, if any. Called once
/// by the package as it is imported, only when importing this module brought OpenBLAS into
/// the process (no other module calls it yet).
#[pyfunction]
fn _select_blas_kernels() -> Option<&'static str> {
    physid::api::openblas_kernels_for_this_cpu()
}

#[pymodule]
fn _physid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The library's parallel loops (the normal equations' chunks) run on rayon's global pool.
    // Named here: threads spawned from a call's worker would otherwise inherit its name
    // ("physid") and look like abandoned workers. An error means a pool already exists.
    let _ = rayon::ThreadPoolBuilder::new()
        .thread_name(|i| format!("physid-rayon-{i}"))
        .build_global();
    m.add_class::<robot::Robot>()?;
    m.add_class::<data::Data>()?;
    m.add_class::<identify::Identification>()?;
    m.add_class::<diagnose::Diagnosis>()?;
    m.add_class::<simulate::Simulation>()?;
    m.add_class::<experiment::Experiment>()?;
    m.add_class::<compare::Comparison>()?;
    m.add_class::<excite::Excitation>()?;
    m.add_class::<sweep::Sweep>()?;
    m.add_class::<floating::FloatingIdentification>()?;
    m.add_class::<floating::FloatingRobot>()?;
    m.add_function(wrap_pyfunction!(floating::simulate_floating, m)?)?;
    m.add_function(wrap_pyfunction!(floating::identify_floating, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep, m)?)?;
    m.add_function(wrap_pyfunction!(excite::excite, m)?)?;
    m.add_function(wrap_pyfunction!(excite::score_motion, m)?)?;
    m.add_function(wrap_pyfunction!(compare::compare, m)?)?;
    m.add_function(wrap_pyfunction!(experiment::experiment, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose::diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(identify::identify, m)?)?;
    m.add_function(wrap_pyfunction!(identify::load, m)?)?;
    m.add_function(wrap_pyfunction!(version, m)?)?;
    m.add_function(wrap_pyfunction!(_select_blas_kernels, m)?)?;
    m.add_function(wrap_pyfunction!(pickle::_restore, m)?)?;
    Ok(())
}
