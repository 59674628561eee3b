//! Dense linear algebra shared by identification, simulation reports and the diagnosis:
//! column scaling to unit diagonal, and least squares that stay defined on rank-deficient
//! normal equations (minimum-norm solutions on the range).
//!
//! Floor 1 (architecture.md §6): imports nothing from physid.

use nalgebra::{DMatrix, DVector, Matrix3, Rotation3, SymmetricEigen, Vector3};

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

/// `argmin θᵀ H θ − 2 gᵀ θ` subject to `θ_i ≥ 0` for `i` in `nonneg` (the others free), for
/// symmetric positive definite `H`: Lawson and Hanson's active set (the bounded variables start
/// at zero; the one whose gradient pulls it up most is freed, a step that would cross a bound
/// stops on it), each subproblem solved by [`least_squares`]. Without bounds, or when the free
/// solution keeps them, it is [`least_squares`]'s.
pub fn least_squares_nonneg(h: &DMatrix<f64>, g: &DVector<f64>, nonneg: &[usize]) -> DVector<f64> {
    let free = least_squares(h, g);
    if nonneg.iter().all(|&i| free[i] >= 0.0) {
        return free;
    }
    let p = g.len();
    let mut at_bound: Vec<bool> = (0..p).map(|i| nonneg.contains(&i)).collect();
    let mut x = solve_off_bounds(h, g, &at_bound);
    // Each pass frees one variable or fixes one: 3p passes are far beyond what convergence
    // takes; the last feasible iterate is kept if it is ever reached.
    for _ in 0..3 * p + 3 {
        // The gradient of ½θᵀHθ − gᵀθ; a variable at its bound with a negative gradient wants up.
        let grad = h * &x - g;
        let scale = g.amax().max(1e-300);
        let pull = (0..p)
            .filter(|&i| at_bound[i] && grad[i] < -1e-12 * scale)
            .min_by(|&a, &b| grad[a].total_cmp(&grad[b]));
        let Some(i) = pull else {
            return x;
        };
        at_bound[i] = false;
        loop {
            let z = solve_off_bounds(h, g, &at_bound);
            let crossing: Vec<usize> = nonneg
                .iter()
                .copied()
                .filter(|&j| !at_bound[j] && z[j] <= 0.0)
                .collect();
            if crossing.is_empty() {
                x = z;
                break;
            }
            // Step from x towards z until the first bounded variable reaches zero.
            let alpha = crossing
                .iter()
                .map(|&j| x[j] / (x[j] - z[j]).max(1e-300))
                .fold(1.0_f64, f64::min)
                .clamp(0.0, 1.0);
            x += (z - &x) * alpha;
            for &j in &crossing {
                if x[j] <= 1e-14 * (1.0 + x.amax()) {
                    x[j] = 0.0;
                    at_bound[j] = true;
                }
            }
        }
    }
    x
}

/// [`least_squares`] over the variables not `at_bound`, those held at zero.
fn solve_off_bounds(h: &DMatrix<f64>, g: &DVector<f64>, at_bound: &[bool]) -> DVector<f64> {
    let idx: Vec<usize> = (0..g.len()).filter(|&i| !at_bound[i]).collect();
    let hf = DMatrix::from_fn(idx.len(), idx.len(), |a, b| h[(idx[a], idx[b])]);
    let gf = DVector::from_fn(idx.len(), |a, _| g[idx[a]]);
    let y = least_squares(&hf, &gf);
    let mut x = DVector::zeros(g.len());
    for (a, &i) in idx.iter().enumerate() {
        x[i] = y[a];
    }
    x
}

/// The minimum-norm solutions `X` of `H X = G` on the range of symmetric positive semidefinite
/// `H` (column-scaled eigen-decomposition, directions below [`RANK_TOL`] dropped), for every
/// column of `G` at once.
pub fn min_norm_solve(h: &DMatrix<f64>, g: &DMatrix<f64>) -> DMatrix<f64> {
    MinNorm::new(h).solve(g)
}

