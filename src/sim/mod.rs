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

/// A joint-force law `u(t, q, q̇)` written into its last argument (N m per joint).
pub type ForceFn<'a> = dyn FnMut(f64, &[f64], &[f64], &mut [f64]) + 'a;

/// The classical Runge–Kutta (RK4) step of `ẋ = (q̇, FD(q, q̇, u))`, with its stage states and
/// slopes kept between steps so that a step allocates nothing.
///
/// Stages (Featherstone's notation, step `Δt`): `k₁ = FD(q, q̇)`, `q̇₂ = q̇ + Δt/2 k₁`,
/// `k₂ = FD(q + Δt/2 q̇, q̇₂)`, `q̇₃ = q̇ + Δt/2 k₂`, `k₃ = FD(q + Δt/2 q̇₂, q̇₃)`,
/// `q̇₄ = q̇ + Δt k₃`, `k₄ = FD(q + Δt q̇₃, q̇₄)`; then `q += Δt/6 (q̇ + 2q̇₂ + 2q̇₃ + q̇₄)` and
/// `q̇ += Δt/6 (k₁ + 2k₂ + 2k₃ + k₄)`. The local error is `O(Δt⁵)`.
#[derive(Debug, Clone)]
pub struct Rk4 {
    /// Position of the stage being evaluated (rad).
    stage_q: Vec<f64>,
    /// Joint force at the stage being evaluated (N m).
    u: Vec<f64>,
    /// Stage velocities `q̇₁ … q̇₄` (rad/s).
    v: [Vec<f64>; 4],
    /// Stage accelerations `k₁ … k₄` (rad/s²).
    k: [Vec<f64>; 4],
}

impl Rk4 {
    /// A workspace for `n` joints.
    pub fn new(n: usize) -> Self {
        let z = vec![0.0; n];
        Rk4 {
            stage_q: z.clone(),
            u: z.clone(),
            v: [z.clone(), z.clone(), z.clone(), z.clone()],
            k: [z.clone(), z.clone(), z.clone(), z],
        }
    }

    /// The acceleration at the start of the last step, `k₁` (rad/s²).
    pub fn start_acceleration(&self) -> &[f64] {
        &self.k[0]
    }

    /// Advances `(q, q̇)` by one step `dt` (s) from time `t`, in place; `force(t, q, q̇, u)`
    /// writes the generalized force applied at the joints (N m), friction included by the
    /// caller.
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        model: &Model,
        data: &mut Data,
        t: f64,
        q: &mut [f64],
        qd: &mut [f64],
        dt: f64,
        force: &mut ForceFn,
    ) -> Result<(), FdError> {
        let half = 0.5 * dt;
        self.v[0].copy_from_slice(qd);
        self.stage_q.copy_from_slice(q);
        self.slope(model, data, force, t, 0)?;
        for (stage, (h, ts)) in [(half, t + half), (half, t + half), (dt, t + dt)]
            .into_iter()
            .enumerate()
        {
            for i in 0..q.len() {
                self.stage_q[i] = q[i] + h * self.v[stage][i];
                self.v[stage + 1][i] = qd[i] + h * self.k[stage][i];
            }
            self.slope(model, data, force, ts, stage + 1)?;
        }
        let (v, k) = (&self.v, &self.k);
        for i in 0..q.len() {
            q[i] += dt / 6.0 * (v[0][i] + 2.0 * v[1][i] + 2.0 * v[2][i] + v[3][i]);
            qd[i] += dt / 6.0 * (k[0][i] + 2.0 * k[1][i] + 2.0 * k[2][i] + k[3][i]);
        }
        Ok(())
    }

    /// `k_stage = FD(stage_q, q̇_stage, u(t, stage_q, q̇_stage))`.
    fn slope(
        &mut self,
        model: &Model,
        data: &mut Data,
        force: &mut ForceFn,
        t: f64,
        stage: usize,
    ) -> Result<(), FdError> {
        force(t, &self.stage_q, &self.v[stage], &mut self.u);
        let qdd = forward_dynamics(model, data, &self.stage_q, &self.v[stage], &self.u)?;
        self.k[stage].copy_from_slice(qdd.as_slice());
        Ok(())
    }
}

/// One classical Runge–Kutta (RK4) step of `ẋ = (q̇, FD(q, q̇, τ))` over `dt` (s), in place
/// ([`Rk4::step`] with a fresh workspace).
///
/// `tau(t, q, q̇)` is the generalized force applied at the joints (N m), friction included by
/// the caller. The local error is `O(dt⁵)`; see the energy-conservation test for its size.
pub fn rk4_step(
    model: &Model,
    data: &mut Data,
    t: f64,
    q: &mut [f64],
    qd: &mut [f64],
    dt: f64,
    tau: &mut TorqueFn,
) -> Result<(), FdError> {
    let mut force =
        |t: f64, q: &[f64], qd: &[f64], u: &mut [f64]| u.copy_from_slice(tau(t, q, qd).as_slice());
    Rk4::new(model.dof()).step(model, data, t, q, qd, dt, &mut force)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reused workspace gives the fresh one's steps bit for bit (no state carried from step
    /// to step), and its first slope is the forward dynamics at the step's start.
    #[test]
    fn reused_workspace_equals_fresh_steps() {
        let model = crate::model::cheetah3::leg();
        let mut data = Data::new(&model);
        let tau = |t: f64, q: &[f64], _: &[f64]| {
            DVector::from_iterator(q.len(), q.iter().map(|x| (3.0 * t).sin() - 2.0 * x))
        };
        let mut force = |t: f64, q: &[f64], qd: &[f64], u: &mut [f64]| {
            u.copy_from_slice(tau(t, q, qd).as_slice())
        };
        let (mut q, mut qd) = (vec![0.1, -0.7, 1.2], vec![0.5, -1.0, 2.0]);
        let (mut q_ref, mut qd_ref) = (q.clone(), qd.clone());
        let mut rk4 = Rk4::new(3);
        for k in 0..20 {
            let t = k as f64 * 1e-3;
            let u: Vec<f64> = q.iter().map(|x| (3.0 * t).sin() - 2.0 * x).collect();
            let start = forward_dynamics(&model, &mut data, &q, &qd, &u)
                .unwrap()
                .clone();
            rk4.step(&model, &mut data, t, &mut q, &mut qd, 1e-3, &mut force)
                .unwrap();
            assert_eq!(rk4.start_acceleration(), start.as_slice());
            let mut tau_ref = |t: f64, q: &[f64], _: &[f64]| {
                DVector::from_iterator(q.len(), q.iter().map(|x| (3.0 * t).sin() - 2.0 * x))
            };
            let mut fresh = Data::new(&model);
            rk4_step(
                &model,
                &mut fresh,
                t,
                &mut q_ref,
                &mut qd_ref,
                1e-3,
                &mut tau_ref,
            )
            .unwrap();
            assert_eq!((&q, &qd), (&q_ref, &qd_ref), "step {k}");
        }
    }
}
