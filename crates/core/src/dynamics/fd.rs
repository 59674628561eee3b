//! Forward dynamics by the composite-rigid-body method (RBDA §6.1; spatial_v2 `FDcrb`).

use super::crba::crba_from_transforms;
use super::{check_len, rnea, Data};
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
/// (add friction to `τ` yourself). Returns `&data.qdd`. The joint transforms are computed once
/// (by the RNEA for the bias) and reused by the CRBA; nothing is allocated.
pub fn forward_dynamics<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
) -> Result<&'a DVector<f64>, FdError> {
    check_len(model, "tau", tau);
    let n = model.dof();
    let mut zero = std::mem::take(&mut data.zero);
    zero.resize(n, 0.0);
    rnea(model, data, q, qd, &zero);
    data.zero = zero;
    std::mem::swap(&mut data.bias, &mut data.tau);
    crba_from_transforms(model, data);
    let mut ws = std::mem::take(&mut data.chol);
    ws.clone_from(&data.h);
    let chol = ws.cholesky().ok_or(FdError::SingularMassMatrix)?;
    for ((a, t), b) in data.qdd.iter_mut().zip(tau).zip(data.bias.iter()) {
        *a = t - b;
    }
    chol.solve_mut(&mut data.qdd);
    data.chol = chol.unpack();
    Ok(&data.qdd)
}
