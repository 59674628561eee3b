//! Time integration of the forward dynamics, and an independent engine ([`rapier`]).
//!
//! A floor of physid (docs/architecture.md §6) of its own crate, `physid-sim`; the `physid`
//! crate re-exports it as `physid::sim`.
#![warn(missing_docs)]

pub mod design;
pub mod effects;
pub mod excitation;
pub mod floating;
pub mod floating_sensors;
#[cfg(test)]
mod floating_tests;
pub mod rapier;
pub mod rapier_floating;
pub mod report;
pub mod scenario;
pub mod simulate;

use nalgebra::DVector;
use physid_core::dynamics::{forward_dynamics, Data, FdError};
use physid_core::model::Model;

/// Runs a scenario (see [`simulate::simulate`]; the engine is the scenario's choice).
pub fn run(
    model: &Model,
    scenario: &scenario::Scenario,
    progress: &mut dyn FnMut(f64),
) -> Result<physid_core::trajectory::Recording, simulate::SimError> {
    simulate::simulate(model, scenario, progress, &|| false)
}

/// [`run`], ended early with [`simulate::SimError::Cancelled`] once `stop` returns true (asked
/// about a hundred times in a run).
pub fn run_until(
    model: &Model,
    scenario: &scenario::Scenario,
    progress: &mut dyn FnMut(f64),
    stop: &dyn Fn() -> bool,
) -> Result<physid_core::trajectory::Recording, simulate::SimError> {
    simulate::simulate(model, scenario, progress, stop)
}

/// A joint-torque law `τ(t, q, q̇)` (N m).
pub type TorqueFn<'a> = dyn FnMut(f64, &[f64], &[f64]) -> DVector<f64> + 'a;

/// A joint-force law `u(t, q, q̇)` written into its last argument (N m per joint).
pub type ForceFn<'a> = dyn FnMut(f64, &[f64], &[f64], &mut [f64]) + 'a;

/// An explicit Runge–Kutta method whose every stage is taken from the one before it (the
/// tableau's only nonzero `a` entries lie just below its diagonal, so `c_i = a_{i,i−1}`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// The classical fourth-order method: four stages, local error `O(Δt⁵)`.
    #[default]
    Rk4,
    /// Ralston's third-order method (the three-stage tableau of least truncation-error
    /// bound, Ralston 1962): `c = (0, ½, ¾)`, `b = (2/9, 1/3, 4/9)`; local error `O(Δt⁴)` for
    /// three forward dynamics a step instead of four.
    Ralston3,
}

impl Method {
    /// Its name in a scenario file.
    pub fn name(self) -> &'static str {
        match self {
            Method::Rk4 => "rk4",
            Method::Ralston3 => "ralston3",
        }
    }

    /// Stages per step (forward-dynamics evaluations).
    pub fn stages(self) -> usize {
        self.offsets().len() + 1
    }

    /// `c_i` of every stage after the first: where in the step (fraction of `Δt`) it is
    /// evaluated, from the previous stage's slope.
    fn offsets(self) -> &'static [f64] {
        match self {
            Method::Rk4 => &[0.5, 0.5, 1.0],
            Method::Ralston3 => &[0.5, 0.75],
        }
    }
}

/// An explicit Runge–Kutta step of `ẋ = (q̇, FD(q, q̇, u))` ([`Method`]), with its stage states
/// and slopes kept between steps so that a step allocates nothing.
///
/// Stages (Featherstone's notation, step `Δt`): `k₁ = FD(q, q̇)`; stage `i > 1` at
/// `q + c_i Δt q̇_{i−1}` with `q̇_i = q̇ + c_i Δt k_{i−1}`, `k_i = FD(q_i, q̇_i)`. RK4 (`c = ½, ½,
/// 1`): `q += Δt/6 (q̇ + 2q̇₂ + 2q̇₃ + q̇₄)`, `q̇ += Δt/6 (k₁ + 2k₂ + 2k₃ + k₄)`. Ralston's third
/// order (`c = ½, ¾`): `q += Δt/9 (2q̇ + 3q̇₂ + 4q̇₃)`, `q̇ += Δt/9 (2k₁ + 3k₂ + 4k₃)`.
#[derive(Debug, Clone)]
pub struct RungeKutta {
    method: Method,
    /// Position of the stage being evaluated (rad).
    stage_q: Vec<f64>,
    /// Joint force at the stage being evaluated (N m).
    u: Vec<f64>,
    /// Stage velocities `q̇₁ …` (rad/s).
    v: [Vec<f64>; 4],
    /// Stage accelerations `k₁ …` (rad/s²).
    k: [Vec<f64>; 4],
}

impl RungeKutta {
    /// A classical RK4 workspace for `n` joints.
    pub fn new(n: usize) -> Self {
        Self::with_method(n, Method::Rk4)
    }