/// [`min_norm_solve`]'s decomposition of `H`, kept to solve for many right-hand sides (each
/// solution the same, bit for bit, as `min_norm_solve`'s).
pub struct MinNorm {
    /// The unit-diagonal column scale `D` (`H_s = D H D`).
    scale: DVector<f64>,
    /// The eigen-decomposition of `H_s`.
    eig: SymmetricEigen<f64, nalgebra::Dyn>,
    /// Its largest eigenvalue.
    largest: f64,
}

impl MinNorm {
    /// Decomposes symmetric positive semidefinite `h`.
    pub fn new(h: &DMatrix<f64>) -> Self {
        let p = h.nrows();
        let d = unit_diagonal_scale(h, 0.0);
        let hs = DMatrix::from_fn(p, p, |i, j| d[i] * h[(i, j)] * d[j]);
        let eig = SymmetricEigen::new(hs);
        let largest = eig.eigenvalues.max();
        Self {
            scale: DVector::from_vec(d),
            eig,
            largest,
        }
    }

    /// The minimum-norm solution of `H X = G`, column by column.
    pub fn solve(&self, g: &DMatrix<f64>) -> DMatrix<f64> {
        let (d, p) = (&self.scale, self.scale.len());
        let mut x = DMatrix::zeros(p, g.ncols());
        for c in 0..g.ncols() {
            let gs = DVector::from_iterator(p, (0..p).map(|i| d[i] * g[(i, c)]));
            let mut xs = DVector::zeros(p);
            for k in 0..p {
                let l = self.eig.eigenvalues[k];
                if l > RANK_TOL * self.largest {
                    let v = self.eig.eigenvectors.column(k);
                    xs += v * (v.dot(&gs) / l);
                }
            }
            for i in 0..p {
                x[(i, c)] = d[i] * xs[i];
            }
        }
        x
    }
}

/// The principal axes of a symmetric 3×3 matrix as a proper rotation (columns the
/// eigenvectors, the third negated where they would make a reflection) and its eigenvalues in
/// the same order: `m = R diag(λ) Rᵀ`. For a rotational inertia, or an ellipsoid's shape matrix.
pub fn principal_axes(m: &Matrix3<f64>) -> (Rotation3<f64>, Vector3<f64>) {
    let eig = SymmetricEigen::new(*m);
    let mut r = eig.eigenvectors;
    if r.determinant() < 0.0 {
        r.column_mut(2).neg_mut();
    }
    (Rotation3::from_matrix_unchecked(r), eig.eigenvalues)
}

/// The median of `v` (values ordered by `f64::total_cmp`, a NaN above every number); 0 for no
/// values.
pub fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len();
    if m == 0 {
        0.0
    } else if m % 2 == 1 {
        s[m / 2]
    } else {
        0.5 * (s[m / 2 - 1] + s[m / 2])
    }
}

#[cfg(test)]
mod rank_tests {
    use super::*;

    #[test]
    fn a_kept_decomposition_gives_each_column_its_minimum_norm_solution() {
        // H = B Bᵀ of rank 4 in 6 unknowns, badly scaled; G in its range.
        let b = DMatrix::from_fn(6, 4, |i, j| {
            ((3 * i + 5 * j) % 7) as f64 - 3.0 + 0.1 * i as f64
        });
        let scale =
            DMatrix::from_diagonal(&DVector::from_vec(vec![1e3, 1.0, 1e-2, 1.0, 10.0, 1.0]));
        let h = &scale * &b * b.transpose() * &scale;
        let u = DMatrix::from_fn(4, 3, |i, j| (i as f64 + 1.0) * (j as f64 - 1.0) + 0.5);
        let g = &h * (&scale.try_inverse().unwrap() * &b * &u);
        let kept = MinNorm::new(&h);
        let x = kept.solve(&g);
        assert_eq!(x, min_norm_solve(&h, &g));
        assert!((&h * &x - &g).norm() <= 1e-8 * g.norm(), "H X = G");
        // The minimum-norm solution in the scaled variables: X = D (D H D)⁺ D G, by an SVD.
        let d = DMatrix::from_diagonal(&DVector::from_vec(unit_diagonal_scale(&h, 0.0)));
        let pinv = (&d * &h * &d).pseudo_inverse(1e-10).unwrap();
        let by_svd = &d * pinv * &d * &g;
        assert!(
            (&x - &by_svd).norm() <= 1e-8 * by_svd.norm(),
            "{x} against {by_svd}"
        );
        // Each column solved alone with the kept decomposition: the same numbers, bit for bit.
        for c in 0..g.ncols() {
            let alone = kept.solve(&g.columns(c, 1).into_owned());
            assert_eq!(alone.column(0), x.column(c));
        }
    }

