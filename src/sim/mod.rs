//! Time integration of the forward dynamics, and an independent engine ([`rapier`]).

pub mod design;
pub mod effects;
pub mod excitation;
pub mod rapier;
pub mod report;
pub mod scenario;
pub mod simulate;

use crate::dynamics::{forward_dynamics, Data, FdError};
use crate::model::Model;
use nalgebra::DVector;

/// Runs a scenario (see [`simulate::simulate`]; the engine is the scenario's choice).
pub fn run(
    model: &Model,
    scenario: &scenario::Scenario,
    progress: &mut dyn FnMut(f64),
) -> Result<crate::trajectory::Recording, simulate::SimError> {
    simulate::simulate(model, scenario, progress)
}

/// A joint-torque law `τ(t, q, q̇)` (N m).
pub type TorqueFn<'a> = dyn FnMut(f64, &[f64], &[f64]) -> DVector<f64> + 'a;

/// One classical Runge–Kutta (RK4) step of `ẋ = (q̇, FD(q, q̇, τ))` over `dt` (s), in place.
///
/// `tau(t, q, q̇)` is the generalized force applied at the joints (N m), friction included by
/// the caller. The local error is `O(dt⁵)`; see the energy-conservation test for its size.
#[allow(clippy::too_many_arguments)]
pub fn rk4_step(
    model: &Model,
    data: &mut Data,
    t: f64,
    q: &mut [f64],
    qd: &mut [f64],
    dt: f64,
    tau: &mut TorqueFn,
) -> Result<(), FdError> {
    let n = model.dof();
    let mut deriv = |t: f64, q: &[f64], qd: &[f64]| -> Result<DVector<f64>, FdError> {
        let u = tau(t, q, qd);
        Ok(forward_dynamics(model, data, q, qd, u.as_slice())?.clone())
    };
    let add = |x: &[f64], k: &[f64], h: f64| -> Vec<f64> {
        x.iter().zip(k).map(|(a, b)| a + h * b).collect()
    };
    let k1v = qd.to_vec();
    let k1a = deriv(t, q, qd)?;
    let (q2, v2) = (add(q, &k1v, 0.5 * dt), add(qd, k1a.as_slice(), 0.5 * dt));
    let k2a = deriv(t + 0.5 * dt, &q2, &v2)?;
    let (q3, v3) = (add(q, &v2, 0.5 * dt), add(qd, k2a.as_slice(), 0.5 * dt));
    let k3a = deriv(t + 0.5 * dt, &q3, &v3)?;
    let (q4, v4) = (add(q, &v3, dt), add(qd, k3a.as_slice(), dt));
    let k4a = deriv(t + dt, &q4, &v4)?;
    for i in 0..n {
        q[i] += dt / 6.0 * (k1v[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
        qd[i] += dt / 6.0 * (k1a[i] + 2.0 * k2a[i] + 2.0 * k3a[i] + k4a[i]);
    }
    Ok(())
}
