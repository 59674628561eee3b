//! The dynamics over many samples at once, on flat arrays as numpy and other callers hold
//! them: `q`, `q̇`, `q̈` sample-major (`samples × n`, row-major), results likewise. Shapes and
//! values are checked before any work (an error naming the array and the sample, never a
//! panic); samples are computed in parallel (rayon) and the results do not depend on the
//! thread count (each sample is computed alone).

use super::ApiError;
use crate::dynamics::{crba, regressor, rnea_with_friction, Data};
use crate::model::Model;
use nalgebra::DMatrix;
use rayon::prelude::*;

/// A wrong shape or value in an array given to a batch routine.
#[derive(Debug, thiserror::Error)]
pub enum ShapeError {
    /// The array's length is not `samples × n`.
    #[error("{name} has {len} values, not a whole number of samples of {n} joints")]
    Length {
        /// The array (`q`, `qd`, `qdd`).
        name: &'static str,
        /// Its length.
        len: usize,
        /// The robot's joints.
        n: usize,
    },
    /// Two arrays hold different numbers of samples.
    #[error("{name} has {got} samples, q has {want}")]
    Samples {
        /// The array.
        name: &'static str,
        /// Its samples.
        got: usize,
        /// q's samples.
        want: usize,
    },
    /// A value is NaN or infinite.
    #[error("{name}: sample {sample}, joint {joint} is {value}")]
    NotFinite {
        /// The array.
        name: &'static str,
        /// The sample.
        sample: usize,
        /// The joint (index in the robot's order).
        joint: usize,
        /// The value.
        value: f64,
    },
}

/// The number of samples in `q` (and in each of `others`, which must hold as many), every value
/// finite: the check every batch routine makes before any work.
pub fn samples(
    model: &Model,
    q: &[f64],
    others: &[(&'static str, &[f64])],
) -> Result<usize, ShapeError> {
    let n = model.dof();
    let count = |name: &'static str, v: &[f64]| -> Result<usize, ShapeError> {
        if n == 0 || v.len() % n != 0 {
            return Err(ShapeError::Length {
                name,
                len: v.len(),
                n,
            });
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(ShapeError::NotFinite {
                name,
                sample: i / n,
                joint: i % n,
                value: v[i],
            });
        }
        Ok(v.len() / n)
    };
    let want = count("q", q)?;
    for (name, v) in others {
        let got = count(name, v)?;
        if got != want {
            return Err(ShapeError::Samples { name, got, want });
        }
    }
    Ok(want)
}

/// Runs `f` on every sample in parallel (`out` values per sample), each with its own
/// workspace.
fn per_sample(
    model: &Model,
    count: usize,
    out: usize,
    f: impl Fn(&mut Data, usize, &mut [f64]) + Sync,
) -> Vec<f64> {
    let mut result = vec![0.0; count * out];
    if out == 0 {
        return result;
    }
    result
        .par_chunks_mut(out)
        .enumerate()
        .for_each_init(|| Data::new(model), |data, (k, slot)| f(data, k, slot));
    result
}

/// `τ = RNEA(q, q̇, q̈) + friction` (N m) per sample: `samples × n`.
pub fn inverse_dynamics(
    model: &Model,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<Vec<f64>, ApiError> {
    let count = samples(model, q, &[("qd", qd), ("qdd", qdd)])?;
    let n = model.dof();
    Ok(per_sample(model, count, n, |data, k, tau| {
        let s = k * n..(k + 1) * n;
        let t = rnea_with_friction(model, data, &q[s.clone()], &qd[s.clone()], &qdd[s]);
        tau.copy_from_slice(t.as_slice());
    }))
}

/// The joint-space mass matrix `H(q)` (kg m², rotors' reflected inertia included) per
/// sample: `samples × n × n`, each matrix row-major.
pub fn mass_matrices(model: &Model, q: &[f64]) -> Result<Vec<f64>, ApiError> {
    let count = samples(model, q, &[])?;
    let n = model.dof();
    Ok(per_sample(model, count, n * n, |data, k, h| {
        let m = crba(model, data, &q[k * n..(k + 1) * n]);
        for i in 0..n {
            for j in 0..n {
                h[i * n + j] = m[(i, j)];
            }
        }
    }))
}

/// The regressor `Y(q, q̇, q̈)` with `Y θ = τ` (the model's parameter layout, friction
/// columns last) per sample: `samples × n × p`, each matrix row-major.
pub fn regressors(model: &Model, q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<Vec<f64>, ApiError> {
    let count = samples(model, q, &[("qd", qd), ("qdd", qdd)])?;
    let (n, p) = (model.dof(), model.layout().len);
    Ok(per_sample(model, count, n * p, |data, k, out| {
        let s = k * n..(k + 1) * n;
        let mut y = DMatrix::zeros(n, p);
        regressor(model, data, &q[s.clone()], &qd[s.clone()], &qdd[s], &mut y);
        for i in 0..n {
            for j in 0..p {
                out[i * p + j] = y[(i, j)];
            }
        }
    }))
}
