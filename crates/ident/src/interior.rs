//! The constrained optimum without the cone solver, where the constraints are inactive.
//!
//! The problem `min θᵀ H θ − 2 gᵀ θ` subject to the constraint set's matrix inequalities and
//! the linear bounds is convex. When `H ≻ 0` its unconstrained minimizer `θ* = H⁻¹ g` is unique,
//! and when `θ*` satisfies every constraint it is also the constrained minimizer: nothing a
//! solver returns can be lower, and a strictly convex objective has one minimizer. This file
//! checks exactly that, strictly (`λ_min ≥ ε`, no tolerance), so a point on a boundary goes to
//! the cone solver as before; it never applies to the log-det regularizer (its objective is not
//! this quadratic).

use super::{bodies, ConstraintSet, Options, Regularizer};
use nalgebra::{DMatrix, DVector};
use physid_core::model::Model;
use physid_core::spatial::InertialParams;

/// `θ* = H⁻¹ g` when `H` is positive definite and `θ*` satisfies every constraint of `opts`
/// (then it is the constrained optimum); `None` otherwise.
pub(crate) fn optimum(
    model: &Model,
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    opts: &Options,
) -> Option<DVector<f64>> {
    if opts.regularizer == Regularizer::LogDet || opts.force_cone_solver {
        return None;
    }
    let theta = h.clone().cholesky()?.solve(g);
    (theta.iter().all(|v| v.is_finite()) && strictly_feasible(model, &theta, opts)).then_some(theta)
}

/// Whether `theta` satisfies every constraint the cone program of `opts` would impose: the
/// set's matrix inequalities per body and rotor (`I ⪰ ε1`, `J ⪰ ε1`, the CoM in its
/// ellipsoid, `tr(JQ) ≥ 0`), friction non-negative under a set, `opts.nonnegative`, the mass
/// bounds and the total mass.
pub(crate) fn strictly_feasible(model: &Model, theta: &DVector<f64>, opts: &Options) -> bool {
    let set = opts.constraints;
    let bodies_hold = bodies(model).iter().all(|(_, col, ellipsoid)| {
        let p = InertialParams(theta.fixed_rows::<10>(*col).into_owned());
        let r = p.consistency(ellipsoid.as_ref());
        match set {
            ConstraintSet::None => true,
            ConstraintSet::Semi => r.min_eig_spatial >= opts.eps,
            ConstraintSet::Consistent => r.min_eig_pseudo >= opts.eps,
            ConstraintSet::Ellipsoid => {
                r.min_eig_pseudo >= opts.eps
                    && r.trace_jq.is_some_and(|t| t >= 0.0)
                    && r.min_eig_com.is_some_and(|c| c >= 0.0)
            }
        }
    });
    let l = model.layout();
    let friction_holds =
        set == ConstraintSet::None || (l.viscous_col..l.len).all(|c| theta[c] >= 0.0);
    let nonnegative_holds = opts.nonnegative.iter().all(|&c| theta[c] >= 0.0);
    let masses_hold = opts
        .mass_bounds
        .iter()
        .all(|&(c, lo, hi)| (lo..=hi).contains(&theta[c]));
    let total_holds = opts.total_mass.as_ref().is_none_or(|(cols, lo, hi)| {
        let total: f64 = cols.iter().map(|&c| theta[c]).sum();
        (*lo..=*hi).contains(&total)
    });
    bodies_hold && friction_holds && nonnegative_holds && masses_hold && total_holds
}
