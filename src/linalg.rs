//! Dense linear algebra shared by identification, simulation reports and the diagnosis:
//! column scaling to unit diagonal, and least squares that stay defined on rank-deficient
//! normal equations (minimum-norm solutions on the range).
//!
//! Floor 1 (architecture.md §6): imports nothing from physid.

use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// Relative eigenvalue threshold below which a direction of the (column-scaled) normal matrix
/// counts as unidentifiable.
pub const RANK_TOL: f64 = 1e-9;

/// Rank and condition number of a regressor from its normal matrix `YᵀY`, physid's one
/// definition (used by `simulate`, `identify` and the README): the columns of `Y` scaled to unit
/// norm (numerically zero columns left at zero, [`excited_scale`]), its singular values `σ_i = √λ_i(D YᵀY D)`; the rank counts those with
/// `σ_i² > RANK_TOL σ_max²` (`σ_i > 3.2·10⁻⁵ σ_max`), the condition number is `σ_max` over
/// the smallest of them (the conditioning of the identifiable subspace).
pub fn rank_and_condition(yty: &DMatrix<f64>) -> (usize, f64) {
    let p = yty.nrows();
    let d = excited_scale(yty);
    let scaled = DMatrix::from_fn(p, p, |i, j| d[i] * yty[(i, j)] * d[j]);
    let ev = SymmetricEigen::new(scaled).eigenvalues;
    let lmax = ev.iter().copied().fold(0.0f64, f64::max);
    let kept: Vec<f64> = ev
        .iter()
        .copied()
        .filter(|l| *l > RANK_TOL * lmax)
        .collect();
    let lmin = kept.iter().copied().fold(f64::INFINITY, f64::min);
    let condition = if kept.is_empty() {
        f64::INFINITY
    } else {
        (lmax / lmin).sqrt()
    };
    (kept.len(), condition)
}

/// A column whose norm is below this fraction of the largest column's is numerically zero (the
/// round-off of a structurally zero column, e.g. a vertical first joint's mass column): unexcited.
pub const UNEXCITED: f64 = 1e-10;

/// Column scaling of a normal matrix to unit diagonal, `1/√m_ii`, with `0` for an unexcited
/// column (`√m_ii` below [`UNEXCITED`] of the largest): scaled to unit norm, round-off would
/// look like an independent direction.
pub fn excited_scale(m: &DMatrix<f64>) -> Vec<f64> {
    let largest = (0..m.nrows()).map(|i| m[(i, i)]).fold(0.0f64, f64::max);
    (0..m.nrows())
        .map(|i| {
            if m[(i, i)] > UNEXCITED * UNEXCITED * largest && m[(i, i)] > 0.0 {
                1.0 / m[(i, i)].sqrt()
            } else {
                0.0
            }
        })
        .collect()
}

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

#[cfg(test)]
mod rank_tests {
    use super::*;

    #[test]
    fn rank_and_condition_follow_the_stated_threshold() {
        // Two nearly collinear columns [1, 0] and [1, ε]: unit-norm Gram [[1, c], [c, 1]] with
        // c = 1/√(1 + ε²), eigenvalues 1 ± c.
        let gram = |eps: f64| DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0 + eps * eps]);
        let (rank, cond) = rank_and_condition(&gram(1e-3));
        let c = 1.0 / (1.0f64 + 1e-6).sqrt();
        assert_eq!(rank, 2);
        assert!(
            (cond - ((1.0 + c) / (1.0 - c)).sqrt()).abs() < 1e-3 * cond,
            "{cond}"
        );
        // (1 − c)/(1 + c) ≈ 2.5e-13 < RANK_TOL: one direction.
        assert_eq!(rank_and_condition(&gram(1e-6)), (1, 1.0));
        // An unexcited column counts for nothing.
        let m = DMatrix::from_row_slice(2, 2, &[4.0, 0.0, 0.0, 0.0]);
        assert_eq!(rank_and_condition(&m), (1, 1.0));
    }
}
