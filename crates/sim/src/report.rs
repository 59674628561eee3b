//! How well a recording excites the model: joint ranges, peak torques and the rank and
//! condition number of the stacked regressor.

use nalgebra::DMatrix;
use physid_core::dynamics::{regressor, Data};
use physid_core::model::Model;
use physid_core::trajectory::Trajectory;

/// Excitation summary of a trajectory.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Excitation {
    /// Per joint `[min, max]` position (rad).
    pub q_range: Vec<[f64; 2]>,
    /// Per joint peak |q̇| (rad/s).
    pub qd_peak: Vec<f64>,
    /// Per joint peak |τ| (N m).
    pub tau_peak: Vec<f64>,
    /// Numerical rank of the stacked regressor ([`physid_core::linalg::rank_and_condition`]).
    pub rank: usize,
    /// Number of parameters.
    pub parameters: usize,
    /// Condition number on its identifiable subspace ([`physid_core::linalg::rank_and_condition`]).
    pub condition: f64,
}

/// Computes the summary from the trajectory's q, q̇, q̈ (every `stride`-th sample).
pub fn excitation(model: &Model, tr: &Trajectory, stride: usize) -> Excitation {
    let n = model.dof();
    let p = model.layout().len;
    let mut d = Data::new(model);
    let mut y = DMatrix::zeros(n, p);
    let mut yty = DMatrix::<f64>::zeros(p, p);
    let zero = vec![0.0; n];
    for k in (0..tr.len()).step_by(stride.max(1)) {
        regressor(
            model,
            &mut d,
            tr.q_at(k),
            tr.qd_at(k),
            tr.qdd_at(k).unwrap_or(&zero),
            &mut y,
        );
        yty.gemm_tr(1.0, &y, &y, 1.0);
    }
    let (rank, condition) = physid_core::linalg::rank_and_condition(&yty);
    let mut q_range = vec![[f64::INFINITY, f64::NEG_INFINITY]; n];
    let (mut qd_peak, mut tau_peak) = (vec![0.0f64; n], vec![0.0f64; n]);
    for k in 0..tr.len() {
        for j in 0..n {
            let q = tr.q_at(k)[j];
            q_range[j] = [q_range[j][0].min(q), q_range[j][1].max(q)];
            qd_peak[j] = qd_peak[j].max(tr.qd_at(k)[j].abs());
            tau_peak[j] = tau_peak[j].max(tr.tau_at(k)[j].abs());
        }
    }
    Excitation {
        q_range,
        qd_peak,
        tau_peak,
        rank,
        parameters: p,
        condition,
    }
}

/// How well physid's inverse dynamics explains a recording's ground truth: per joint RMS and max
/// of `τ_mot + τ_effects − τ_friction − RNEA(q, q̇, q̈)` (N m). Zero up to integration error for
/// physid's own engine; for rapier it measures how far the two engines' torques differ on the
/// same trajectory.
pub fn engine_consistency(
    model: &Model,
    rec: &physid_core::trajectory::Recording,
) -> (Vec<f64>, Vec<f64>) {
    let n = model.dof();
    let mut d = Data::new(model);
    let tr = &rec.truth;
    let (mut ss, mut mx) = (vec![0.0; n], vec![0.0f64; n]);
    for k in 0..tr.len() {
        let tau = physid_core::dynamics::rnea(
            model,
            &mut d,
            tr.q_at(k),
            tr.qd_at(k),
            tr.qdd_at(k).expect("truth has q̈"),
        );
        for j in 0..n {
            let r = tr.tau_at(k)[j] + rec.effects[k * n + j] - rec.friction[k * n + j] - tau[j];
            ss[j] += r * r;
            mx[j] = mx[j].max(r.abs());
        }
    }
    (
        ss.iter().map(|s| (s / tr.len() as f64).sqrt()).collect(),
        mx,
    )
}
