//! Forward dynamics by the composite-rigid-body method (RBDA §6.1; spatial_v2 `FDcrb`).

use super::{check_len, crba, rnea, Data};
use crate::model::Model;
use nalgebra::DVector;

/// Forward dynamics failed.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FdError {
    /// `H(q)` is not positive definite (an inconsistent inertia, or a massless chain end).
    #[error("the mass matrix is not positive definite at this configuration")]
    SingularMassMatrix,
}

/// `q̈ = H(q)⁻¹ (τ − C(q, q̇) q̇ − g(q))` for the generalized force `τ` applied at the joints
/// (add friction to `τ` yourself). Returns `&data.qdd`.
pub fn forward_dynamics<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
) -> Result<&'a DVector<f64>, FdError> {
    check_len(model, "tau", tau);
    let zero = [0.0; 64];
    let n = model.dof();
    let bias = if n <= zero.len() {
        rnea(model, data, q, qd, &zero[..n]).clone()
    } else {
        rnea(model, data, q, qd, &vec![0.0; n]).clone()
    };
    data.bias.copy_from(&bias);
    crba(model, data, q);
    let chol = data
        .h
        .clone()
        .cholesky()
        .ok_or(FdError::SingularMassMatrix)?;
    let rhs = DVector::from_column_slice(tau) - &data.bias;
    data.qdd = chol.solve(&rhs);
    Ok(&data.qdd)
}
