//! `simulate`: a scenario's excitation experiment run, its report (the JSON contract
//! [`SimulateJson`], schema docs/schemas/simulate.schema.json) and its logs (MCAP, CSV).

use super::ApiError;
use crate::io::{mcap_log, samples};
use crate::model::Model;
use crate::sim::report::Excitation;
use crate::sim::scenario::Scenario;

/// The simulator a scenario runs on.
pub use crate::sim::scenario::Engine;
use crate::trajectory::Recording;
use std::path::{Path, PathBuf};

/// `simulate --json` (schema `physid.simulate/1`, docs/schemas/).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct SimulateJson {
    /// The scenario file.
    pub scenario: PathBuf,
    /// The MCAP log written.
    pub out: PathBuf,
    /// The engine that integrated it (`physid` or `rapier`).
    pub engine: String,
    /// The physid engine's Runge–Kutta method (`rk4`, `ralston3`); none for rapier.
    pub integrator: Option<String>,
    /// Integration steps per control period.
    pub substeps: usize,
    /// Samples logged.
    pub samples: usize,
    /// s.
    pub simulated_seconds: f64,
    /// s.
    pub wall_seconds: f64,
    /// Simulated seconds per wall second.
    pub real_time_factor: f64,
    /// What the motion excites: joint ranges, peaks, the regressor's rank and condition.
    pub excitation: Excitation,
    /// physid's inverse dynamics on the true motion against the torque the engine applied.
    pub physid_inverse_dynamics_residual: Residual,
}

/// How well physid's inverse dynamics explains the recording, per joint (N m).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Residual {
    /// RMS per joint (N m).
    pub rms: Vec<f64>,
    /// Largest absolute value per joint (N m).
    pub max: Vec<f64>,
}

/// What `simulate` may change in the scenario it reads.
#[derive(Clone, Debug, Default)]
pub struct SimulateOptions {
    /// The engine instead of the scenario's.
    pub engine: Option<Engine>,
    /// The duration (s) instead of the scenario's.
    pub duration: Option<f64>,
    /// The seed instead of the scenario's.
    pub seed: Option<u64>,
}

/// A simulated experiment: the scenario as run, its robot and the recording.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Simulation {
    /// The scenario file.
    pub path: PathBuf,
    /// The scenario as run (the options applied).
    pub scenario: Scenario,
    /// The scenario file's text (logged with the recording).
    pub scenario_text: String,
    /// Its robot (the ground truth).
    pub model: Model,
    /// The true and the processed signals.
    pub recording: Recording,
    /// Wall time of the integration (s).
    pub wall_seconds: f64,
}

/// Runs the scenario at `path` with `opts` applied; `progress` is called with the fraction
/// done.
pub fn simulate(
    path: &Path,
    opts: &SimulateOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<Simulation, ApiError> {
    simulate_until(path, opts, progress, &|| false)
}

/// [`simulate`], ended early once `stop` returns true ([`crate::sim::run_until`]).
pub fn simulate_until(
    path: &Path,
    opts: &SimulateOptions,
    progress: &mut dyn FnMut(f64),
    stop: &dyn Fn() -> bool,
) -> Result<Simulation, ApiError> {
    let (mut scenario, model, scenario_text) = crate::sim::scenario::load(path)?;
    if let Some(e) = opts.engine {
        scenario.simulation.engine = e;
    }
    if let Some(d) = opts.duration {
        scenario.simulation.duration = d;
    }
    if let Some(s) = opts.seed {
        scenario.simulation.seed = s;
    }
    let start = std::time::Instant::now();
    let recording = crate::sim::run_until(&model, &scenario, progress, stop).map_err(|source| {
        ApiError::Simulation {
            path: path.to_path_buf(),
            source,
        }
    })?;
    Ok(Simulation {
        path: path.to_path_buf(),
        scenario,
        scenario_text,
        model,
        recording,
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

impl Simulation {
    /// The engine's name as logged (`physid`, `rapier`).
    pub fn engine_name(&self) -> String {
        format!("{:?}", self.scenario.simulation.engine).to_lowercase()
    }

    /// Writes the MCAP log (the recording, the scenario and the ground-truth parameters).
    pub fn write_mcap(&self, out: &Path) -> Result<(), ApiError> {
        let theta = self.model.parameters();
        let names = self.model.parameter_names();
        mcap_log::write(
            out,
            &self.recording,
            &mcap_log::LogMeta {
                scenario_toml: &self.scenario_text,
                engine: &self.engine_name(),
                parameters: (&names, theta.as_slice()),
            },
        )?;
        Ok(())
    }

    /// Writes the processed samples (t, q, q̇, q̈, τ) as CSV.
    pub fn write_csv(&self, out: &Path) -> Result<(), ApiError> {
        Ok(samples::write_csv(out, &self.recording.processed)?)
    }

    /// Writes the MCAP log at `out` and, if asked, the CSV at `csv`, and returns the run's
    /// [`report`](Self::report): the same files and numbers as the three calls one after the
    /// other, in less wall time (the log is written on a thread of its own while the rest runs).
    pub fn write_with_report(
        &self,
        out: &Path,
        csv: Option<&Path>,
    ) -> Result<SimulateJson, ApiError> {
        std::thread::scope(|scope| {
            let log = scope.spawn(|| self.write_mcap(out));
            let table = csv.map(|c| self.write_csv(c)).transpose();
            let report = self.report(out);
            log.join()
                .unwrap_or_else(|p| std::panic::resume_unwind(p))?;
            table?;
            Ok(report)
        })
    }

    /// The report of the run, its log written at `out`.
    pub fn report(&self, out: &Path) -> SimulateJson {
        let (excitation, (rms, max)) = rayon::join(
            || crate::sim::report::excitation(&self.model, &self.recording.truth, 10),
            || crate::sim::report::engine_consistency(&self.model, &self.recording),
        );
        let sim = &self.scenario.simulation;
        let simulated = sim.duration;
        SimulateJson {
            scenario: self.path.clone(),
            out: out.to_path_buf(),
            engine: self.engine_name(),
            integrator: (sim.engine == Engine::Physid).then(|| sim.method().name().to_string()),
            substeps: sim.substeps,
            samples: self.recording.truth.len(),
            simulated_seconds: simulated,
            wall_seconds: self.wall_seconds,
            real_time_factor: simulated / self.wall_seconds,
            excitation,
            physid_inverse_dynamics_residual: Residual { rms, max },
        }
    }
}
