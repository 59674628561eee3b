//! Least squares without the cone solver, prediction errors, identifiability and parameter
//! uncertainty.

use super::NormalEquations;
use crate::dynamics::{regressor, Data};
use crate::io::samples::Trajectory;
use crate::model::Model;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use serde::Serialize;

/// Relative eigenvalue threshold below which a direction of the (column-scaled) normal matrix
/// counts as unidentifiable.
pub const RANK_TOL: f64 = 1e-9;

/// Column scaling to unit diagonal: `1/√m_ii`, or `fallback` where `m_ii <= 0` (an
/// unexcited column).
pub fn unit_diagonal_scale(m: &DMatrix<f64>, fallback: f64) -> Vec<f64> {
    (0..m.nrows())
        .map(|i| {
            if m[(i, i)] > 0.0 {
                1.0 / m[(i, i)].sqrt()
            } else {
                fallback
            }
        })
        .collect()
}

/// `argmin θᵀ H θ − 2 gᵀ θ` for symmetric positive semidefinite `H`: Cholesky when `H` is
/// positive definite, otherwise the minimum-norm solution on `H`'s range (column-scaled
/// eigen-decomposition, directions below [`RANK_TOL`] dropped).
pub fn least_squares(h: &DMatrix<f64>, g: &DVector<f64>) -> DVector<f64> {
    if let Some(ch) = h.clone().cholesky() {
        let x = ch.solve(g);
        if x.iter().all(|v| v.is_finite()) {
            return x;
        }
    }
    min_norm_solve(h, &DMatrix::from_column_slice(g.len(), 1, g.as_slice()))
        .column(0)
        .into()
}

/// The minimum-norm solutions `X` of `H X = G` on the range of symmetric positive semidefinite
/// `H` (column-scaled eigen-decomposition, directions below [`RANK_TOL`] dropped), for every
/// column of `G` at once.
pub fn min_norm_solve(h: &DMatrix<f64>, g: &DMatrix<f64>) -> DMatrix<f64> {
    let p = h.nrows();
    let d = unit_diagonal_scale(h, 0.0);
    let hs = DMatrix::from_fn(p, p, |i, j| d[i] * h[(i, j)] * d[j]);
    let eig = SymmetricEigen::new(hs);
    let lmax = eig.eigenvalues.max();
    let mut x = DMatrix::zeros(p, g.ncols());
    for c in 0..g.ncols() {
        let gs = DVector::from_iterator(p, (0..p).map(|i| d[i] * g[(i, c)]));
        let mut xs = DVector::zeros(p);
        for k in 0..p {
            let l = eig.eigenvalues[k];
            if l > RANK_TOL * lmax {
                let v = eig.eigenvectors.column(k);
                xs += v * (v.dot(&gs) / l);
            }
        }
        for i in 0..p {
            x[(i, c)] = d[i] * xs[i];
        }
    }
    x
}

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

/// Per-joint RMS of `Y θ − τ` over samples `range` of a CSV file, streamed (N m).
pub fn rms_error_csv(
    model: &Model,
    theta: &DVector<f64>,
    path: &std::path::Path,
    range: std::ops::Range<usize>,
) -> Result<(Vec<f64>, f64), crate::io::IoError> {
    let (n, p) = (model.dof(), model.layout().len);
    let mut d = Data::new(model);
    let mut y = DMatrix::zeros(n, p);
    let mut ss = vec![0.0; n];
    let mut count = 0usize;
    crate::io::samples::stream_csv(path, n, range, &mut |_, s| {
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
#[derive(Clone, Debug, Serialize)]
pub struct Identifiability {
    /// Numerical rank of the column-scaled `YᵀY`.
    pub rank: usize,
    /// Number of parameters.
    pub parameters: usize,
    /// Condition number on the identifiable subspace (scaled columns).
    pub condition: f64,
    /// Unidentifiable parameter combinations: the largest terms of each null-space direction,
    /// e.g. `"0.71 thigh.m − 0.71 hip_rotor.m"`. At most 20 are listed.
    pub unidentifiable: Vec<String>,
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
    let mut lmin = f64::INFINITY;
    let mut null_weight = vec![0.0f64; p];
    let mut unidentifiable = vec![];
    let mut cov_s = DMatrix::zeros(p, p);
    for k in 0..p {
        let l = eig.eigenvalues[k];
        let v = eig.eigenvectors.column(k);
        if l > RANK_TOL * lmax {
            rank += 1;
            lmin = lmin.min(l);
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
    let rows = (ne.samples * model.dof()) as f64;
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
    Identifiability {
        rank,
        parameters: p,
        condition: (lmax / lmin).sqrt(),
        unidentifiable,
        standard_errors,
    }
}
