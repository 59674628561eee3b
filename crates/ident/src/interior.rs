//! The constrained optimum without the cone solver, where the constraints are inactive.
//!
//! The problem `min θᵀ H θ − 2 gᵀ θ` subject to the constraint [`Group`]s is convex. When
//! `H ≻ 0` its unconstrained minimizer `θ* = H⁻¹ g` is unique, and when `θ*` satisfies every
//! group it is also the constrained minimizer: nothing a solver returns can be lower, and a
//! strictly convex objective has one minimizer. This file checks exactly that, strictly
//! (`λ_min ≥ ε`, no tolerance), so a point on a boundary goes to the cone solver; it never
//! applies to the log-det regularizer (its objective is not this quadratic).
//!
//! Only this all-or-nothing case is taken. Solving a relaxation with only the groups `θ*`
//! breaks, the other columns eliminated by their Schur complement, and adding groups until
//! the rest hold, was tried: on the KUKA diagnosis every body breaks at `θ*` and on the leg's
//! sample-size experiment most do, so the rounds cost more than the smaller programs saved.

use super::cone::Group;
use super::{Options, Regularizer};
use nalgebra::{DMatrix, DVector};

/// `θ* = H⁻¹ g` when `H` is positive definite and `θ*` satisfies every group of `groups`
/// (then it is the constrained optimum); `None` otherwise.
pub(crate) fn optimum(
    groups: &[Group],
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    opts: &Options,
) -> Option<DVector<f64>> {
    if opts.regularizer == Regularizer::LogDet || opts.force_cone_solver {
        return None;
    }
    let theta = h.clone().cholesky()?.solve(g);
    let finite = theta.iter().all(|v| v.is_finite());
    (finite && groups.iter().all(|group| group.holds(&theta, opts))).then_some(theta)
}
