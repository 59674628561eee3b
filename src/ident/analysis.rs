//! Least squares without the cone solver, prediction errors, identifiability and parameter
//! uncertainty.

use super::NormalEquations;
use crate::dynamics::{regressor, Data};
use crate::linalg::{unit_diagonal_scale, RANK_TOL};
use crate::model::Model;
use crate::trajectory::{SampleSink, Trajectory};
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use serde::Serialize;

/// The residual `τ − Y θ` (N m) of samples `range`, sample-major.
pub fn residuals(
    model: &Model,
    theta: &DVector<f64>,
    tr: &Trajectory,
    range: std::ops::Range<usize>,
) -> Vec<f64> {
    let n = model.dof();
    let mut out = Vec::with_capacity(range.len() * n);
    super::normal::for_each_regressor(model, tr, range, &mut |k, y| {
        let pred = y * theta;
        out.extend((0..n).map(|j| tr.tau_at(k)[j] - pred[j]));
    });
    out
}

/// Per-joint RMS of `Y θ − τ` over samples `range` (N m), and the overall RMS.
pub fn rms_error(
    model: &Model,
    theta: &DVector<f64>,
    tr: &Trajectory,
    range: std::ops::Range<usize>,
) -> (Vec<f64>, f64) {
    let n = model.dof();
    let count = range.len().max(1) as f64;
    let res = residuals(model, theta, tr, range);
    let per: Vec<f64> = (0..n)
        .map(|j| (res.iter().skip(j).step_by(n).map(|r| r * r).sum::<f64>() / count).sqrt())
        .collect();
    let overall = (res.iter().map(|r| r * r).sum::<f64>() / (count * n as f64)).sqrt();
    (per, overall)
}

/// Per-joint and overall RMS of `Y θ − τ` (N m) over the samples a source streams (e.g. a CSV
/// read from disk by `io::samples::stream_csv`).
pub fn rms_error_stream<E>(
    model: &Model,
    theta: &DVector<f64>,
    source: impl FnOnce(&mut SampleSink) -> Result<usize, E>,
) -> Result<(Vec<f64>, f64), E> {
    let (n, p) = (model.dof(), model.layout().len);
    let mut d = Data::new(model);
    let mut y = DMatrix::zeros(n, p);
    let mut ss = vec![0.0; n];
    let mut count = 0usize;
    source(&mut |_, s| {
        regressor(model, &mut d, s.q, s.qd, s.qdd, &mut y);
        let pred = &y * theta;
        for j in 0..n {
            ss[j] += (pred[j] - s.tau[j]).powi(2);
        }
        count += 1;
    })?;
    let c = count.max(1) as f64;
    Ok((
        ss.iter().map(|v| (v / c).sqrt()).collect(),
        (ss.iter().sum::<f64>() / (c * n as f64)).sqrt(),
    ))
}

/// What the data determine.
#[derive(Clone, Debug, Serialize, schemars::JsonSchema)]
pub struct Identifiability {
    /// Numerical rank ([`crate::linalg::rank_and_condition`], the same definition).
    pub rank: usize,
    /// Number of parameters.
    pub parameters: usize,
    /// Condition number on the identifiable subspace ([`crate::linalg::rank_and_condition`]).
    pub condition: f64,
    /// Unidentifiable parameter combinations: the largest terms of each null-space direction,
    /// e.g. `"0.71 thigh.m − 0.71 hip_rotor.m"`. At most 20 are listed
    /// ([`Identifiability::unidentifiable_total`] counts them all).
    pub unidentifiable: Vec<String>,
    /// How many unidentifiable directions there are (`parameters − rank`), of which
    /// `unidentifiable` lists the first 20.
    pub unidentifiable_total: usize,
    /// Standard error of each parameter (`σ² (YᵀY)⁺` with `σ²` the residual variance), infinite
    /// where the parameter moves along an unidentifiable direction.
    pub standard_errors: Vec<f64>,
}

/// Rank, conditioning, null space and standard errors of the normal equations at `theta`.
pub fn identifiability(
    model: &Model,
    ne: &NormalEquations,
    theta: &DVector<f64>,
) -> Identifiability {
    let p = model.layout().len;
    let yty = &ne.yty;
    let d = unit_diagonal_scale(yty, 0.0);
    let hs = DMatrix::from_fn(p, p, |i, j| d[i] * yty[(i, j)] * d[j]);
    let eig = SymmetricEigen::new(hs);
    let lmax = eig.eigenvalues.max().max(0.0);
    let names = model.parameter_names();
    let mut rank = 0;
    let mut null_weight = vec![0.0f64; p];
    let mut unidentifiable = vec![];
    let mut cov_s = DMatrix::zeros(p, p);
    for k in 0..p {
        let l = eig.eigenvalues[k];
        let v = eig.eigenvectors.column(k);
        if l > RANK_TOL * lmax {
            rank += 1;
            cov_s += v * v.transpose() / l;
        } else {
            // Unscaled direction: θ = D x.
            let mut dir: Vec<(usize, f64)> = (0..p)
                .map(|i| (i, if d[i] > 0.0 { v[i] * d[i] } else { v[i] }))
                .collect();
            let norm = dir.iter().map(|(_, x)| x * x).sum::<f64>().sqrt();
            for (i, x) in &mut dir {
                *x /= norm;
                null_weight[*i] = null_weight[*i].max(x.abs());
            }
            if unidentifiable.len() < 20 {
                dir.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
                let terms: Vec<String> = dir
                    .iter()
                    .take(4)
                    .filter(|(_, x)| x.abs() > 0.05)
                    .map(|(i, x)| format!("{x:+.2} {}", names[*i]))
                    .collect();
                unidentifiable.push(terms.join(" "));
            }
        }
    }
    // Parameters whose column is never excited are unidentifiable too.
    for i in 0..p {
        if d[i] == 0.0 {
            null_weight[i] = 1.0;
        }
    }
    let rows = (ne.samples * ne.rows_per_sample()) as f64;
    let sigma2 = ne.residual_sum_of_squares(theta) / (rows - rank as f64).max(1.0);
    let standard_errors = (0..p)
        .map(|i| {
            if null_weight[i] > 1e-6 {
                f64::INFINITY
            } else {
                (sigma2 * cov_s[(i, i)]).sqrt() * d[i]
            }
        })
        .collect();
    // The one definition of rank and condition; the loop above drew the same line.
    let (rank_checked, condition) = crate::linalg::rank_and_condition(yty);
    debug_assert_eq!(rank_checked, rank);
    Identifiability {
        rank,
        parameters: p,
        condition,
        unidentifiable,
        unidentifiable_total: p - rank,
        standard_errors,
    }
}
