//! `excite`: the JSON contract of a designed excitation ([`ExciteJson`], schema
//! docs/schemas/excite.schema.json) and its check in simulation against the robot's limits
//! (the design itself is [`crate::sim::design`]).

use super::ApiError;
use crate::model::Model;
use crate::sim::design::{Design, DesignOptions};
use std::path::PathBuf;

/// The limits as the simulated robot used them (peak over the run / the robot's own limit,
/// no margin).
#[derive(Clone, Debug, serde::Serialize, schemars::JsonSchema)]
pub struct SimulatedUse {
    /// Joint name.
    pub joint: String,
    /// Lowest and highest angle reached (rad).
    pub q_range: [f64; 2],
    /// The robot's position limits (rad; null: none).
    pub q_limits: [f64; 2],
    /// Peak speed over the speed limit.
    pub velocity: f64,
    /// Peak acceleration in the motion's band (rad/s²; the true acceleration low-passed at 5×
    /// the highest harmonic).
    pub acceleration: f64,
    /// Peak torque over the effort limit.
    pub torque: f64,
    /// Every peak inside its limit.
    pub within: bool,
}

/// `excite --json` (schema `physid.excite/1`, docs/schemas/).
#[derive(serde::Serialize, schemars::JsonSchema)]
pub struct ExciteJson {
    /// The design.
    pub design: Design,
    /// The scenario written, if any.
    pub out: Option<PathBuf>,
    /// The check in simulation (null with --no-check).
    pub simulated: Option<Vec<SimulatedUse>>,
    /// Every simulated peak inside the robot's limits and the acceleration limit.
    pub within_limits: Option<bool>,
}

/// The check of a design in simulation: each joint's peaks against its limits.
#[derive(Clone, Debug)]
pub struct LimitCheck {
    /// Per joint, in the robot's order.
    pub joints: Vec<SimulatedUse>,
    /// Every peak of every joint inside its limit.
    pub within: bool,
}

/// Simulates the scenario `text` (its robot is `model`) and compares each joint's peaks
/// with the robot's limits (position, speed, torque: the true motion) and the acceleration
/// limit (the true acceleration low-passed at `band` Hz, zero phase, without the first and
/// last second: the tracking controller's reaction to encoder quantization adds broadband
/// jitter of a few rad/s² that is not part of the motion, and its start-up a transient).
pub fn check_in_simulation(
    model: &Model,
    text: &str,
    opts: &DesignOptions,
    band: f64,
) -> Result<LimitCheck, ApiError> {
    let designed = |m: String| ApiError::Designed(m);
    let sc: crate::sim::scenario::Scenario =
        toml::from_str(text).map_err(|e| designed(e.to_string()))?;
    sc.validate(model.dof())
        .map_err(|e| designed(e.to_string()))?;
    let rec = crate::sim::run(model, &sc, &mut |_| {})
        .map_err(|source| ApiError::DesignedSimulation { source })?;
    let tr = &rec.truth;
    let rate = sc.simulation.rate;
    let sos = crate::signal::butterworth_lowpass(2, band.min(0.4 * rate), rate)
        .map_err(|e| designed(format!("acceleration band {band} Hz: {e}")))?;
    // The tracking controller's start-up and the filter's ends: the first and last second.
    let settle = (rate as usize).min(tr.len() / 4);
    let mut ok = true;
    let joints = model
        .bodies
        .iter()
        .enumerate()
        .map(|(j, b)| {
            let col = |f: &dyn Fn(usize) -> f64| (0..tr.len()).map(f).collect::<Vec<f64>>();
            let q = col(&|k| tr.q_at(k)[j]);
            let qd = col(&|k| tr.qd_at(k)[j].abs());
            let qdd: Vec<f64> = sos
                .filtfilt(&col(&|k| tr.qdd_at(k).map_or(0.0, |a| a[j])))
                .iter()
                .skip(settle)
                .take(tr.len().saturating_sub(2 * settle))
                .map(|x| x.abs())
                .collect();
            let tau = col(&|k| tr.tau_at(k)[j].abs());
            let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
            let l = &b.limits;
            let ratio = |p: f64, lim: f64| if lim.is_finite() { p / lim } else { 0.0 };
            let mut u = SimulatedUse {
                joint: b.joint_name.clone(),
                q_range: [min(&q), max(&q)],
                q_limits: [l.lower, l.upper],
                velocity: ratio(max(&qd), l.velocity),
                acceleration: max(&qdd),
                torque: ratio(max(&tau), l.effort),
                within: false,
            };
            u.within = u.q_range[0] >= l.lower
                && u.q_range[1] <= l.upper
                && u.velocity <= 1.0
                && u.torque <= 1.0
                && u.acceleration <= opts.acceleration_limit(j);
            ok &= u.within;
            u
        })
        .collect();
    Ok(LimitCheck { joints, within: ok })
}