    /// The bounded solution by brute force: every subset of the bounded variables held at
    /// zero, the feasible subproblem solution of least cost.
    fn brute_force(h: &DMatrix<f64>, g: &DVector<f64>, nonneg: &[usize]) -> DVector<f64> {
        let cost = |x: &DVector<f64>| (x.transpose() * h * x)[(0, 0)] - 2.0 * g.dot(x);
        let mut best: Option<(f64, DVector<f64>)> = None;
        for mask in 0..(1usize << nonneg.len()) {
            let at_bound: Vec<bool> = (0..g.len())
                .map(|i| {
                    nonneg
                        .iter()
                        .position(|&j| j == i)
                        .is_some_and(|k| mask >> k & 1 == 1)
                })
                .collect();
            let x = solve_off_bounds(h, g, &at_bound);
            if nonneg.iter().any(|&i| x[i] < -1e-12) {
                continue;
            }
            let c = cost(&x);
            if best.as_ref().is_none_or(|(b, _)| c < *b) {
                best = Some((c, x));
            }
        }
        best.unwrap().1
    }

    #[test]
    fn the_bounded_solution_is_the_best_feasible_one() {
        // Random well- and ill-conditioned problems, bounds on some variables: the active set's
        // answer equals the brute-force enumeration's, and is feasible.
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let mut bound_active = 0;
        for trial in 0..200 {
            let p = 2 + trial % 6;
            let a = DMatrix::from_fn(p + 3, p, |_, _| next());
            let mut h = a.transpose() * &a;
            if trial % 3 == 0 {
                // A nearly collinear pair of columns.
                for i in 0..p {
                    h[(i, 1)] = h[(i, 0)] * (1.0 + 1e-4);
                    h[(1, i)] = h[(i, 1)];
                }
                h[(1, 1)] = h[(0, 0)] * (1.0 + 1e-4) * (1.0 + 1e-4) + 1e-6;
            }
            let g = DVector::from_fn(p, |_, _| next());
            let nonneg: Vec<usize> = (0..p).filter(|i| (i + trial) % 2 == 0).collect();
            let x = least_squares_nonneg(&h, &g, &nonneg);
            let y = brute_force(&h, &g, &nonneg);
            assert!(nonneg.iter().all(|&i| x[i] >= 0.0), "trial {trial}: {x}");
            let cost = |x: &DVector<f64>| (x.transpose() * &h * x)[(0, 0)] - 2.0 * g.dot(x);
            assert!(
                cost(&x) <= cost(&y) + 1e-9 * (1.0 + cost(&y).abs()),
                "trial {trial}: cost {} vs brute force {}",
                cost(&x),
                cost(&y)
            );
            if nonneg.iter().any(|&i| least_squares(&h, &g)[i] < 0.0) {
                bound_active += 1;
            }
        }
        // The bounds mattered in a good share of the problems (the check is not vacuous).
        assert!(bound_active > 50, "{bound_active}");
    }

    #[test]
    fn without_active_bounds_it_is_the_free_solution() {
        let h = DMatrix::from_row_slice(2, 2, &[2.0, 0.5, 0.5, 1.0]);
        let g = DVector::from_row_slice(&[1.0, 1.0]);
        assert_eq!(least_squares_nonneg(&h, &g, &[0, 1]), least_squares(&h, &g));
        // x = [−1/3, 1] free (H x = g for H = [[1, 1], [1, 4]] , g = [2/3, 11/3]); x₀ ≥ 0 gives
        // x₀ = 0, x₁ = g₁ / H₁₁ = 11/12.
        let h = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 4.0]);
        let g = DVector::from_row_slice(&[2.0 / 3.0, 11.0 / 3.0]);
        let x = least_squares_nonneg(&h, &g, &[0]);
        assert!(x[0] == 0.0 && (x[1] - 11.0 / 12.0).abs() < 1e-12, "{x}");
    }

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
