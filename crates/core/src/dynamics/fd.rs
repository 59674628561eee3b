//! Forward dynamics by the composite-rigid-body method (RBDA §6.1; spatial_v2 `FDcrb`).

use super::crba::crba_from_transforms;
use super::{check_len, rnea, Data};
use crate::model::Model;
use nalgebra::DVector;

/// Forward dynamics failed.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FdError {
    /// `H(q)` is not positive definite (an inconsistent inertia, a massless chain end, or a
    /// joint whose subtree has no inertia about its axis: point masses on it).
    #[error("the mass matrix is not positive definite at this configuration: joint '{joint}' (the first whose leading block is not) moves no inertia that the joints before it do not already (a body of point masses on its axis, or massless)")]
    SingularMassMatrix {
        /// The joint at which the leading blocks of `H(q)` stop being positive definite.
        joint: String,
    },
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
    let Some(chol) = ws.cholesky() else {
        return Err(FdError::SingularMassMatrix {
            joint: model.bodies()[first_singular_block(&data.h)]
                .joint_name
                .clone(),
        });
    };
    for ((a, t), b) in data.qdd.iter_mut().zip(tau).zip(data.bias.iter()) {
        *a = t - b;
    }
    chol.solve_mut(&mut data.qdd);
    data.chol = chol.unpack();
    Ok(&data.qdd)
}

/// The first `k` whose leading `(k+1) × (k+1)` block of `h` has no Cholesky factor (the last
/// index when every block has one, which a matrix that failed as a whole does not).
fn first_singular_block(h: &nalgebra::DMatrix<f64>) -> usize {
    let n = h.nrows();
    (0..n)
        .find(|&k| {
            h.view((0, 0), (k + 1, k + 1))
                .into_owned()
                .cholesky()
                .is_none()
        })
        .unwrap_or(n.saturating_sub(1))
}