    /// A workspace for `n` joints stepping with `method`.
    pub fn with_method(n: usize, method: Method) -> Self {
        let z = vec![0.0; n];
        RungeKutta {
            method,
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
        self.v[0].copy_from_slice(qd);
        self.stage_q.copy_from_slice(q);
        self.slope(model, data, force, t, 0)?;
        for (stage, c) in self.method.offsets().iter().enumerate() {
            let h = c * dt;
            for i in 0..q.len() {
                self.stage_q[i] = q[i] + h * self.v[stage][i];
                self.v[stage + 1][i] = qd[i] + h * self.k[stage][i];
            }
            self.slope(model, data, force, t + h, stage + 1)?;
        }
        let (v, k) = (&self.v, &self.k);
        match self.method {
            Method::Rk4 => {
                for i in 0..q.len() {
                    q[i] += dt / 6.0 * (v[0][i] + 2.0 * v[1][i] + 2.0 * v[2][i] + v[3][i]);
                    qd[i] += dt / 6.0 * (k[0][i] + 2.0 * k[1][i] + 2.0 * k[2][i] + k[3][i]);
                }
            }
            Method::Ralston3 => {
                for i in 0..q.len() {
                    q[i] += dt / 9.0 * (2.0 * v[0][i] + 3.0 * v[1][i] + 4.0 * v[2][i]);
                    qd[i] += dt / 9.0 * (2.0 * k[0][i] + 3.0 * k[1][i] + 4.0 * k[2][i]);
                }
            }
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
/// ([`RungeKutta::step`] with a fresh workspace).
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
    RungeKutta::new(model.dof()).step(model, data, t, q, qd, dt, &mut force)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The state after `t_end` (s) from the same start with `steps` steps of `method`.
    fn integrate(method: Method, steps: usize, t_end: f64) -> Vec<f64> {
        let model = physid_core::model::cheetah3::leg();
        let mut data = Data::new(&model);
        let mut force = |t: f64, q: &[f64], qd: &[f64], u: &mut [f64]| {
            for ((u, q), qd) in u.iter_mut().zip(q).zip(qd) {
                *u = 20.0 * (3.0 * t).sin() - 40.0 * q - 2.0 * qd;
            }
        };
        let (mut q, mut qd) = (vec![0.1, -0.7, 1.2], vec![0.5, -1.0, 2.0]);
        let mut stepper = RungeKutta::with_method(3, method);
        let dt = t_end / steps as f64;
        for k in 0..steps {
            stepper
                .step(
                    &model,
                    &mut data,
                    k as f64 * dt,
                    &mut q,
                    &mut qd,
                    dt,
                    &mut force,
                )
                .unwrap();
        }
        q.into_iter().chain(qd).collect()
    }

    /// Each method converges at its order: halving the step divides the global error by about
    /// `2^order` (8 for Ralston's third order, 16 for RK4), against RK4 at a step 16 times
    /// finer than the finest; and each method's stage count is its forward dynamics a step.
    #[test]
    fn each_method_converges_at_its_order() {
        let t_end = 0.3;
        let reference = integrate(Method::Rk4, 1920, t_end);
        let error = |method: Method, steps: usize| {
            let x = integrate(method, steps, t_end);
            x.iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        };
        for (method, order) in [(Method::Ralston3, 3), (Method::Rk4, 4)] {
            let (coarse, fine) = (error(method, 60), error(method, 120));
            let ratio = coarse / fine;
            let expected = 2f64.powi(order);
            assert!(
                (0.75 * expected..1.25 * expected).contains(&ratio),
                "{}: error {coarse:.3e} -> {fine:.3e}, ratio {ratio:.2}, expected about {expected}",
                method.name()
            );
            assert_eq!(method.stages(), order as usize);
        }
    }

    /// A reused workspace gives the fresh one's steps bit for bit (no state carried from step
    /// to step), and its first slope is the forward dynamics at the step's start.
    #[test]
    fn reused_workspace_equals_fresh_steps() {
        let model = physid_core::model::cheetah3::leg();
        let mut data = Data::new(&model);
        let tau = |t: f64, q: &[f64], _: &[f64]| {
            DVector::from_iterator(q.len(), q.iter().map(|x| (3.0 * t).sin() - 2.0 * x))
        };
        let mut force = |t: f64, q: &[f64], qd: &[f64], u: &mut [f64]| {
            u.copy_from_slice(tau(t, q, qd).as_slice())
        };
        let (mut q, mut qd) = (vec![0.1, -0.7, 1.2], vec![0.5, -1.0, 2.0]);
        let (mut q_ref, mut qd_ref) = (q.clone(), qd.clone());
        let mut rk4 = RungeKutta::new(3);
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
#[cfg(test)]
mod rapier_floating_tests;
